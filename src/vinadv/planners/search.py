"""The second planner shape: a search planner answers paths, not a policy.

A search planner (A*, weighted A*, Neural A*, a user's own) implements

    plan_paths(obstacles (B, N, N) bool, starts (B, 2) int64, goals (B, 2) int64, corner_cutting) -> SearchResult

one path per row, with the cells it expanded where it reports them. `SearchPlanner.plan_maps` plans a maps file with
S starts per map as S rows per map, so a search planner works wherever a `Planner` does (plan, attack, run,
identify, robustness, eval). It has no policy logits: `policy_logits` refuses with a `PlannerError`, and the code
that needs logits (the rollout metrics' per-cell policy, `interop.protocols`) says it needs a policy planner.

Attack signals (`attacks.strategies`): `value_maps` is the planner's own cost or heuristic map where it has one,
else minus the exact cost-to-go (as `optimal`'s); `differentiable` is None, and a planner whose search is
differentiable offers `differentiable_paths` instead (None otherwise).
"""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.shortest_paths import shortest_distances
from vinadv.planners.interface import DEFAULT_CHUNK, Planner, PlannerError, check_multi_inputs
from vinadv.planners.result import PlanResult, check_plan_inputs

if TYPE_CHECKING:
    from torch import nn


@dataclass(kw_only=True, eq=False)
class SearchResult(PlanResult):
    """B searched paths (`PlanResult`: paths, termination) and the cells each search expanded.

    Attributes:
        expanded: `(B, N, N)` bool, the cells search b expanded (closed), start included; None for a planner that
            does not report them (its Exp metric is then undefined).
    """

    expanded: np.ndarray | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.expanded is not None:
            self.expanded = np.asarray(self.expanded, dtype=bool)
            if self.expanded.ndim != 3 or len(self.expanded) != len(self.paths):
                raise InputError(
                    f"SearchResult: expanded has shape {self.expanded.shape}, expected ({len(self.paths)}, N, N)"
                )

    @property
    def expansions(self) -> np.ndarray | None:
        """`(B,)` int64, how many cells each search expanded; None where the planner does not report them."""
        return None if self.expanded is None else self.expanded.sum(axis=(1, 2), dtype=np.int64)


class SearchPlanner(Planner):
    """A planner that searches: `plan_paths` gives the paths (and expansions); no policy logits.

    Subclasses set `name`, `size`, `moves` (the movement model they search, `vinadv.grid.moves`) and implement
    `plan_paths`. They may override `value_maps` (their own cost or heuristic map) and `differentiable_paths`.
    """

    @abstractmethod
    def plan_paths(
        self, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True
    ) -> SearchResult:
        """One searched path per row: obstacles `(B, N, N)` bool, starts and goals `(B, 2)` int64 `(row, col)`."""

    def policy_logits(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        raise PlannerError(f"planner {self.name!r} is a search planner: it answers paths, not policy logits")

    @property
    def differentiable_paths(self) -> nn.Module | None:
        """A module `module(obstacles (B,N,N) float, starts (B,2) int64, goals (B,2) int64) -> (B, N, N)` float path
        map, differentiable with respect to the obstacles (the saliency attack uses it); None for a planner whose
        search has no gradients."""
        return None

    def value_maps(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """Minus the exact cost-to-go under the planner's movement model, `(B, N, N)` float64 (NaN where the goal
        cannot be reached): the ranking signal of a search planner without a cost or heuristic map of its own."""
        obstacles = np.ascontiguousarray(obstacles, dtype=bool)
        self._check_size(obstacles)
        dist, _ = shortest_distances(obstacles, np.asarray(goals, dtype=np.int64), True, self.moves)
        return np.where(np.isfinite(dist), -dist, np.nan)

    def plan_maps(
        self,
        obstacles: np.ndarray,
        goals: np.ndarray,
        starts: np.ndarray,
        corner_cutting: bool = True,
        chunk_size: int = DEFAULT_CHUNK,
        progress: bool = False,
    ) -> SearchResult:
        """Paths from `starts (B, S, 2)`: row `b * S + s` searches from start `s` of map `b`, `chunk_size` rows at a
        time."""
        obstacles, goals, starts = check_multi_inputs(obstacles, goals, starts)
        self._check_size(obstacles)
        per_map = starts.shape[1]
        map_of_row = np.repeat(np.arange(len(obstacles)), per_map)
        rows = starts.reshape(-1, 2)
        chunk_size = max(1, int(chunk_size))
        chunks = range(0, len(rows), chunk_size)
        if progress:
            from tqdm import tqdm

            chunks = tqdm(chunks, unit="chunk", desc=f"planning ({self.name})")
        parts = [
            self.plan_paths(
                obstacles[map_of_row[i : i + chunk_size]],
                rows[i : i + chunk_size],
                goals[map_of_row[i : i + chunk_size]],
                corner_cutting,
            )
            for i in chunks
        ]
        return SearchResult.concat(parts)

    def plan_batch(
        self, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True
    ) -> SearchResult:
        obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
        self._check_size(obstacles)
        return self.plan_paths(obstacles, starts, goals, corner_cutting)
