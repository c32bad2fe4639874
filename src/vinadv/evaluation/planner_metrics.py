"""How good a VIN (or any planner, `evaluate_planner`) is on a set of maps: action accuracy and rollout metrics
(`PlannerMetrics`, `RolloutMetrics`: `vinadv.planners.records`).

- action accuracy: over every free, reachable, non-goal cell of every map, the fraction where the argmax action
  (lowest index on ties) is one of the optimal actions (Dijkstra).
- rollouts (DESIGN.md rule, by `vinadv.planners.vin.engine`), from every start of every map:
  success rate (goal reached), % optimal (path cost equals the expert cost within 1e-9; an unreached path is
  not optimal), mean extra path cost of the reached paths (cost - expert cost), and the termination reasons.

A planner without a policy at every cell (`Capabilities.policy` False: a search planner) has no action accuracy
(`action_accuracy` None, `action_cells` 0); its paths get the same rollout figures. The search figures (Opt, Exp,
Hmean, cost ratio) of any planner are `vinadv.evaluation.search_metrics`'.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch
from tqdm import tqdm

from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import DEFAULT_MOVES, move_model, require_moves
from vinadv.grid.shortest_paths import COST_TOL, optimal_actions, shortest_distances
from vinadv.planners.records import LengthBucketMetrics, PlannerMetrics, RolloutMetrics
from vinadv.planners.result import PlanResult
from vinadv.planners.vin import engine
from vinadv.planners.vin.model import VIN, make_input
from vinadv.vocabulary import TERMINATIONS

#: planner(obstacles (B,N,N), goals (B,2), starts (B,S,2), model, corner_cutting) -> PlanResult, path b*S+s.
MultiStartPlanner = Callable[[np.ndarray, np.ndarray, np.ndarray, VIN, bool], PlanResult]


def action_accuracy_counts(
    model: VIN, obstacles: np.ndarray, goals: np.ndarray, corner_cutting: bool = True, batch_size: int = 256
) -> tuple[int, int]:
    """`(correct, cells)`: supervised cells (free, reachable, not the goal) whose argmax action is optimal."""
    correct, cells = 0, 0
    model.eval()
    for i in range(0, len(obstacles), batch_size):
        obs, g = obstacles[i : i + batch_size], goals[i : i + batch_size]
        with torch.no_grad():
            logits = model.action_logits(make_input(obs, g)).numpy()
        c, n = accuracy_counts_from_logits(logits, obs, g, corner_cutting)
        correct += c
        cells += n
    return correct, cells


def accuracy_counts_from_logits(
    logits: np.ndarray,
    obstacles: np.ndarray,
    goals: np.ndarray,
    corner_cutting: bool = True,
    moves: str = DEFAULT_MOVES,
) -> tuple[int, int]:
    """`(correct, cells)` for logits `(B, N, N, A)` of the maps `obstacles (B, N, N)`, `goals (B, 2)`, under the
    movement model `moves` (its optimal actions; the argmax over its actions, as the rollouts take it)."""
    model = move_model(moves)
    dist, _ = shortest_distances(obstacles, goals, corner_cutting, model)
    optimal = optimal_actions(dist, obstacles, corner_cutting, model)
    best = np.argmax(logits[..., : model.n_actions], axis=-1)  # lowest index on ties, as the rollout rule
    supervised = optimal.any(axis=-1)
    hit = np.take_along_axis(optimal, best[..., None], axis=-1)[..., 0]
    return int((hit & supervised).sum()), int(supervised.sum())


def _engine_planner(obstacles, goals, starts, model, corner_cutting) -> PlanResult:
    if hasattr(engine, "plan_maps"):  # one value map per map, shared by its starts
        return engine.plan_maps(obstacles, goals, starts, model, corner_cutting)
    s = starts.shape[1]
    idx = np.repeat(np.arange(len(obstacles)), s)
    return engine.plan_batch(obstacles[idx], starts.reshape(-1, 2), goals[idx], model, corner_cutting)


#: width, in moves of the optimal path, of the buckets of `rollout_metrics`' `by_length`
LENGTH_BUCKET = 5


def rollout_metrics(
    result: PlanResult,
    expert_costs: np.ndarray,
    mask: np.ndarray | None = None,
    expert_moves: np.ndarray | None = None,
    moves: str = DEFAULT_MOVES,
) -> RolloutMetrics:
    """Rollout figures from a `PlanResult` and the expert (optimal) cost of each path `(B,)`.

    `mask` `(B,)` bool, if given, keeps only those paths (a MapSet's padded start slots are left out).
    `expert_moves` `(B,)`, if given, the optimal path's move count L of each path: the figures then also come
    `by_length`, in buckets of `LENGTH_BUCKET` moves (where a planner fails: long paths take more decisions).
    `moves`: the maps' movement model (the paths' costs are its costs).
    """
    keep = np.ones(len(result), dtype=bool) if mask is None else np.asarray(mask, dtype=bool).reshape(-1)
    expert_costs = np.asarray(expert_costs, dtype=np.float64).reshape(-1)[keep]
    n = int(keep.sum())
    costs = result.paths.costs(moves)[keep]
    reached = np.asarray(result.reached, dtype=bool)[keep]
    optimal = reached & (np.abs(costs - expert_costs) <= COST_TOL)
    extra = costs[reached] - expert_costs[reached]
    names = result.termination_names[keep]
    metrics: RolloutMetrics = {
        "rollouts": int(n),
        "success_rate": float(reached.mean()) if n else float("nan"),
        "optimal_rate": float(optimal.mean()) if n else float("nan"),
        "optimal_rate_of_reached": float(optimal[reached].mean()) if reached.any() else float("nan"),
        "mean_extra_cost": float(extra.mean()) if len(extra) else float("nan"),
        "mean_extra_cost_relative": float((extra / expert_costs[reached]).mean()) if len(extra) else float("nan"),
        "terminations": {t: int((names == t).sum()) for t in TERMINATIONS},
    }
    if expert_moves is not None:
        lengths = np.asarray(expert_moves, dtype=np.int64).reshape(-1)[keep]
        metrics["by_length"] = _by_length(lengths, reached, optimal, result.termination[keep])
    return metrics


def _by_length(
    moves: np.ndarray, reached: np.ndarray, optimal: np.ndarray, termination: np.ndarray
) -> list[LengthBucketMetrics]:
    """One row per non-empty bucket of `LENGTH_BUCKET` optimal moves: rollouts, success, optimal paths and the
    terminations, counted with `bincount` over the buckets."""
    bucket = moves // LENGTH_BUCKET
    size = int(bucket.max()) + 1 if len(bucket) else 0
    n = np.bincount(bucket, minlength=size)
    ok = np.bincount(bucket, weights=reached, minlength=size)
    opt = np.bincount(bucket, weights=optimal, minlength=size)
    ends = {t: np.bincount(bucket, weights=termination == i, minlength=size) for i, t in enumerate(TERMINATIONS)}
    return [
        {
            "moves": [int(b * LENGTH_BUCKET), int((b + 1) * LENGTH_BUCKET - 1)],
            "rollouts": int(n[b]),
            "success_rate": float(ok[b] / n[b]),
            "optimal_rate": float(opt[b] / n[b]),
            "terminations": {t: int(ends[t][b]) for t in TERMINATIONS},
        }
        for b in np.flatnonzero(n)
    ]


def evaluate_vin(
    model: VIN, maps: MapSet, planner: MultiStartPlanner | None = None, batch_size: int = 256, progress: bool = False
) -> PlannerMetrics:
    """All figures for `model` on `maps` (rollouts from every start). `planner` defaults to the engine."""
    planner = planner or _engine_planner

    require_moves(maps.moves, ("octile",), "the VIN's evaluation")  # the engine plans octile moves

    def counts(obs, goals):
        return action_accuracy_counts(model, obs, goals, maps.corner_cutting, batch_size)

    return _evaluate(
        maps,
        counts,
        lambda obs, goals, starts: planner(obs, goals, starts, model, maps.corner_cutting),
        batch_size,
        progress,
    )


def evaluate_planner(
    planner, maps: MapSet, batch_size: int = 256, progress: bool = False, result: PlanResult | None = None
) -> PlannerMetrics:
    """All figures for any `vinadv.planners.interface.Planner` on `maps`: action accuracy from its logits, rollouts
    (from every start) by its `plan`, under the maps' movement model, which the planner must plan
    (`Planner.for_moves`: one of another model is refused in one line). A search planner's paths get the rollout
    figures, and no action accuracy (it declares no policy). `result`: the planner's `plan` of every start of `maps`
    already made (path `b*S+s`), used instead of planning again."""
    planner = planner.for_moves(maps.moves)

    def counts(obs, goals):
        logits = planner.logits(obs, goals).transpose(0, 2, 3, 1)
        return accuracy_counts_from_logits(logits, obs, goals, maps.corner_cutting, maps.moves)

    return _evaluate(
        maps,
        counts if planner.capabilities.policy else None,
        None
        if result is not None
        else lambda obs, goals, starts: planner.plan(obs, starts, goals, maps.corner_cutting, maps.moves),
        batch_size,
        progress,
        result,
    )


def _evaluate(
    maps: MapSet, counts, plan, batch_size: int, progress: bool, result: PlanResult | None = None
) -> PlannerMetrics:
    """Figures over `maps` in chunks: `counts(obs, goals) -> (correct, cells)` (None: no action accuracy, a search
    planner's), `plan(obs, goals, starts)` (None: `result`, the plan of every start, is given)."""
    obstacles, goals, starts = maps.obstacles, maps.goals, maps.starts
    chunks = range(0, len(maps), batch_size)
    if progress:
        chunks = tqdm(chunks, desc="evaluating", unit="batch")
    correct, cells, parts = 0, 0, []
    for i in chunks:
        sl = slice(i, i + batch_size)
        if counts is not None:
            c, n = counts(obstacles[sl], goals[sl])
            correct += c
            cells += n
        if plan is not None:
            parts.append(plan(obstacles[sl], goals[sl], starts[sl]))
    if plan is not None:
        result = PlanResult.concat(parts)
    lengths = maps.expert.lengths - 1  # cells - 1: an optimal path's move count L, the same for all of them
    return {
        "maps": len(maps),
        "size": maps.size,
        "starts_per_map": maps.n_starts,
        "seed": int(maps.seed),
        "corner_cutting": bool(maps.corner_cutting),
        "action_accuracy": None if counts is None else (correct / cells if cells else float("nan")),
        "action_cells": cells,
        **rollout_metrics(result, maps.expert_costs, maps.start_mask, lengths, maps.moves),
    }
