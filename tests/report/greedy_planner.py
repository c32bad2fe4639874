"""A greedy planner whose logits are small integers, so its paths are the same on every CPU: the planner of the
report's byte-identical baseline (`test_report_baseline.py`). `make(size)` follows the bring-your-own contract
(`examples/my_planner.py`).

Each move's logit is minus the octile distance (x2, integers) from the cell it leads to to the goal, minus 1,000 when
that cell is an obstacle or off the map: the planner walks straight at the goal and gets stuck behind obstacles, so
an attack finds every category (unreached, forks, detours, unchanged). The run stores this file's SHA-256, so a
change here changes the baseline."""

import torch
from torch import nn

#: (d_row, d_col) of the actions N, S, E, W, NE, NW, SE, SW (`vinadv.grid.actions.ACTION_DELTAS`)
DELTAS = ((-1, 0), (1, 0), (0, 1), (0, -1), (-1, 1), (-1, -1), (1, 1), (1, -1))
BLOCKED = 1000.0


class GreedyPlanner(nn.Module):
    def forward(self, obstacles: torch.Tensor, goals: torch.Tensor) -> torch.Tensor:
        b, n, _ = obstacles.shape
        # a wall of obstacles around the map, so every move's target cell can be read by slicing
        walled = torch.nn.functional.pad(obstacles, (1, 1, 1, 1), value=1.0)
        cells = torch.arange(n, dtype=torch.float32)
        logits = []
        for dr, dc in DELTAS:
            rows = (cells + dr)[None, :, None] - goals[:, 0].float()[:, None, None]
            cols = (cells + dc)[None, None, :] - goals[:, 1].float()[:, None, None]
            big, small = torch.maximum(rows.abs(), cols.abs()), torch.minimum(rows.abs(), cols.abs())
            distance = 2.0 * big + small  # octile distance x2 rounded to integers: (2 * max + min)
            blocked = walled[:, 1 + dr : 1 + dr + n, 1 + dc : 1 + dc + n]
            logits.append(-distance.expand(b, n, n) - BLOCKED * blocked)
        return torch.stack(logits, dim=1)


def make(size: int) -> nn.Module:
    return GreedyPlanner()
