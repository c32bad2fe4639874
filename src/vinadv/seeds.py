"""What vinadv takes as a random seed: one rule for every command and library entry point that stores one.

A seed is an integer with `0 <= seed < 2**63`: NumPy's generators refuse a negative seed, and the store keeps seeds
in signed 64-bit columns (`runs.seed`, `evaluations.seed`), so a larger one could be used but never recorded.
"""

from __future__ import annotations

import operator

from vinadv.errors import InputError

#: one past the largest seed (the largest signed 64-bit integer, plus one)
SEED_LIMIT = 2**63


def check_seed(seed: object, name: str = "seed") -> int:
    """`seed` as an int when `0 <= seed < SEED_LIMIT`; InputError naming the parameter `name` otherwise."""
    try:
        value = operator.index(seed)  # an int or a NumPy integer; not a bool, float or string
    except TypeError:
        value = None
    if isinstance(seed, bool) or value is None or not 0 <= value < SEED_LIMIT:
        raise InputError(f"{name} must be an integer from 0 to 2**63 - 1, got {_short(seed)}", name)
    return value


def _short(value: object) -> str:
    """`value` for a one-line message: a number of hundreds of digits is cut to its first and last few."""
    text = repr(value) if not isinstance(value, int) else str(value)
    return text if len(text) <= 40 else f"{text[:16]}...{text[-8:]} ({len(text)} characters)"
