"""How a figure is shown: rounded to the digits it is printed with, float noise shown as 0, an em dash for none.

A mean of costs that cancel (A*'s regret, 0 on every map) is stored as it was computed, say `-1.5e-15`; shown, it is
`0.000`, never `-0.000` nor `-1.5e-15`. Only the text changes: stored figures (entries, databases, JSON output,
DataFrames) keep their values. The report, the leaderboard, the docs' tables and the commands' text all format
their numbers here.
"""

from __future__ import annotations

import math
import numbers

__all__ = ["NOISE", "NONE", "number", "percent", "points"]

#: what a figure below this in magnitude is shown as: 0 (sums of float costs that cancel leave ~1e-15)
NOISE = 1e-9
#: the text of a figure that is not there (None, NaN)
NONE = "—"


def _finite(value) -> float | None:
    """`value` as a float, None where there is none (None, NaN, not a number); noise (`NOISE`) as 0.0."""
    if value is None or isinstance(value, bool) or not isinstance(value, numbers.Real):
        return None
    value = float(value)
    if not math.isfinite(value):
        return None
    return 0.0 if abs(value) < NOISE else value


def number(value, digits: int = 3) -> str:
    """`1,234` for integers, `0.913` for floats with `digits` decimals (|x| < `NOISE` and anything that rounds to
    zero as `0.000`, never `-0.000`), `NONE` for None or NaN."""
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        return f"{int(value):,}"
    x = _finite(value)
    if x is None:
        return NONE
    return f"{round(x, digits) + 0.0:.{digits}f}"  # + 0.0: a rounded -0.0 shows as 0


def percent(fraction, digits: int = 1) -> str:
    """A share (a fraction) in percent with `digits` decimals: `57.7%`; `NONE` for None or NaN."""
    x = _finite(fraction)
    return NONE if x is None else f"{round(100.0 * x, digits) + 0.0:.{digits}f}%"


def points(low, high, digits: int = 1) -> str:
    """An interval of shares in percentage points: `[47.9, 67.0]`; `NONE` where an end is missing."""
    a, b = _finite(low), _finite(high)
    if a is None or b is None:
        return NONE
    return f"[{round(100.0 * a, digits) + 0.0:.{digits}f}, {round(100.0 * b, digits) + 0.0:.{digits}f}]"
