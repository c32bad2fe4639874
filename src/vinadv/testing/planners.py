"""Synthetic VIN weights for tests and benchmarks, so planning can be checked before (or without) trained weights.

`planning_vin` hand-sets a VIN that does plan (reward -penalty on obstacles and +1 per goal-image unit, q channel a =
reward + gamma * value of the a-th neighbour, fc = identity on the first 8 channels) and adds random noise to every
weight, so paths are long and varied (goal, collision, loop and step-limit endings all occur) and logits have no
structure a hand-written engine could exploit by accident. `exact_vin` sets a VIN to exact value iteration on
DESIGN.md's move costs, with no noise: the architecture's best case, which plans optimal paths.
"""

from __future__ import annotations

import numpy as np
import torch

from vinadv.grid.actions import ACTION_COSTS, ACTION_DELTAS
from vinadv.planners.vin.arrays import GOAL_VALUE, VINConfig, default_k
from vinadv.planners.vin.model import VIN, init_shift_kernels


def planning_vin(
    size: int = 28, seed: int = 0, noise: float = 0.3, gamma: float = 0.9, penalty: float = 4.0, k: int | None = None
) -> VIN:
    """A VIN that plans, with relative random noise `noise` on all weights (`torch.manual_seed(seed)`)."""
    torch.manual_seed(seed)
    model = VIN(VINConfig(k=default_k(size) if k is None else k))
    with torch.no_grad():
        for p in model.parameters():
            p.mul_(noise)
        model.h.weight[0, 0, 1, 1] += 1.0  # obstacle channel
        model.h.weight[1, 1, 1, 1] += 1.0  # goal channel (10 at the goal)
        model.r.weight[0, 0] += -penalty
        model.r.weight[0, 1] += 1.0
        for a, (dr, dc) in enumerate(ACTION_DELTAS):
            model.q.weight[a, 0, 1, 1] += 1.0
            model.w[a, 0, 1 + dr, 1 + dc] += gamma
            model.fc.weight[a, a] += 1.0
    return model


def random_vin(size: int = 28, seed: int = 0, k: int | None = None) -> VIN:
    """PyTorch's default initialisation (`torch.manual_seed(seed)`): short paths, mostly collisions."""
    torch.manual_seed(seed)
    return VIN(VINConfig(k=default_k(size) if k is None else k))


def exact_vin(size: int = 28, k: int | None = None, obstacle_cost: float = 1e7, tie_cost: float = 1e-4) -> VIN:
    """A VIN whose weights are exact value iteration on DESIGN.md's moves and costs (corner cutting allowed).

    Reward `r` = -1 on free cells, -`obstacle_cost` on obstacles, 0 at the goal; q channel a (a < 8) = `cost_a * r`
    at the cell + `tie_cost * r` at its a-th neighbour + the neighbour's value, so q_a = -cost_a - tie_cost + v(next)
    into a free cell and about -`obstacle_cost * tie_cost` into an obstacle; channels 8 and 9 stay put (free at the
    goal, -1000 elsewhere), which keeps the goal's value at 0. After k steps `v` = -(optimal cost to the goal) -
    `tie_cost` * (moves - 1) on every cell whose optimal cost is below k (the first value estimate is about -1 on every
    free cell, so a walk of k moves that never meets the goal scores about -(k + 1): cells further than that are not
    resolved), and fc = identity on the first 8 channels: the greedy rollout follows an optimal path (`tie_cost` only
    orders paths of equal cost by their moves; it is below every cost difference of paths under 40 moves). Shows that
    the VIN can represent an optimal planner, so what a trained VIN lacks is training, not capacity.
    """
    model = VIN(VINConfig(k=default_k(size) if k is None else k))
    with torch.no_grad():
        for p in model.parameters():
            p.zero_()
        init_shift_kernels(model)
        model.h.weight[0, 0, 1, 1] = 1.0  # h0: obstacle image
        model.h.weight[1, 1, 1, 1] = 1.0  # h1: goal image (GOAL_VALUE at the goal)
        model.h.bias[2] = 1.0  # h2: 1 everywhere
        model.r.weight[0, :3, 0, 0] = torch.tensor([1.0 - obstacle_cost, 1.0 / GOAL_VALUE, -1.0])
        for a, (dr, dc) in enumerate(ACTION_DELTAS):
            model.q.weight[a, 0, 1, 1] = float(ACTION_COSTS[a])
            model.q.weight[a, 0, 1 + dr, 1 + dc] = tie_cost
        model.q.weight[8:, 0, 1, 1] = 1000.0
    return model


def tie_flips(reference, other, rel_tol: float = 1e-4) -> dict:
    """Where two logits arrays `(B, 8, N, N)` of one planner on the same maps (say the CPU's and a GPU's) choose
    another action (argmax, lowest index on ties), and whether each such cell is a near tie of `reference`: its logits
    of the two actions closer than `rel_tol` times the largest |logit| of that map, so a difference of float sums may
    flip it.

    Returns `{"cells": flipped cells, "not_ties": flipped cells that are not near ties, "maps": (B,) bool, the maps
    with a flip}`. A planner whose two devices differ only at near ties has `not_ties == 0`; a path can differ only
    on a map with a flip."""
    reference, other = np.asarray(reference, np.float64), np.asarray(other, np.float64)
    mine, theirs = reference.argmax(axis=1), other.argmax(axis=1)  # (B, N, N)
    flipped = mine != theirs
    # how much better `reference` finds its own choice than the other's
    both = np.take_along_axis(reference, np.stack([mine, theirs], axis=1), axis=1)  # (B, 2, N, N)
    gap = both[:, 0] - both[:, 1]
    finite = np.where(np.isfinite(reference), np.abs(reference), 0.0)
    scale = np.maximum(finite.max(axis=(1, 2, 3)), 1e-30)[:, None, None]
    tie = gap <= rel_tol * scale
    return {
        "cells": int(flipped.sum()),
        "not_ties": int((flipped & ~tie).sum()),
        "maps": flipped.any(axis=(1, 2)),
    }
