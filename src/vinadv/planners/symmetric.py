"""A planner averaged over the 8 symmetries of the grid (`+d4` after a planner's name: `gppn+d4`).

The task is symmetric: rotating or flipping a map rotates or flips its shortest paths, and the moves and costs of
DESIGN.md are the same in every direction (with or without corner cutting). A learned planner is not: it sees each
orientation of a map as a different map and errs differently on each. `DihedralAverage` plans the map in all 8
orientations, brings each answer back (the grid transformed back, the actions renamed) and averages the action
log-probabilities:

    logits(x)[a, p] = 1/8 sum_g log_softmax(f(g x))[g a, g p]

so the planner is exactly equivariant (its policy on a rotated map is the rotated policy) and each of its decisions
is an ensemble of 8 looks at the same map with the same weights. It costs 8 forward passes.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from vinadv.grid.dihedral import INVERSE, STEPS, transform_actions, transform_cells, transform_grids


class DihedralAverage(nn.Module):
    """`forward(obstacles (B, N, N) float 0/1, goals (B, 2) int64) -> (B, 8, N, N)`: the mean over the 8 dihedral
    transforms of `module`'s action log-probabilities, each taken on the transformed map and transformed back.

    `module` follows the planner contract (`vinadv.planners.interface.TorchPlanner`); gradients flow through it."""

    def __init__(self, module: nn.Module):
        super().__init__()
        self.module = module
        # perms[g][a]: the action of the transformed map that is action a of the original one
        self.register_buffer("perms", torch.from_numpy(np.stack([transform_actions(g) for g in range(len(STEPS))])))

    def forward(self, obstacles: torch.Tensor, goals: torch.Tensor) -> torch.Tensor:
        n = obstacles.shape[-1]
        cells = goals.detach().cpu().numpy()
        looks = []
        for g in range(len(STEPS)):
            moved_goals = torch.from_numpy(transform_cells(cells, n, g)).to(goals.device)
            logp = torch.log_softmax(self.module(transform_grids(obstacles, g).contiguous(), moved_goals), dim=1)
            looks.append(transform_grids(logp, INVERSE[g], axes=(2, 3))[:, self.perms[g]])
        # Where the map is symmetric, two actions get the same 8 numbers in another order: summed in sorted order
        # they tie exactly, so the rollout's lowest-index rule decides, not the rounding of the sum.
        return torch.stack(looks).sort(dim=0).values.sum(dim=0) / len(STEPS)
