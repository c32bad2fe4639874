"""The `optimal` planner: exact shortest paths, the control every learned planner is compared with.

Its logits are minus the excess cost of each move over the best one: `-(cost(a) + d(next) - d(cell))`, with `d` the
exact cost-to-go (Dijkstra, `vinadv.grid.shortest_paths`). Every optimal action gets exactly 0 (the optimal set is
decided with the tolerance of `optimal_actions`, so rounding never splits a tie) and every other legal move a
negative logit, so the rollout's argmax (lowest index on ties) takes the lowest-index optimal action: DESIGN.md's
tie-break, the paths of `expert_paths`. An illegal move gets `ILLEGAL`; at cells without an optimal action (the
goal, obstacles, cells cut off from the goal) every legal move gets 0.

It follows any movement model (`vinadv.grid.moves`): costs, cost-to-go and legal moves are the model's, and an
action outside it (a diagonal on `news`) is `ILLEGAL` everywhere.
"""

from __future__ import annotations

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.actions import N_ACTIONS
from vinadv.grid.moves import DEFAULT_MOVES, check_moves, move_model
from vinadv.grid.shortest_paths import negative_cost_to_go, optimal_actions, shortest_distances, valid_moves
from vinadv.planners.interface import Capabilities, Planner

#: logit of an illegal move: below the excess cost of any legal move (at most about 2 * sqrt(2) * N * N).
ILLEGAL = -1.0e9


class OptimalPlanner(Planner):
    """Exact shortest paths with DESIGN.md's tie-break, as a whole-map policy planner (no weights), on the movement
    model `moves`. Capabilities: a policy at every cell and value maps of its own (minus the exact cost-to-go); no
    weights, so no gradients."""

    capabilities = Capabilities(policy=True, value_maps=True)

    def __init__(self, size: int, corner_cutting: bool = True, moves: str = DEFAULT_MOVES):
        self.name, self.size, self.corner_cutting = "optimal", int(size), bool(corner_cutting)
        self.moves = check_moves(moves, self.corner_cutting)

    @property
    def config(self) -> dict:
        # octile, the default, is left out: the records of octile runs stay as they were
        return {"corner_cutting": self.corner_cutting, **({} if self.moves == DEFAULT_MOVES else {"moves": self.moves})}

    def for_moves(self, moves: str) -> OptimalPlanner:
        """The `optimal` planner of the movement model `moves` (itself when it is this one's)."""
        model = move_model(moves)
        return self if model.name == self.moves else OptimalPlanner(self.size, self.corner_cutting, model.name)

    def policy_logits(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """`(B, 8, N, N)` float64: 0 for optimal moves, minus the excess cost for other legal ones, ILLEGAL else."""
        model = move_model(self.moves)
        dist, _ = shortest_distances(obstacles, goals, self.corner_cutting, model.name)
        legal = valid_moves(obstacles, self.corner_cutting, model.name)
        optimal = optimal_actions(dist, obstacles, self.corner_cutting, model.name)
        b, n = obstacles.shape[0], obstacles.shape[1]
        padded = np.full((b, n + 2, n + 2), np.inf)
        padded[:, 1:-1, 1:-1] = dist
        out = np.full((b, N_ACTIONS, n, n), ILLEGAL)  # the actions outside the model stay illegal
        has_optimal = optimal.any(axis=-1)
        for a, (dr, dc) in enumerate(model.deltas):
            via = padded[:, 1 + dr : 1 + dr + n, 1 + dc : 1 + dc + n] + model.costs[a]
            with np.errstate(invalid="ignore"):  # inf - inf where both cells are cut off from the goal
                excess = np.where(has_optimal, via - dist, 0.0)
            # a legal move to a cell cut off from the goal, from a cell that is not: excess inf -> a finite floor
            excess = np.minimum(np.nan_to_num(excess, nan=0.0, posinf=-ILLEGAL / 2), -ILLEGAL / 2)
            out[:, a] = np.where(optimal[..., a], 0.0, np.where(legal[..., a], -excess, ILLEGAL))
        return out

    def value_maps(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """Minus the exact cost-to-go, `(B, N, N)` float64; NaN where the goal cannot be reached (and on obstacles)."""
        obstacles = np.ascontiguousarray(obstacles, dtype=bool)
        self._check_size(obstacles)
        return negative_cost_to_go(obstacles, goals, self.corner_cutting, self.moves)

    def _chunk_planner(self, corner_cutting: bool):
        if corner_cutting != self.corner_cutting:  # the logits follow the planner's own move rule
            raise InputError(
                f"planner 'optimal' was made with corner_cutting={self.corner_cutting}, "
                f"the maps use corner_cutting={corner_cutting}"
            )
        return super()._chunk_planner(corner_cutting)
