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

TransPath's own metrics (Kirilenko et al., AAAI 2023; their `eval.py`), `transpath_ratios`, beside these for a TransPath
planner (`evaluate_search(..., theirs=True)`; `octile` maps only): the reference is their vanilla A*, their search
(`vinadv.planners.transpath.search`, the compiled replica) with the plain octile heuristic, `f = 0.5 g + 0.501 h` (the
`cf` search with every correction factor 1), not vinadv's exact A*; the rows kept are the hard ones, whose vanilla
path cost is at least `HARDNESS` (1.05) times the octile heuristic at the start (their `hardness_limit`); on those,
the expansions ratio is the mean of `E / E_vanilla` and the cost ratio the mean of `cost / vanilla cost` (over the
kept rows the planner's path reaches; the others are counted, `unreached`). Below 1 is fewer cells and shorter paths
than their vanilla A*. Costs are float64 path costs under the maps' movement model, the octile heuristic
`min(dr, dc) * sqrt 2 + |dr - dc|` in float64.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NotRequired, TypedDict

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.grid.paths import path_costs
from vinadv.grid.shortest_paths import COST_TOL
from vinadv.planners.classical.astar import AStarPlanner
from vinadv.planners.interface import plan_every_start
from vinadv.planners.result import PlanResult
from vinadv.planners.search import SearchResult

#: the authors' guard against a zero in the harmonic mean
EPS = 1e-10
#: TransPath's `eval.py`: the rows kept are those whose vanilla cost is at least this times the octile heuristic
HARDNESS = 1.05


class TransPathRatios(TypedDict):
    """TransPath's metrics (`transpath_ratios`): their vanilla A* the reference; None where no row is kept."""

    rows: int
    kept: int
    hardness: float
    expansions_ratio: float | None
    cost_ratio: float | None
    unreached: int
    expansions: float | None
    vanilla_expansions: float | None


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
    #: TransPath's own ratios against their vanilla A* (`evaluate_search(..., theirs=True)` only)
    transpath: NotRequired[TransPathRatios]


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
    ratio = row_cost_ratios(costs, reached, optimal_costs)[reached]
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
    saved = row_exp(expansions, reference)
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


def row_cost_ratios(costs, reached, optimal_costs) -> np.ndarray:
    """`(n,)` each row's cost ratio `cost / optimal cost` (1 where both are 0: a start on its goal), NaN where the
    path does not reach the goal: the values `search_metrics` averages into `cost_ratio`."""
    costs = np.asarray(costs, dtype=np.float64).reshape(-1)
    reached = np.asarray(reached, dtype=bool).reshape(-1)
    optimal_costs = np.asarray(optimal_costs, dtype=np.float64).reshape(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(optimal_costs > 0, costs / optimal_costs, 1.0)
    return np.where(reached, ratio, np.nan)


def row_exp(expansions, astar_expansions) -> np.ndarray:
    """`(n,)` each row's share of A*'s search saved, `max(0, (E_A* - E) / E_A*)`: the values `search_metrics`
    averages into Exp (`astar_expansions` >= 1)."""
    expansions = np.asarray(expansions, dtype=np.float64).reshape(-1)
    reference = np.asarray(astar_expansions, dtype=np.float64).reshape(-1)
    return np.maximum((reference - expansions) / reference, 0.0)


def harmonic_mean(opt, exp):
    """The authors' Hmean of Opt and Exp (scalars or arrays): `2 / (1 / (opt + EPS) + 1 / (exp + EPS))`."""
    return 2.0 / (1.0 / (opt + EPS) + 1.0 / (exp + EPS))


def octile_distances(starts: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """`(n,)` float64 octile heuristic `min(dr, dc) * sqrt 2 + |dr - dc|` from each start `(n, 2)` to its goal."""
    d = np.abs(np.asarray(starts, dtype=np.int64) - np.asarray(goals, dtype=np.int64)).reshape(-1, 2)
    return np.minimum(d[:, 0], d[:, 1]) * math.sqrt(2.0) + np.abs(d[:, 0] - d[:, 1])


def transpath_ratios(
    costs: np.ndarray,
    reached: np.ndarray,
    expansions: np.ndarray,
    vanilla_costs: np.ndarray,
    vanilla_reached: np.ndarray,
    vanilla_expansions: np.ndarray,
    octile_start: np.ndarray,
    hardness: float = HARDNESS,
) -> TransPathRatios:
    """TransPath's expansions ratio and cost ratio of `n` rows against their vanilla A* (module doc).

    Args:
        costs: `(n,)` the planner's path costs.
        reached: `(n,)` whether each of the planner's paths reaches the goal.
        expansions: `(n,)` the cells the planner expanded.
        vanilla_costs: `(n,)` their vanilla A*'s path costs on the same rows.
        vanilla_reached: `(n,)` whether each of vanilla A*'s paths reaches the goal.
        vanilla_expansions: `(n,)` the cells vanilla A* expanded.
        octile_start: `(n,)` the octile heuristic at each row's start (`octile_distances`).
        hardness: the rows kept: reached by vanilla A*, start off the goal, vanilla cost >= hardness * octile_start.
    """
    arrays = [np.asarray(a, dtype=np.float64).reshape(-1) for a in (costs, expansions, vanilla_costs)]
    costs, expansions, vanilla_costs = arrays
    vanilla_expansions = np.asarray(vanilla_expansions, dtype=np.float64).reshape(-1)
    octile_start = np.asarray(octile_start, dtype=np.float64).reshape(-1)
    reached = np.asarray(reached, dtype=bool).reshape(-1)
    vanilla_reached = np.asarray(vanilla_reached, dtype=bool).reshape(-1)
    n = len(costs)
    if any(
        len(a) != n for a in (reached, expansions, vanilla_costs, vanilla_reached, vanilla_expansions, octile_start)
    ):
        raise InputError(f"transpath_ratios: every array must hold the {n} rows")
    kept = vanilla_reached & (octile_start > 0) & (vanilla_costs >= hardness * octile_start)
    both = kept & reached
    return {
        "rows": n,
        "kept": int(kept.sum()),
        "hardness": float(hardness),
        "expansions_ratio": float((expansions[kept] / vanilla_expansions[kept]).mean()) if kept.any() else None,
        "cost_ratio": float((costs[both] / vanilla_costs[both]).mean()) if both.any() else None,
        "unreached": int((kept & ~reached).sum()),
        "expansions": float(expansions[kept].mean()) if kept.any() else None,
        "vanilla_expansions": float(vanilla_expansions[kept].mean()) if kept.any() else None,
    }


def vanilla_transpath(obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True):
    """TransPath's vanilla A* on `(B, N, N)` rows: their search (the compiled replica) with the plain octile heuristic,
    `f = 0.5 g + 0.501 h` (the `cf` search with every correction factor 1: `octile / max(1, 0.1)` is the octile
    heuristic, exactly). Returns its `SearchResult`."""
    from vinadv.planners.transpath.search import transpath_search  # noqa: PLC0415 (Numba's compile, when asked)

    ones = np.ones(np.shape(obstacles), dtype=np.float32)
    return transpath_search(ones, obstacles, starts, goals, "cf", corner_cutting)


@dataclass(frozen=True)
class SearchRows:
    """The rows `search_metrics` averages, one per start of a `MapSet` that has one (`search_rows`), in row order:
    `costs`, `reached` and `optimal_costs` `(n,)`; `expansions` and A*'s `astar_expansions` `(n,)` (None for a
    planner that reports no expansions); `maps` `(n,)` the map of each row."""

    costs: np.ndarray
    reached: np.ndarray
    optimal_costs: np.ndarray
    expansions: np.ndarray | None
    astar_expansions: np.ndarray | None
    maps: np.ndarray

    def metrics(self) -> SearchMetrics:
        """Opt / Exp / Hmean and the figures beside them (`search_metrics`)."""
        return search_metrics(
            self.costs, self.reached, self.optimal_costs, self.expansions, self.astar_expansions, self.maps
        )

    @property
    def cost_ratio(self) -> np.ndarray:
        """`(n,)` each row's cost ratio, NaN where it does not reach (`row_cost_ratios`)."""
        return row_cost_ratios(self.costs, self.reached, self.optimal_costs)

    @property
    def exp(self) -> np.ndarray | None:
        """`(n,)` each row's share of A*'s search saved (`row_exp`); None without expansions."""
        return None if self.expansions is None else row_exp(self.expansions, self.astar_expansions)


def search_rows(
    planner, maps: MapSet, chunk_size: int = 256, progress: bool = False, result: PlanResult | None = None
) -> SearchRows:
    """The rows of `planner` (any `Planner`, its `plan`) on every start of `maps`: its paths' costs, their optimal
    (expert) costs and, for a search planner, its expansions beside vanilla A*'s (`astar` on the maps' movement
    model) from the same starts. `result`: the planner's `plan` of every start already made, used instead of
    planning again."""
    mask = maps.start_mask.reshape(-1)
    if result is None:
        result = plan_every_start(planner, maps, chunk_size=chunk_size, progress=progress)
    expansions = result.expansions if isinstance(result, SearchResult) else None
    reference = None
    if expansions is not None:
        astar = AStarPlanner(maps.size, maps.moves)
        reference = plan_every_start(astar, maps, chunk_size=chunk_size).expansions[mask]
        expansions = expansions[mask]
    return SearchRows(
        costs=path_costs(result.paths, maps.moves)[mask],
        reached=result.reached[mask],
        optimal_costs=maps.expert_costs.reshape(-1)[mask],
        expansions=expansions,
        astar_expansions=reference,
        maps=np.repeat(np.arange(len(maps)), maps.n_starts)[mask],
    )


def evaluate_search(
    planner,
    maps: MapSet,
    chunk_size: int = 256,
    progress: bool = False,
    theirs: bool = False,
    result: PlanResult | None = None,
) -> SearchMetrics:
    """`search_metrics` of `planner` on every start of `maps` (`search_rows`: against vanilla A* from the same
    starts and the maps' exact expert costs); with `theirs` (a search planner on `octile` maps), also TransPath's
    ratios against their vanilla A* (`transpath_ratios`, under the key `transpath`). `result`: the planner's `plan`
    of every start of `maps` already made, used instead of planning again."""
    rows = search_rows(planner, maps, chunk_size=chunk_size, progress=progress, result=result)
    out = rows.metrics()
    if theirs:
        if rows.expansions is None or maps.moves != "octile":
            raise InputError(f"TransPath's ratios need a search planner on octile maps, not {maps.moves} maps")
        starts = maps.starts.reshape(-1, 2)[maps.start_mask.reshape(-1)]
        goals = maps.goals[rows.maps]
        vanilla = vanilla_transpath(maps.obstacles[rows.maps], starts, goals, maps.corner_cutting)
        out["transpath"] = transpath_ratios(
            rows.costs,
            rows.reached,
            rows.expansions,
            path_costs(vanilla.paths, maps.moves),
            vanilla.reached,
            vanilla.expansions,
            octile_distances(starts, goals),
        )
    return out
