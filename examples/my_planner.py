"""A bring-your-own planner for vinadv:
`vinadv plan --maps maps.npz --out paths.npz --planner examples/my_planner.py:make`.

`make(size)` returns a torch.nn.Module; `forward(obstacles, goals)` gets obstacles as 0/1 floats (B, N, N) and goals
as int64 (B, 2) (row, col), and returns (B, 8, N, N) action logits in the order N, S, E, W, NE, NW, SE, SW.
This one is untrained (a small CNN); load your own weights in `make` with `net.load_state_dict(torch.load(...))`.
"""

import torch
from torch import nn


class TinyPlanner(nn.Module):
    def __init__(self, hidden: int = 16):
        super().__init__()
        self.net = nn.Sequential(nn.Conv2d(2, hidden, 3, padding=1), nn.ReLU(), nn.Conv2d(hidden, 8, 3, padding=1))

    def forward(self, obstacles: torch.Tensor, goals: torch.Tensor) -> torch.Tensor:
        goal_map = torch.zeros_like(obstacles)
        goal_map[torch.arange(len(goals), device=goals.device), goals[:, 0], goals[:, 1]] = 1.0
        return self.net(torch.stack([obstacles, goal_map], dim=1))


def make(size: int) -> nn.Module:
    torch.manual_seed(0)  # the same untrained weights every time
    return TinyPlanner()
