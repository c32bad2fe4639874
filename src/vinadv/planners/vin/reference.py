"""The reference planner: what the public VIN ports do, kept as the oracle for the fast engine.

At every step of every rollout it re-runs the full PyTorch VIN (batch size 1, float32) on the map and takes the
logits at the agent's cell with `VIN.forward(x, rows, cols)`. It is slow on purpose (about 3.5 ms per forward at
28x28) and simple enough to be obviously right. The rollout rule is DESIGN.md's, spelled out in `rollout`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch

from vinadv.grid.actions import ACTION_DELTAS
from vinadv.planners.result import (
    COLLISION,
    GOAL,
    LOOP,
    STEP_LIMIT,
    PlanResult,
    check_plan_inputs,
    step_limits,
)
from vinadv.planners.vin.model import VIN, make_input


def rollout(
    action_at: Callable[[int, int], int],
    obstacles: np.ndarray,
    start: tuple[int, int],
    goal: tuple[int, int],
    max_moves: int,
    corner_cutting: bool = True,
) -> tuple[list[tuple[int, int]], int]:
    """Follow a policy from `start`: returns the visited cells (start included) and the termination code.

    Order of the checks at each cell: the goal ends it ('goal'); a path that already made `max_moves` moves ends
    as 'step_limit' (it would need more than `max_moves`); otherwise the policy's move is taken: off the grid, into
    an obstacle, or (without corner cutting) diagonally past an obstacle is a 'collision' and a move to a cell
    already on the path a 'loop' (neither target cell is appended).
    """
    n = obstacles.shape[0]
    cur = (int(start[0]), int(start[1]))
    goal = (int(goal[0]), int(goal[1]))
    path = [cur]
    visited = {cur}
    while True:
        if cur == goal:
            return path, GOAL
        if len(path) - 1 >= max_moves:
            return path, STEP_LIMIT
        dr, dc = (int(d) for d in ACTION_DELTAS[action_at(*cur)])
        nr, nc = cur[0] + dr, cur[1] + dc
        if not (0 <= nr < n and 0 <= nc < n) or obstacles[nr, nc]:
            return path, COLLISION
        if not corner_cutting and dr != 0 and dc != 0 and (obstacles[nr, cur[1]] or obstacles[cur[0], nc]):
            return path, COLLISION
        if (nr, nc) in visited:
            return path, LOOP
        cur = (nr, nc)
        path.append(cur)
        visited.add(cur)


def torch_action_at(model: VIN, x: torch.Tensor, q: torch.Tensor | None = None) -> Callable[[int, int], int]:
    """The ports' policy for one map `x (1, 2, N, N)`: argmax (lowest index on ties) of `VIN.forward` at a cell.

    With `q` (that map's `model.q_values(x)`, computed once) the logits are the same numbers `forward` computes
    (it picks `q[arange(1), :, row, col]` and applies `fc`), without re-running value iteration each step.
    """

    def action_at(row: int, col: int) -> int:
        with torch.no_grad():
            rows, cols = torch.tensor([row]), torch.tensor([col])
            if q is None:
                logits = model(x, rows, cols)
            else:
                logits = model.fc(q[torch.arange(1), :, rows, cols])
        return int(np.argmax(logits[0].numpy()))  # np.argmax returns the first of tied maxima

    return action_at


def plan_reference(
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    model: VIN,
    corner_cutting: bool = True,
    chunk_size: int | None = None,
) -> PlanResult:
    """Plan one path per map by re-running the whole VIN at every step (the public ports' way).

    Args:
        obstacles: `(B, N, N)` bool. starts, goals: `(B, 2)` int `(row, col)`.
        model: the VIN; corner_cutting: whether a diagonal move may pass between obstacles.
        chunk_size: ignored (same signature as `engine.plan_batch`).
    """
    obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
    limits = step_limits(obstacles, starts, goals, corner_cutting)
    model.eval()
    paths, terms = [], []
    for b in range(len(obstacles)):
        x = make_input(obstacles[b : b + 1], goals[b : b + 1])
        path, term = rollout(
            torch_action_at(model, x), obstacles[b], starts[b], goals[b], int(limits[b]), corner_cutting
        )
        paths.append(np.array(path, dtype=np.int16).reshape(-1, 2))
        terms.append(term)
    return PlanResult.from_paths(paths, np.array(terms, dtype=np.int8))
