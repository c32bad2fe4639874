"""The Value Iteration Network of Tamar et al. (2016), in the layout of the common PyTorch ports.

State-dict keys are exactly `h.weight h.bias r.weight q.weight w fc.weight`, so weights move between vinadv and
those ports. Input channels: `[obstacles (1/0), goal image (10 at the goal, 0 elsewhere)]`.

The value map does not depend on the agent's cell, so `action_logits` returns the logits of every cell at once;
`forward(x, rows, cols)` picks the cells of a batch of states, as the ports do.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

GOAL_VALUE = 10.0
#: value-iteration steps k for the map sizes of the VIN paper; other sizes use `default_k`.
K_BY_SIZE = {8: 10, 16: 20, 28: 36}


def default_k(size: int) -> int:
    """k for an N x N map: 10, 20, 36 at 8, 16, 28 (the VIN paper), else about 1.3 N (enough to cross the map)."""
    return K_BY_SIZE.get(size, int(np.ceil(1.3 * size)))


@dataclass(frozen=True)
class VINConfig:
    """Hyper-parameters: k value-iteration steps, l_i input channels, l_h hidden channels, l_q q channels."""

    k: int = 36
    l_i: int = 2
    l_h: int = 150
    l_q: int = 10
    n_actions: int = 8

    def to_dict(self) -> dict:
        return asdict(self)


class VIN(nn.Module):
    def __init__(self, config: VINConfig = VINConfig()):
        super().__init__()
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


def make_input(obstacles: np.ndarray, goals: np.ndarray) -> torch.Tensor:
    """VIN input `(B, 2, N, N)` float32 from obstacles `(B, N, N)` bool and goals `(B, 2)`."""
    obstacles = np.asarray(obstacles, dtype=bool)
    b = len(obstacles)
    x = np.zeros((b, 2) + obstacles.shape[1:], dtype=np.float32)
    x[:, 0] = obstacles
    x[np.arange(b), 1, goals[:, 0], goals[:, 1]] = GOAL_VALUE
    return torch.from_numpy(x)
