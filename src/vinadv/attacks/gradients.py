"""The gradients of the white-box strategy (`saliency`, `vinadv.attacks.strategies`): the obstacle gradient of a
policy planner's confidence in its own path (`policy_saliency`), or of a search planner's differentiable path map
summed over its path (`path_saliency`). Each is a candidate score per cell, `(B, N, N)`, highest first. PyTorch is
imported only when a gradient is taken: the other strategies run without it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from vinadv.planners.device import full_precision
from vinadv.planners.interface import PlannerError
from vinadv.vocabulary import REMOVE

if TYPE_CHECKING:
    from vinadv.attacks.strategies import AttackContext

#: maps per torch forward and backward of the white-box strategy
TORCH_CHUNK = 128


def policy_saliency(ctx: AttackContext, module) -> np.ndarray:
    """The gradient, with respect to the obstacles, of the log-probability of the planner's chosen actions along its
    path on each map (every path cell but the goal), `module(obstacles (B,N,N) float, goals (B,2)) -> logits
    (B,8,N,N)`; signed so that the highest score lowers that confidence the most for the edit (adding: the most
    negative gradient; removing: the most positive). `TORCH_CHUNK` maps per forward and backward."""
    import torch  # noqa: PLC0415 (here only: the other strategies run without PyTorch)

    device = getattr(ctx.planner, "device", torch.device("cpu"))
    module.eval()
    b = len(ctx.obstacles)
    owner_all = ctx.plans.paths.owners()
    cells_all = ctx.plans.paths.cells.astype(np.int64)
    # the decisions along the path: every path cell but the goal
    at_goal = np.all(cells_all == ctx.goals[owner_all], axis=1)
    out = np.empty(ctx.obstacles.shape)
    with full_precision(device):  # a GPU's gradients in float32, as the CPU's (no TF32)
        for lo in range(0, b, TORCH_CHUNK):
            hi = min(b, lo + TORCH_CHUNK)
            sel = (owner_all >= lo) & (owner_all < hi) & ~at_goal
            x = torch.from_numpy(ctx.obstacles[lo:hi].astype(np.float32)).to(device).requires_grad_(True)
            logits = module(x, torch.from_numpy(ctx.goals[lo:hi]).to(device))  # (b, 8, N, N)
            owner = torch.from_numpy(owner_all[sel] - lo).to(device)
            rows = torch.from_numpy(cells_all[sel, 0]).to(device)
            cols = torch.from_numpy(cells_all[sel, 1]).to(device)
            picked = torch.log_softmax(logits[owner, :, rows, cols], dim=-1)
            chosen = picked.detach().argmax(dim=-1)
            objective = picked.gather(1, chosen[:, None]).sum()
            (grad,) = torch.autograd.grad(objective, x)
            # adding raises a cell's input (0 -> 1): the most negative gradient first; removing lowers it (1 -> 0)
            out[lo:hi] = grad.cpu().numpy() if ctx.edit == REMOVE else -grad.cpu().numpy()
    return out


def path_saliency(ctx: AttackContext, module) -> np.ndarray:
    """Minus the gradient, with respect to the obstacles, of a search planner's differentiable path map
    `module(obstacles (B,N,N) float, starts (B,2), goals (B,2)) -> (B,N,N)` summed over the cells of its path on each
    searched map, `TORCH_CHUNK` maps per forward and backward."""
    import torch  # noqa: PLC0415 (here only: the other strategies run without PyTorch)

    device = getattr(ctx.planner, "device", torch.device("cpu"))
    if hasattr(module, "eval"):
        module.eval()
    on_path = ctx.path_mask()
    out = np.empty(ctx.obstacles.shape)
    for lo in range(0, len(ctx.obstacles), TORCH_CHUNK):
        hi = min(len(ctx.obstacles), lo + TORCH_CHUNK)
        x = torch.from_numpy(ctx.obstacles[lo:hi].astype(np.float32)).to(device).requires_grad_(True)
        starts = torch.from_numpy(ctx.starts[lo:hi]).to(device)
        goals = torch.from_numpy(ctx.goals[lo:hi]).to(device)
        path_map = module(x, starts, goals)
        if tuple(path_map.shape) != tuple(x.shape):
            raise PlannerError(
                f"planner {ctx.planner.name!r}: its differentiable path map has shape {tuple(path_map.shape)}, "
                f"expected {tuple(x.shape)}"
            )
        objective = (path_map * torch.from_numpy(on_path[lo:hi]).to(device, path_map.dtype)).sum()
        (grad,) = torch.autograd.grad(objective, x)
        out[lo:hi] = -grad.detach().cpu().double().numpy()
    return out
