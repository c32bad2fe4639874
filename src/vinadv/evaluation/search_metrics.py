"""The search planners' metrics, Opt / Exp / Hmean, as the Neural A* authors define them, for any planner.

Over the rows (one per map and start) a planner plans (Yonetani et al., ICML 2021; their evaluation code,
omron-sinicx/neural-astar `utils/training.py`: `calc_metrics`, `calc_metrics_from_multiple_results`):

- Opt: the share of rows whose path reaches the goal at the optimal cost (the cost of the path vanilla A* finds: A*
  is exact, `vinadv.planners.classical.astar`; vinadv takes the exact cost of the maps' expert paths, the same
  number). A path that does not reach the goal is not optimal.
- Exp: the mean over rows of `max(0, (E_A* - E) / E_A*)`, `E` the cells the planner expanded and `E_A*` those
  vanilla A* (`astar`, on the maps' movement model) expanded from the same start: the share of A*'s search saved.
  Defined for planners that report their expansions (search planners); None for the others.
- Hmean: the harmonic mean `2 / (1 / (Opt + 1e-10) + 1 / (Exp + 1e-10))`. With one start per map it is taken of the
  two means (their `calc_metrics`); with several starts per map, per map over its starts and then averaged over the
  maps (their `calc_metrics_from_multiple_results`).
- success: the share of rows whose path reaches the goal; cost_ratio: the mean of `cost / optimal cost` over the rows
  that reach it (1 where both are 0: a start on its goal).

Differences from the authors' code, all where their code cannot tell: they compare the number of cells on the two
paths (`paths.sum()`), vinadv compares costs under the maps' movement model (the same thing on their `moore` maps,
where every move costs 1 and a searched path has no repeated cell); they count a failed search's path as whatever
their backtracking gives, vinadv as not optimal; Exp includes the rows that fail, as `calc_metrics` does (their
`compute_opt_exp` leaves them out). On `octile` and `news` maps the reference A* is vinadv's (module doc of
`vinadv.planners.classical.astar`), so Exp there is vinadv's extension of their definition.
"""

from __future__ import annotations

from typing import TypedDict

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.grid.paths import path_costs
from vinadv.grid.shortest_paths import COST_TOL
from vinadv.planners.classical.astar import AStarPlanner
from vinadv.planners.search import SearchResult

#: the authors' guard against a zero in the harmonic mean
EPS = 1e-10


class SearchMetrics(TypedDict):
    """Opt / Exp / Hmean and the figures beside them (`search_metrics`); None where undefined."""

    rows: int
    opt: float | None
    exp: float | None
    hmean: float | None
    success: float | None
    cost_ratio: float | None
    expansions: float | None
    astar_expansions: float | None


def search_metrics(
    costs: np.ndarray,
    reached: np.ndarray,
    optimal_costs: np.ndarray,
    expansions: np.ndarray | None = None,
    astar_expansions: np.ndarray | None = None,
    maps: np.ndarray | None = None,
) -> SearchMetrics:
    """Opt / Exp / Hmean, success and cost ratio of `n` rows (module doc).

    Args:
        costs: `(n,)` the cost of each row's path (any value where it does not reach the goal).
        reached: `(n,)` bool, the path reaches the goal.
        optimal_costs: `(n,)` the optimal cost of each row.
        expansions: `(n,)` the cells the planner expanded; None for a planner that does not report them (Exp and
            Hmean are then None).
        astar_expansions: `(n,)` >= 1, the cells vanilla A* expanded on the same rows (with `expansions`).
        maps: `(n,)` int, the map of each row: with several rows on a map, Hmean is averaged over the maps' own
            harmonic means (None: one row per map).
    """
    costs = np.asarray(costs, dtype=np.float64).reshape(-1)
    reached = np.asarray(reached, dtype=bool).reshape(-1)
    optimal_costs = np.asarray(optimal_costs, dtype=np.float64).reshape(-1)
    n = len(costs)
    if len(reached) != n or len(optimal_costs) != n:
        raise InputError(f"search_metrics: {n} costs, {len(reached)} reached, {len(optimal_costs)} optimal costs")
    optimal = reached & (np.abs(costs - optimal_costs) <= COST_TOL)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(optimal_costs[reached] > 0, costs[reached] / optimal_costs[reached], 1.0)
    out: SearchMetrics = {
        "rows": n,
        "opt": float(optimal.mean()) if n else None,
        "exp": None,
        "hmean": None,
        "success": float(reached.mean()) if n else None,
        "cost_ratio": float(ratio.mean()) if len(ratio) else None,
        "expansions": None,
        "astar_expansions": None,
    }
    if expansions is None or n == 0:
        return out
    expansions = np.asarray(expansions, dtype=np.float64).reshape(-1)
    reference = np.asarray(astar_expansions, dtype=np.float64).reshape(-1)
    if len(expansions) != n or len(reference) != n or (reference < 1).any():
        raise InputError(f"search_metrics: expansions and astar_expansions must be {n} counts, A*'s >= 1")
    saved = np.maximum((reference - expansions) / reference, 0.0)
    out["exp"] = float(saved.mean())
    out["expansions"] = float(expansions.mean())
    out["astar_expansions"] = float(reference.mean())
    if maps is None or len(np.unique(maps)) == n:  # one row per map: the harmonic mean of the means
        out["hmean"] = float(harmonic_mean(optimal.mean(), saved.mean()))
    else:  # several starts per map: each map's harmonic mean over its starts, averaged over the maps
        _, owner = np.unique(np.asarray(maps).reshape(-1), return_inverse=True)
        rows = np.bincount(owner)
        per_map = harmonic_mean(np.bincount(owner, weights=optimal) / rows, np.bincount(owner, weights=saved) / rows)
        out["hmean"] = float(per_map.mean())
    return out


def harmonic_mean(opt, exp):
    """The authors' Hmean of Opt and Exp (scalars or arrays): `2 / (1 / (opt + EPS) + 1 / (exp + EPS))`."""
    return 2.0 / (1.0 / (opt + EPS) + 1.0 / (exp + EPS))


def evaluate_search(planner, maps: MapSet, chunk_size: int = 256, progress: bool = False) -> SearchMetrics:
    """`search_metrics` of `planner` (any `Planner`, its `plan`) on every start of `maps`, against vanilla A*
    (`astar` on the maps' movement model) from the same starts and the maps' exact expert costs."""
    mask = maps.start_mask.reshape(-1)
    result = planner.plan(
        maps.obstacles,
        maps.starts,
        maps.goals,
        maps.corner_cutting,
        maps.moves,
        chunk_size=chunk_size,
        progress=progress,
    )
    expansions = result.expansions if isinstance(result, SearchResult) else None
    reference = None
    if expansions is not None:
        astar = AStarPlanner(maps.size, maps.moves)
        reference = astar.plan(
            maps.obstacles, maps.starts, maps.goals, maps.corner_cutting, maps.moves, chunk_size=chunk_size
        ).expansions
        expansions, reference = expansions[mask], reference[mask]
    owner = np.repeat(np.arange(len(maps)), maps.n_starts)[mask]
    return search_metrics(
        path_costs(result.paths, maps.moves)[mask],
        result.reached[mask],
        maps.expert_costs.reshape(-1)[mask],
        expansions,
        reference,
        owner,
    )
