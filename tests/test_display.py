"""How figures are shown: rounded, float noise as 0, never `-0.000`, an em dash for none; the value itself untouched."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from vinadv.display import NOISE, NONE, number, percent, points


def test_float_noise_and_negative_zero_show_as_zero():
    assert number(-1.5e-15) == "0.000" and number(2e-16, digits=1) == "0.0"
    assert number(-0.0004) == "0.000"  # rounds to zero: no minus sign
    assert number(-0.0006) == "-0.001" and number(1.23456) == "1.235"
    assert percent(-1e-12) == "0.0%" and percent(0.5775) == "57.8%"


def test_none_nan_and_integers():
    assert number(None) == NONE and number(float("nan")) == NONE and number(math.inf) == NONE
    assert percent(None) == NONE and points(None, 0.5) == NONE
    assert number(1234) == "1,234" and number(True) == NONE


def test_an_interval_in_points():
    assert points(0.479, 0.67) == "[47.9, 67.0]"
    assert points(-1e-15, 0.037) == "[0.0, 3.7]"


@given(st.floats(min_value=-1e6, max_value=1e6, allow_nan=False), st.integers(0, 6))
def test_the_shown_number_is_the_value_rounded(value, digits):
    shown = number(value, digits)
    expected = 0.0 if abs(value) < NOISE else value
    assert float(shown.replace(",", "")) == pytest.approx(round(expected, digits), abs=10.0**-digits)
    assert not shown.startswith("-") or round(expected, digits) < 0
