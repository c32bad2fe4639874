"""Planners: the contract (`interface`, `search`), the shared mechanics, the registry and one package per family.

`check_planner` (from `vinadv.planners.checks`, imported when first asked for: `import vinadv.planners` stays
light) checks a planner against the contract and its declared capabilities.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from vinadv import lazy_names

if TYPE_CHECKING:
    from vinadv.planners.checks import check_planner as check_planner

# NumPy and Numba behind it: imported when first asked for
__all__, __getattr__, __dir__ = lazy_names(__name__, {"checks": ("check_planner",)})
