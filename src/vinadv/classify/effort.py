"""Search effort of a path pair (DESIGN.md "Search effort"): did the attack blow up the planner's search?

A search planner (`Capabilities.expansions`: A*, weighted A*, Neural A*, TransPath) exists to save expansions, so an
attack on it is also judged by how many cells its search expands. For a pair with the planner's expansions `E_o`,
`E_a` on the original and the adversarial map and those of the exact A* of the pairs' movement model `A_o`, `A_a` on
the same maps (the reference: how much harder the edit made the map itself):

- effort ratio `E_a / E_o`: how much the planner's search grew;
- A*'s effort ratio `A_a / A_o`: how much a search with the exact heuristic grew on the same pair;
- relative effort `(E_a / E_o) / (A_a / A_o)`: the planner's growth beyond what the map explains (1 for A* itself);
- effort-harmful: the pair is valid (the original path reaches the goal), the planner's search grew (`E_a > E_o`)
  and its relative effort exceeds `EFFORT_TOL`.

Every count is at least 1 where a search ran (the start is expanded); a count below 1 (none reported) makes the
figures NaN and the verdict None. Computed from the counts wherever they are read (the store keeps the counts, not
the figures), so one definition serves the pairs, the DataFrames, the exports and the robustness benchmark.
"""

from __future__ import annotations

import numpy as np

#: the relative effort above which a pair is effort-harmful: the planner's search grew more than twice as much as
#: A*'s on the same pair (DESIGN.md "Search effort": why 2)
EFFORT_TOL = 2.0

#: the figures of `effort_figures`, in the order the DataFrames and exports show them
EFFORT_FIELDS = ("effort_ratio", "astar_effort_ratio", "relative_effort", "effort_harmful")


def effort_figures(expansions_o, expansions_a, astar_o, astar_a, valid=None, tol: float = EFFORT_TOL) -> dict:
    """The effort figures of n pairs (module doc) from their counts (`(n,)` each; a count below 1 or NaN: none).

    Returns `{"effort_ratio", "astar_effort_ratio", "relative_effort"}`: `(n,)` float64, NaN where a count is
    missing, and `"effort_harmful"`: `(n,)` object, True/False, None where the verdict is undefined (a count missing,
    or the pair invalid: `valid` `(n,)` bool False; None: every pair valid)."""
    counts = [np.asarray(c, dtype=np.float64).reshape(-1) for c in (expansions_o, expansions_a, astar_o, astar_a)]
    e_o, e_a, a_o, a_a = (np.where(c >= 1, c, np.nan) for c in counts)
    ratio = e_a / e_o
    astar_ratio = a_a / a_o
    relative = ratio / astar_ratio
    known = ~np.isnan(relative)
    if valid is not None:
        known &= np.asarray(valid, dtype=bool).reshape(-1)
    harmful = np.full(len(ratio), None, dtype=object)
    harmful[known] = (ratio[known] > 1) & (relative[known] > tol)
    return {
        "effort_ratio": ratio,
        "astar_effort_ratio": astar_ratio,
        "relative_effort": relative,
        "effort_harmful": harmful,
    }
