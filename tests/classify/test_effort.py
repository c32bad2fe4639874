"""The search effort of a pair (`vinadv.classify.effort`, DESIGN.md "Search effort") against a plain-Python reading
of the definition, pair by pair."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from vinadv.classify.effort import EFFORT_TOL, effort_figures

count = st.one_of(st.just(0), st.integers(1, 500))  # 0: not reported


def by_hand(e_o, e_a, a_o, a_a, valid):
    if min(e_o, e_a, a_o, a_a) < 1:
        return math.nan, None
    relative = (e_a / e_o) / (a_a / a_o)
    return relative, (e_a > e_o and relative > EFFORT_TOL) if valid else None


@settings(max_examples=25)
@given(st.lists(st.tuples(count, count, count, count, st.booleans()), min_size=1, max_size=20))
def test_the_figures_follow_the_definition_pair_by_pair(rows):
    e_o, e_a, a_o, a_a, valid = (np.array(c) for c in zip(*rows))
    got = effort_figures(e_o, e_a, a_o, a_a, valid=valid)
    for i, row in enumerate(rows):
        relative, harmful = by_hand(*row)
        assert (math.isnan(relative) and math.isnan(got["relative_effort"][i])) or math.isclose(
            got["relative_effort"][i], relative
        )
        assert got["effort_harmful"][i] is harmful or got["effort_harmful"][i] == harmful


def test_a_star_against_itself_is_never_effort_harmful():
    rng = np.random.default_rng(0)
    e_o, e_a = rng.integers(1, 900, 50), rng.integers(1, 900, 50)
    got = effort_figures(e_o, e_a, e_o, e_a)  # the planner is the reference: relative effort 1
    assert np.allclose(got["relative_effort"], 1.0) and not any(got["effort_harmful"])
    grown = effort_figures([10, 10, 10], [31, 19, 5], [10, 10, 10], [10, 10, 1])
    assert list(grown["effort_harmful"]) == [True, False, False]  # 3.1 > 2; 1.9 not; fewer expansions not
