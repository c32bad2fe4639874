"""A planner measured the way each codebase measures it, so figures side by side compare like with like.

`vinadv` and `gppn` take any planner (`vinadv.planners.interface.Planner`, or a VIN); `kentsommer` a VIN (its goal
prior is a VIN input).

- `vinadv` (DESIGN.md): `vinadv.evaluation.planner_metrics.evaluate_vin`: action accuracy against the set of optimal
  actions at every free reachable cell; rollouts from every real start, a collision, a revisited cell or more than
  2L moves (L: moves of an optimal path) end a path unreached.
- `kentsommer` (the port's test.py and train.py): the goal channel is its test-time reward prior, -1 everywhere and
  10 at the goal (`prior`; its training data used 0); from each start, up to 2L + 1 moves (`L = len(path) * 2`
  cells, start included), a move is clamped to the grid and into an obstacle leaves the agent where it is, no loop
  stop;
  success when the agent stands on the goal at the end. Accuracy is single-label: over the states of the expert
  trajectories (goal excluded), the share where the argmax equals the trajectory's own action.
- `gppn` (GPPN's utils/runner.py): every Moore move costs 1 (every NEWS move on `news` maps); from every free
  cell the argmax policy is followed (an illegal move stays put, no step limit); %Suc is the share of free cells
  (goal included) whose policy reaches the goal, %Opt the share whose policy path has as few moves as a shortest
  path (free cells that cannot reach the goal at all count as optimal, as GPPN's code counts them), averaged over
  maps.
Ties between logits go to the lowest vinadv action index in all three. `gppn` and `kentsommer` read a policy at every
cell: a planner that declares none (`Capabilities.policy` False: a search planner, paths only) is refused with one
line; `vinadv` measures its paths (`evaluate_planner`). `kentsommer` reads a VIN's own network (`planner_vin`).
"""

from __future__ import annotations

import numpy as np
import torch

from vinadv.errors import InputError
from vinadv.evaluation.planner_metrics import evaluate_planner, evaluate_vin
from vinadv.grid.actions import ACTION_DELTAS
from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import DEFAULT_MOVES, require_moves
from vinadv.interop.formats.gppn import unit_cost_distances
from vinadv.interop.formats.samples import expert_steps
from vinadv.planners.interface import PlannerError
from vinadv.planners.vin.model import VIN, make_input
from vinadv.planners.vin.planner import as_planner

PROTOCOLS = ("vinadv", "kentsommer", "gppn")
PORT_TEST_PRIOR = -1.0


def argmax_actions(
    model: VIN, obstacles: np.ndarray, goals: np.ndarray, prior: float = 0.0, batch_size: int = 128
) -> np.ndarray:
    """The argmax action of every cell, `(n, N, N)` int64; the goal channel is 10 at the goal, `prior` elsewhere."""
    out = []
    model.eval()
    for i in range(0, len(obstacles), batch_size):
        x = make_input(obstacles[i : i + batch_size], goals[i : i + batch_size])
        if prior != 0.0:
            x[:, 1] = torch.where(x[:, 1] == 0, torch.tensor(float(prior)), x[:, 1])
        with torch.no_grad():
            out.append(np.argmax(model.action_logits(x).numpy(), axis=-1))
    return np.concatenate(out) if out else np.zeros(obstacles.shape, np.int64)


def _moves(obstacles: np.ndarray, actions: np.ndarray, clamp: bool = False) -> np.ndarray:
    """Flat index of the cell each cell's action leads to, staying put where the move is illegal: `(n, N*N)`.

    `clamp`: the port's gridworld first clamps each coordinate to the grid (a diagonal move off one edge slides
    along it), then stays put on an obstacle; without it (GPPN) a move off the grid stays put.
    """
    n, size = obstacles.shape[0], obstacles.shape[1]
    rows, cols = np.divmod(np.arange(size * size), size)
    flat = actions.reshape(n, size * size)
    nr, nc = rows + ACTION_DELTAS[flat, 0], cols + ACTION_DELTAS[flat, 1]
    if clamp:
        nr, nc = np.clip(nr, 0, size - 1), np.clip(nc, 0, size - 1)
    inside = (nr >= 0) & (nr < size) & (nc >= 0) & (nc < size)
    ok = inside & ~obstacles.reshape(n, size * size)[np.arange(n)[:, None], np.where(inside, nr * size + nc, 0)]
    return np.where(ok, nr * size + nc, np.arange(size * size))


def kentsommer_protocol(model: VIN, maps: MapSet, prior: float = PORT_TEST_PRIOR) -> dict:
    """The port's figures on `maps` (module doc): rollout success and single-label accuracy."""
    actions = argmax_actions(model, maps.obstacles, maps.goals, prior)
    map_of_step, states, labels, traj_map = expert_steps(maps)
    hit = actions[map_of_step, states[:, 0], states[:, 1]] == labels
    real = np.flatnonzero(maps.start_mask.reshape(-1))
    size = maps.size
    succ = _moves(maps.obstacles, actions, clamp=True)
    pos = maps.starts.reshape(-1, 2)[real] @ np.array([size, 1])
    goal = maps.goals[traj_map] @ np.array([size, 1])
    limit = 2 * maps.expert.lengths[real] - 1  # the port: L = 2 * cells, moves j = 1 .. L - 1
    for step in range(int(limit.max()) if len(limit) else 0):
        moving = (step < limit) & (pos != goal)
        pos = np.where(moving, succ[traj_map, pos], pos)
    reached = pos == goal
    return {
        "protocol": "kentsommer",
        "prior": float(prior),
        "maps": len(maps),
        "size": size,
        "rollouts": len(real),
        "success_rate": float(reached.mean()) if len(real) else float("nan"),
        "action_accuracy_single_label": float(hit.mean()) if len(hit) else float("nan"),
        "trajectory_states": int(len(hit)),
    }


def planner_actions(planner, obstacles: np.ndarray, goals: np.ndarray, batch_size: int = 256) -> np.ndarray:
    """The argmax action (lowest index on ties) of every cell by `planner` (a `Planner` or a VIN), `(n, N, N)`; a
    planner without a policy at every cell (a search planner) is refused (`require_policy`)."""
    planner = as_planner(planner, obstacles.shape[1])
    require_policy(planner, "the argmax action of every cell")
    out = [
        np.argmax(planner.logits(obstacles[i : i + batch_size], goals[i : i + batch_size]), axis=1)
        for i in range(0, len(obstacles), batch_size)
    ]
    return np.concatenate(out) if out else np.zeros(obstacles.shape, np.int64)


def planner_vin(planner) -> VIN:
    """The PyTorch VIN of `planner` (its `vin`), which the kentsommer protocol runs (its goal prior is a VIN input);
    a planner without one is refused in one line."""
    vin = getattr(planner, "vin", None)
    if vin is None:
        raise PlannerError(
            f"the kentsommer protocol measures a VIN (its goal prior is a VIN input); planner {planner.name!r} has no "
            "VIN network"
        )
    return vin


def require_policy(planner, what: str) -> None:
    """Refuse (`PlannerError`, one line) a planner that declares no policy at every cell (`Capabilities.policy`: a
    search planner) for `what` ("the gppn protocol"), which reads one."""
    if not planner.capabilities.policy:
        raise PlannerError(
            f"{what} follows a policy from every cell: it needs a policy planner (vin, gppn, optimal, "
            f"your own torch module); {planner.name!r} declares no policy (a search planner: measure it with the "
            "vinadv protocol)"
        )


def gppn_protocol(planner, maps: MapSet) -> dict:
    """GPPN's %Opt and %Suc of `planner` (a `Planner` or a VIN) on `maps` (module doc); a search planner is
    refused (`require_policy`)."""
    n, size = len(maps), maps.size
    planner = as_planner(planner, size).for_moves(maps.moves)  # a planner of another movement model is refused
    require_policy(planner, "the gppn protocol")
    actions = planner_actions(planner, maps.obstacles, maps.goals)
    succ = _moves(maps.obstacles, actions)
    goal = maps.goals @ np.array([size, 1])
    rows = np.arange(n)[:, None]
    succ[np.arange(n), goal] = goal  # the goal absorbs, with no move counted
    length = (np.arange(size * size)[None, :] != goal[:, None]).astype(np.int64)
    # pointer doubling: after k rounds succ is the 2^k-th successor and length the moves made on the way
    for _ in range(int(np.ceil(np.log2(size * size))) + 1):
        length = length + length[rows, succ]
        succ = succ[rows, succ]
    reached = succ == goal[:, None]
    free = ~maps.obstacles.reshape(n, size * size)
    # GPPN's shortest paths count moves of cost 1: Moore's 8 moves, or NEWS's 4 on `news` maps
    mechanism = "news" if maps.moves == "news" else "moore"
    opt = unit_cost_distances(maps.obstacles, maps.goals, mechanism).reshape(n, size * size)
    optimal = free & (~np.isfinite(opt) | (reached & (length == opt)))
    open_cells = free.sum(axis=1)
    return {
        "protocol": "gppn",
        "maps": n,
        "size": size,
        "cells": int(open_cells.sum()),
        "percent_optimal": float((optimal.sum(axis=1) / open_cells).mean()) if n else float("nan"),
        "percent_success": float(((free & reached).sum(axis=1) / open_cells).mean()) if n else float("nan"),
    }


def evaluate_protocol(
    model: VIN, maps: MapSet, protocol: str, prior: float | None = None, progress: bool = False
) -> dict:
    """`model`'s figures on `maps` measured by `protocol` ('vinadv', 'kentsommer' or 'gppn')."""
    if protocol not in PROTOCOLS:
        raise InputError(f"protocol must be one of {', '.join(PROTOCOLS)}, got {protocol!r}")
    # GPPN's %Opt and %Suc count moves of cost 1 whatever the maps' costs (NEWS's on news maps), vinadv's follow the
    # maps' model; the port's judges paths by octile costs
    require_moves(
        maps.moves, ("octile",) if protocol == "kentsommer" else ("octile", "moore", "news"), f"the {protocol} protocol"
    )
    if prior is not None and protocol != "kentsommer":
        raise InputError("prior applies to the kentsommer protocol only")
    if protocol == "vinadv":
        if maps.moves != DEFAULT_MOVES:  # the engine plans octile moves: the VIN planner of the VIN's own model
            planner = as_planner(model, maps.size).for_moves(maps.moves)
            return {"protocol": "vinadv", **evaluate_planner(planner, maps, progress=progress)}
        return {"protocol": "vinadv", **evaluate_vin(model, maps, progress=progress)}
    if protocol == "kentsommer":
        return kentsommer_protocol(model, maps, PORT_TEST_PRIOR if prior is None else prior)
    return gppn_protocol(model, maps)
