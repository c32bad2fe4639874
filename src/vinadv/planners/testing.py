"""Synthetic VIN weights for tests and benchmarks, so planning can be checked before (or without) trained weights.

`planning_vin` hand-sets a VIN that does plan (reward -penalty on obstacles and +1 per goal-image unit, q channel a =
reward + gamma * value of the a-th neighbour, fc = identity on the first 8 channels) and adds random noise to every
weight, so paths are long and varied (goal, collision, loop and step-limit endings all occur) and logits have no
structure a hand-written engine could exploit by accident.
"""

from __future__ import annotations

import torch

from vinadv.grid.actions import ACTION_DELTAS
from vinadv.planners.vin import VIN, VINConfig, default_k


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
