"""TransPath's search (their `modules/planners.py`, `DifferentiableDiagAstar`) in PyTorch, batched: the
differentiable mode, for gradients.

The same search as the compiled replica (`vinadv.planners.transpath.search`), written as the authors' code computes
it, for B maps with the network's values `v` (B, N, N) (correction factors `k` for `cf`, focal values for `f`):

    octile = min(dr, dc) * sqrt 2 + |dr - dc|                                    (float32, their order)
    cf:  h = octile / where(k > 0.1, k, 0.1);  f = 0.5 g + (1 - 0.5 + 0.001) h;  E = exp(-f / sqrt N) * O
    f:   f = 0.5 g + 0.5 octile;  E = exp(v) * [O and f <= min over O of f * f_w]
    y = E / sum(E);  v* = the first index (row-major) of the largest y;  s = onehot(v*) + y - detach(y)
    H += s;  O[v*] = 0 unless v* is the goal (then the search of that map ends)
    for each of the 8 neighbours u of v* that is free (and, without corner cutting, whose diagonal has both cells
    beside it free):  g2 = g[v*] + (1 or float32 sqrt 2);
        open u with g[u] = g2 and parent[u] = v*, if u is neither open nor closed, or open with g[u] > g2

The straight-through selection s is the one-hot map in value and carries the softmax's gradient, so the history H
is differentiable with respect to the network's values (hence its input map); g, O and the parents are detached, as
in the authors' code and in Neural A*'s (`vinadv.planners.neural_astar.differentiable`, whose result type this
module returns).

Each map stops at its goal, when no cell is open (the authors' code divides 0 by 0 there), or after N * N
selections. The two modes select the same cells except where two open cells' values are equal in one computation
and not the other: PyTorch's vectorised float32 `exp(-f / 8)` here against the correctly rounded one of the compiled
replica, and the division by the sum before the argmax here (it can merge two values one unit apart). Where every
open `exp(-f / sqrt N)` is subnormal or 0 (`cf`, f above about 700), this module selects among the open cells of
that largest value the one of the smallest f (the first on ties), as the compiled replica and `astar` do.
"""

from __future__ import annotations

import math

import numpy as np
import torch
from torch import nn

from vinadv.grid.actions import ACTION_DELTAS
from vinadv.planners.neural_astar.differentiable import (
    DifferentiableSearch,
    close_selected,
    relax,
    search_state,
    smallest_f_where_tiny,
    traced_search,
)
from vinadv.planners.transpath.model import TransPath
from vinadv.planners.transpath.search import F_W

__all__ = ["TransPathPaths", "octile_torch", "search_arrays", "transpath_differentiable_search"]

#: the diagonal move's cost as the authors' cost filter holds it (a float32 tensor of sqrt 2)
DIAGONAL = float(torch.tensor(2**0.5, dtype=torch.float32))
_DELTAS = torch.as_tensor(ACTION_DELTAS)
_MOVE_COSTS = torch.tensor([DIAGONAL if dr and dc else 1.0 for dr, dc in ACTION_DELTAS.tolist()], dtype=torch.float32)


def octile_torch(goals: torch.Tensor, n: int) -> torch.Tensor:
    """`(B, N, N)` float32 octile distance to each goal in the authors' float32 order: `min(dr, dc) * 2**0.5 + |dr -
    dc|`."""
    idx = torch.arange(n, dtype=torch.float32, device=goals.device)
    dr = (idx[None, :, None] - goals[:, 0, None, None].to(torch.float32)).abs().expand(-1, n, n)
    dc = (idx[None, None, :] - goals[:, 1, None, None].to(torch.float32)).abs().expand(-1, n, n)
    return torch.minimum(dr, dc) * (2**0.5) + (dr - dc).abs()


def _selection(focal_exp, h, g, open_, mode: str, f_w: float, n: int):
    """`(y, e, f)`: the selection's shares `y = E / sum(E)` (module doc), the unnormalised `E` and the f of every cell
    (`(B, N*N)` each); a row whose E sums to 0 keeps E as its y. `focal_exp`: `exp(focal values)` (mode `f`)."""
    if mode == "cf":
        f = 0.5 * g + (1 - 0.5 + 0.001) * h
        e = torch.exp(-1 * f / math.sqrt(n)) * open_
    else:
        f = 0.5 * g + (1 - 0.5) * h
        lowest = torch.where(open_ > 0, f, torch.full_like(f, math.inf)).min(dim=-1, keepdim=True).values
        e = focal_exp * ((f <= lowest * f_w) & (open_ > 0))
    total = e.sum(dim=-1, keepdim=True)
    return e / torch.where(total == 0, torch.ones_like(total), total), e, f


def _neighbours(free: torch.Tensor, sel: torch.Tensor, n: int, corner_cutting: bool):
    """`(nb, legal, cost)` `(b, 8)` each: the cell indices one move from the selected cells `sel` (clamped into the
    grid), whether the move is legal on the `(b, N*N)` bool free maps (the maps' rule), and the move's cost."""
    deltas = _DELTAS.to(sel.device)
    r, c = sel // n, sel % n
    nr, nc = r[:, None] + deltas[None, :, 0], c[:, None] + deltas[None, :, 1]
    inside = (nr >= 0) & (nr < n) & (nc >= 0) & (nc < n)
    rows = torch.arange(len(sel), device=sel.device)[:, None]

    def free_at(rr, cc):
        return free[rows, rr.clamp(0, n - 1) * n + cc.clamp(0, n - 1)]

    legal = inside & free_at(nr, nc)
    if not corner_cutting:  # a diagonal also needs both cells beside it free
        legal &= free_at(nr, c[:, None].expand_as(nr)) & free_at(r[:, None].expand_as(nc), nc)
    nb = nr.clamp(0, n - 1) * n + nc.clamp(0, n - 1)
    return nb, legal, _MOVE_COSTS.to(sel.device)[None, :].expand_as(nb)


def transpath_differentiable_search(
    values: torch.Tensor,
    free: torch.Tensor,
    starts: torch.Tensor,
    goals: torch.Tensor,
    mode: str,
    corner_cutting: bool = True,
    f_w: float = F_W,
) -> DifferentiableSearch:
    """The authors' search on B maps (module doc), differentiable with respect to `values`.

    Args:
        values: `(B, N, N)` float32, the network's `(output + 1) / 2`: correction factors (`mode` "cf") or focal
            values (`mode` "f").
        free: `(B, N, N)` float 1 on free cells, 0 on obstacles (read detached).
        starts, goals: `(B, 2)` int64 `(row, col)`.
        corner_cutting: the maps' rule (the authors': True).
        f_w: the focal weight (mode "f").
    """
    b, n = values.shape[0], values.shape[-1]
    device = values.device
    cells = n * n
    rows = torch.arange(b, device=device)
    octile = octile_torch(goals, n)
    if mode == "cf":
        thr = torch.tensor(0.1, device=device)
        h = (octile / torch.where(values > thr, values, thr)).reshape(b, cells)
    else:
        h = octile.reshape(b, cells)
    focal_exp = torch.exp(values).reshape(b, cells) if mode == "f" else None
    free_flat = free.detach().reshape(b, cells) > 0.5
    goal_idx, (open_, closed, g, parents, histories, active, reached) = search_state(starts, goals, n, values.dtype)
    t = 0
    for t in range(cells):  # noqa: B007 (the last t bounds the backtrack)
        is_open = open_ > 0
        active = active & is_open.any(dim=-1)  # nothing left to open: the goal cannot be reached
        if not bool(active.any()):
            break
        y, e, f = _selection(focal_exp, h, g, open_.clone(), mode, f_w, n)
        selected = y.detach().argmax(dim=-1)  # the first index of the largest share
        if mode == "cf":  # every open exp subnormal or 0: the compiled replica's rule (module doc)
            selected = smallest_f_where_tiny(selected, e, f, is_open, active)
        hard = torch.zeros_like(y)
        hard[rows, selected] = 1.0
        histories = histories + (hard + (y - y.detach())) * active[:, None]
        active = close_selected(selected, active, closed, reached, goal_idx)
        if not bool(active.any()):
            break
        ex = rows[active]
        sel = selected[active]
        nb, legal, cost = _neighbours(free_flat[ex], sel, n, corner_cutting)
        relax(open_, closed, g, parents, ex, sel, nb, legal, g[ex, sel][:, None] + cost)
    # a search that did not reach its goal: the goal alone, as Neural A*'s
    return traced_search(parents, histories, reached, goal_idx, rows[reached], t)


class TransPathPaths(nn.Module):
    """The saliency attack's module: `forward(obstacles (B, 64, 64) float 1/0, starts (B, 2), goals (B, 2)) -> (B, 64,
    64)` path map, 1 on the goal and its chain of parents, 0 elsewhere in value; its gradient is the straight-through
    search history's on the path's cells (`path + (H - detach(H)) * path`, as Neural A*'s `NeuralAstarPaths`),
    through the network's values to its input map. Obstacles also gate which cells open; that part is not
    differentiable. `corner_cutting`: the rule the search keeps (the authors': True)."""

    def __init__(self, model: TransPath, f_w: float = F_W, corner_cutting: bool = True):
        super().__init__()
        self.model = model
        self.f_w = f_w
        self.corner_cutting = corner_cutting

    def search(self, obstacles: torch.Tensor, starts: torch.Tensor, goals: torch.Tensor) -> DifferentiableSearch:
        """The network's values, then the differentiable search on them."""
        values = self.model.outputs(obstacles, starts, goals)
        return transpath_differentiable_search(
            values, 1.0 - obstacles, starts, goals, self.model.mode, self.corner_cutting, self.f_w
        )

    def forward(self, obstacles: torch.Tensor, starts: torch.Tensor, goals: torch.Tensor) -> torch.Tensor:
        out = self.search(obstacles, starts, goals)
        path = out.path_maps
        return path + (out.histories - out.histories.detach()) * path


def as_search_arrays(out: DifferentiableSearch, starts: np.ndarray, goals: np.ndarray):
    """`(paths, reached, expanded)` of a differentiable search as NumPy: the ordered paths (`[start]` where not
    reached), `(B,)` bool and the `(B, N, N)` bool selected cells."""
    return out.paths(starts, goals), out.reached.cpu().numpy(), out.histories.detach().cpu().numpy() > 0.5


def search_arrays(
    values: torch.Tensor,
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    mode: str,
    corner_cutting: bool = True,
):
    """`as_search_arrays` of the differentiable search on the network's `values`, without gradients, for NumPy
    `(B, N, N)` bool obstacles, starts and goals: `(paths, reached, expanded)`."""
    with torch.no_grad():
        out = transpath_differentiable_search(
            values,
            torch.from_numpy((~obstacles).astype(np.float32)),
            torch.from_numpy(starts),
            torch.from_numpy(goals),
            mode,
            corner_cutting,
        )
    return as_search_arrays(out, starts, goals)
