"""The Value Iteration Network of Tamar et al. (2016), in the layout of the common PyTorch ports.

State-dict keys are exactly `h.weight h.bias r.weight q.weight w fc.weight`, so weights move between vinadv and
those ports. Input channels: `[obstacles (1/0), goal image (10 at the goal, 0 elsewhere)]`.

The value map does not depend on the agent's cell, so `action_logits` returns the logits of every cell at once;
`forward(x, rows, cols)` picks the cells of a batch of states, as the ports do.

`init_shift_kernels` starts a VIN's value iteration as moves to the neighbours (`vinadv vin train --vi-init shift`):
trained from there, the VIN learns the shortest-path recursion itself (docs/results/history.md, "Adversarial training").
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from vinadv.errors import InputError
from vinadv.grid.actions import ACTION_DELTAS
from vinadv.planners.padding import pad_actions
from vinadv.planners.vin.arrays import GOAL_VALUE, VINConfig, input_array

__all__ = ["VI_INITS", "VIN", "VINPolicy", "init_shift_kernels", "make_input"]

#: how a fresh VIN's value-iteration kernels start (`TrainConfig.vi_init`): PyTorch's default (the paper's VIN), or
#: `init_shift_kernels`
VI_INITS = ("default", "shift")


class VIN(nn.Module):
    def __init__(self, config: VINConfig | None = None):
        super().__init__()
        config = VINConfig() if config is None else config
        self.config = config
        self.h = nn.Conv2d(config.l_i, config.l_h, 3, padding=1, bias=True)
        self.r = nn.Conv2d(config.l_h, 1, 1, bias=False)
        self.q = nn.Conv2d(1, config.l_q, 3, padding=1, bias=False)
        self.w = nn.Parameter(torch.zeros(config.l_q, 1, 3, 3))
        self.fc = nn.Linear(config.l_q, config.n_actions, bias=False)

    def q_values(self, x: torch.Tensor) -> torch.Tensor:
        """Q map after k value-iteration steps: `x (B, 2, N, N) -> (B, l_q, N, N)`."""
        r = self.r(self.h(x))
        # The ports convolve cat([r, v]) with cat([q.weight, w]) at every step; the reward part of that sum does
        # not change between steps, so it is computed once and only the 1-channel value map is convolved (same
        # function, about a third less work per step).
        q_r = self.q(r)
        q = q_r
        v = q.max(dim=1, keepdim=True).values
        for _ in range(self.config.k):
            q = q_r + F.conv2d(v, self.w, padding=1)
            v = q.max(dim=1, keepdim=True).values
        return q

    def action_logits(self, x: torch.Tensor) -> torch.Tensor:
        """Action logits of every cell: `x (B, 2, N, N) -> (B, N, N, n_actions)`."""
        return self.fc(self.q_values(x).permute(0, 2, 3, 1))

    def forward(self, x: torch.Tensor, rows: torch.Tensor, cols: torch.Tensor) -> torch.Tensor:
        """Logits at one cell per map, as the ports do: `(B, 2, N, N), (B,), (B,) -> (B, n_actions)`."""
        q = self.q_values(x)
        picked = q[torch.arange(len(q), device=q.device), :, rows, cols]
        return self.fc(picked)


def init_shift_kernels(model: VIN) -> VIN:
    """Set `model`'s value-iteration kernels to moves (in place, returned): q channel a < 8 adds the value of the
    cell's a-th neighbour (DESIGN.md action order) and channels 8 and up the cell's own value (`w`), and `fc` reads
    channel a as action a. `h`, `r` and `q` keep their initialisation: the rewards and move costs are learned.

    With the default initialisation the VIN has to find this structure itself and settles for an approximation of it
    (`vin28.pt`: 96.8% action accuracy, 87% optimal paths); started here it learns the recursion in a few epochs.
    """
    n_actions = len(ACTION_DELTAS)
    if model.config.n_actions != n_actions or model.config.l_q < n_actions:
        raise InputError(f"vi_init 'shift' needs n_actions = {n_actions} and l_q >= {n_actions}, got {model.config}")
    with torch.no_grad():
        model.w.zero_()
        model.fc.weight.zero_()
        for a, (dr, dc) in enumerate(ACTION_DELTAS):
            model.w[a, 0, 1 + dr, 1 + dc] = 1.0
            model.fc.weight[a, a] = 1.0
        model.w[n_actions:, 0, 1, 1] = 1.0
    return model


class VINPolicy(nn.Module):
    """A `VIN` behind the bring-your-own contract: `forward(obstacles (B,N,N) float, goals (B,2) int64)` ->
    `(B, 8, N, N)` logits (`VIN.action_logits` with the channels first; a 4-action VIN's padded with -inf)."""

    def __init__(self, vin: VIN):
        super().__init__()
        self.vin = vin

    def forward(self, obstacles: torch.Tensor, goals: torch.Tensor) -> torch.Tensor:
        b = obstacles.shape[0]
        goal_image = torch.zeros_like(obstacles)
        goal_image[torch.arange(b, device=goals.device), goals[:, 0], goals[:, 1]] = GOAL_VALUE
        x = torch.stack([obstacles, goal_image], dim=1)
        # a `news` VIN's 4 actions padded to the contract's 8 with -inf (`vinadv.planners.padding`)
        return pad_actions(self.vin.action_logits(x).permute(0, 3, 1, 2))


def make_input(obstacles: np.ndarray, goals: np.ndarray) -> torch.Tensor:
    """VIN input `(B, 2, N, N)` float32 tensor from obstacles `(B, N, N)` bool and goals `(B, 2)` (`input_array`)."""
    return torch.from_numpy(input_array(obstacles, goals))
