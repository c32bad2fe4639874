"""Planners: the contract (`interface`, `search`), the shared mechanics, the registry and one package per family.

`check_planner` (from `vinadv.planners.checks`, imported when first asked for: `import vinadv.planners` stays
light) checks a planner against the contract and its declared capabilities.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from vinadv.planners.checks import check_planner

__all__ = ["check_planner"]


def __getattr__(name: str):
    if name == "check_planner":
        from vinadv.planners.checks import check_planner  # noqa: PLC0415 (NumPy and Numba: only when asked for)

        return check_planner
    raise AttributeError(f"module 'vinadv.planners' has no attribute {name!r}")
