"""Logits of a model with fewer than 8 actions (a `news` model: 4) in the planner contract's 8-action layout.

A `news` model's actions are the first 4 of DESIGN.md's order (N, S, E, W; `vinadv.grid.moves`), so its logits go in
channels 0..3 and the diagonal channels 4..7 get -inf: a masked move, which the rollout (its argmax runs over the
maps' actions only) and the attacks read as "never taken", and whose softmax weight and gradient are 0.
"""

from __future__ import annotations

import torch
from torch import nn

from vinadv.grid.actions import N_ACTIONS

__all__ = ["ActionPadding", "pad_actions"]


def pad_actions(logits: torch.Tensor) -> torch.Tensor:
    """`(B, A, N, N)` logits, A <= 8, as `(B, 8, N, N)`: channels A..7 are -inf (the same tensor when A = 8)."""
    missing = N_ACTIONS - logits.shape[1]
    if missing <= 0:
        return logits
    fill = logits.new_full((logits.shape[0], missing, *logits.shape[2:]), float("-inf"))
    return torch.cat([logits, fill], dim=1)


class ActionPadding(nn.Module):
    """`module` (`forward(obstacles, goals) -> (B, A, N, N)`, A <= 8) with its logits padded to 8 by `pad_actions`;
    `inner` keeps the model (its config, its record)."""

    def __init__(self, module: nn.Module):
        super().__init__()
        self.inner = module

    def forward(self, obstacles: torch.Tensor, goals: torch.Tensor) -> torch.Tensor:
        return pad_actions(self.inner(obstacles, goals))
