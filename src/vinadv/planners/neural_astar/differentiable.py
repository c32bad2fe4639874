"""The differentiable A* of Neural A* (Yonetani et al. 2021), batched, in PyTorch.

Written from the paper and the authors' `differentiable_astar.py`; the same arithmetic, in float32, so the forward
pass gives the same search as theirs. For B maps with guidance cost maps `c` (B, N, N), the search keeps an open map
O, a closed map (the history) H, costs-so-far g and parents, and repeats, at most `int(tmax * N * N)` times:

    h = heuristic + c,   heuristic = chebyshev(v, goal) + tb_factor * euclid(v, goal)   (float32)
    f = g_ratio * g + (1 - g_ratio) * h
    y = E / sum(E),      E = exp(-f / sqrt(N)) * O                        (a softmax over the open cells)
    v* = the first index (row-major) of the largest y;  s = onehot(v*) + y - detach(y)   (straight-through)
    H += s;  O[v*] = 0 unless v* is the goal (then the search of that map ends)
    for each of the 8 neighbours u of v* that is free (the 3x3 neighbour filter times the free map):
        g2 = g[v*] + c[v*]
        open u, with g[u] = g2 and parent[u] = v*, if u is neither open nor closed, or open with g[u] > g2
    path map = the goal and its chain of parents (the authors' backtrack)

The straight-through selection s is exactly the one-hot map in value and carries the softmax's gradient, so H is
the search history in value and differentiable with respect to the cost maps (hence the encoder and its input map);
g, O and the parents are detached, as in the authors' code.

Where the authors' batched loop goes on until every map is solved, re-selecting the goal of the solved ones (which
changes nothing: the goal then has the smallest f among the open cells, and its neighbours are not re-opened), this
module stops each map at its goal; and a map whose open list empties (the goal cannot be reached: the authors' code
divides 0 by 0 there) stops unsolved with a path map holding the goal alone, as a search that ran out of Tmax
before opening the goal does. Where the largest open exp(-f / sqrt(N)) is subnormal or 0 in float32 (f / sqrt(N)
above about 87: long searches on large maps), float32 can no longer tell those cells apart (and where all are 0 the
authors' selection is 0/0); this module then selects, among the open cells of that largest value, the one of the
smallest f (the first on ties), as the exact mode (`vinadv.planners.classical.astar`) does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from vinadv.grid.actions import ACTION_DELTAS
from vinadv.planners.batching import over_maps, torch_threads
from vinadv.planners.classical.astar import FLOAT32_TINY, TIE_BREAK
from vinadv.planners.neural_astar.model import NeuralAstar
from vinadv.planners.result import GOAL, STEP_LIMIT, PlanResult
from vinadv.planners.search import SearchResult

#: the smallest normal float32: below it exp(-f / sqrt(N)) is subnormal (`vinadv.planners.classical.astar.FLOAT32_TINY`)
TINY = float(FLOAT32_TINY)
__all__ = ["DifferentiableSearch", "NeuralAstarPaths", "authors_heuristic", "differentiable_astar", "search_results"]


def authors_heuristic(goals: torch.Tensor, n: int, tb_factor: float = TIE_BREAK) -> torch.Tensor:
    """`(B, N, N)` float32: Chebyshev distance to the goal plus `tb_factor` times the Euclidean distance, computed in
    float32 in the authors' order (`(|dr| + |dc|) - min(|dr|, |dc|)`, `sqrt(dr^2 + dc^2)`)."""
    idx = torch.arange(n, dtype=torch.float32, device=goals.device)
    dr = (idx[None, :, None] - goals[:, 0, None, None].to(torch.float32)).abs().expand(-1, n, n)
    dc = (idx[None, None, :] - goals[:, 1, None, None].to(torch.float32)).abs().expand(-1, n, n)
    cheb = (dr + dc) - torch.minimum(dr, dc)
    euclid = torch.sqrt(dr * dr + dc * dc)
    return cheb + tb_factor * euclid


@dataclass
class DifferentiableSearch:
    """What the differentiable search found for B maps.

    Attributes:
        histories: `(B, N, N)` float, the closed cells (goal included when reached), 1/0 in value, differentiable.
        path_maps: `(B, N, N)` float 1/0, the goal and its chain of parents (no gradient).
        parents: `(B, N * N)` int64, each cell's parent index (the goal's index where none was set).
        reached: `(B,)` bool, the goal was selected.
        iterations: selections made by the batch's loop.
    """

    histories: torch.Tensor
    path_maps: torch.Tensor
    parents: torch.Tensor
    reached: torch.Tensor
    iterations: int

    def paths(self, starts: np.ndarray, goals: np.ndarray) -> list[np.ndarray]:
        """The ordered paths `(L, 2)` int64 `(row, col)`, start to goal, of the reached searches (the chain of parents
        from the goal back to the start); for a search that did not reach its goal, the start alone."""
        parents = self.parents.detach().cpu().numpy()
        n = self.histories.shape[-1]
        out = []
        for b, (start, goal) in enumerate(zip(np.asarray(starts), np.asarray(goals), strict=True)):
            s, v = int(start[0]) * n + int(start[1]), int(goal[0]) * n + int(goal[1])
            if not bool(self.reached[b]):
                out.append(np.asarray([start], dtype=np.int64))
                continue
            chain = [v]
            while v != s and len(chain) <= n * n:
                v = int(parents[b, v])
                chain.append(v)
            cells = np.asarray(chain[::-1], dtype=np.int64)
            out.append(np.stack([cells // n, cells % n], axis=1))
        return out


def search_state(starts: torch.Tensor, goals: torch.Tensor, n: int, dtype: torch.dtype) -> tuple:
    """`(goal_idx, state)`: the goals' flat indices `(B,)` and the batched search's starting state on B maps of N x N
    cells, `(open, closed, g, parents, histories, active, reached)`, the start open, every parent the goal's index,
    histories of `dtype` (the gradient's)."""
    b, device, cells = len(starts), starts.device, n * n
    start_idx = starts[:, 0] * n + starts[:, 1]
    goal_idx = goals[:, 0] * n + goals[:, 1]
    open_ = torch.zeros(b, cells, dtype=torch.float32, device=device)
    open_[torch.arange(b, device=device), start_idx] = 1.0
    closed = torch.zeros(b, cells, dtype=torch.bool, device=device)
    g = torch.zeros(b, cells, dtype=torch.float32, device=device)
    parents = goal_idx[:, None].expand(b, cells).clone()
    histories = torch.zeros(b, cells, dtype=dtype, device=device)
    active = torch.ones(b, dtype=torch.bool, device=device)
    reached = torch.zeros(b, dtype=torch.bool, device=device)
    return goal_idx, (open_, closed, g, parents, histories, active, reached)


def smallest_f_where_tiny(
    selected: torch.Tensor, e: torch.Tensor, f: torch.Tensor, is_open: torch.Tensor, active: torch.Tensor
) -> torch.Tensor:
    """`selected`, except on the maps whose largest open exp `e` is subnormal or 0 (below `TINY`): there the open
    cell of that largest value with the smallest f (the first on ties), the exact mode's rule (module doc)."""
    top = e.detach().max(dim=-1, keepdim=True).values
    low = top[:, 0] < TINY
    if not bool((low & active).any()):
        return selected
    tied = is_open & (e.detach() == top)
    lowest = torch.where(tied, f.detach(), torch.full_like(f, math.inf)).argmin(dim=-1)
    return torch.where(low, lowest, selected)


def close_selected(
    selected: torch.Tensor, active: torch.Tensor, closed: torch.Tensor, reached: torch.Tensor, goal_idx: torch.Tensor
) -> torch.Tensor:
    """Closes each active map's selected cell (in place, as `reached` for the maps that selected their goal) and
    returns the maps that go on: active and not at their goal."""
    rows = torch.arange(len(selected), device=selected.device)
    at_goal = active & (selected == goal_idx)
    closed[rows[active], selected[active]] = True
    reached |= at_goal
    return active & ~at_goal


def relax(open_, closed, g, parents, ex, sel, nb, legal, g2) -> None:
    """Expands the selected cells `sel` of the maps `ex` in place: each leaves the open set, and each of its
    neighbours `nb` `(k, 8)` where `legal` opens with cost `g2` and parent `sel` if it is neither open nor closed,
    or is open at a higher cost."""
    open_[ex, sel] = 0.0
    exb = ex[:, None].expand_as(nb)
    nb_open = open_[exb, nb] > 0
    update = legal & ((~nb_open & ~closed[exb, nb]) | (nb_open & (g[exb, nb] > g2)))
    ub, un = exb[update], nb[update]
    g[ub, un] = g2.expand_as(nb)[update]
    open_[ub, un] = 1.0
    parents[ub, un] = sel[:, None].expand_as(nb)[update]


def traced_search(
    parents: torch.Tensor, histories: torch.Tensor, reached: torch.Tensor, goal_idx: torch.Tensor, traced, t: int
) -> DifferentiableSearch:
    """The search's result after its last selection `t`: the path maps hold each goal and, on the maps `traced`
    (row indices), its chain of `t` parents (the authors' backtrack)."""
    b, cells = parents.shape
    n = math.isqrt(cells)
    path = torch.zeros(b, cells, dtype=torch.float32, device=parents.device)
    path[torch.arange(b, device=parents.device), goal_idx] = 1.0
    loc = parents[traced, goal_idx[traced]]
    for _ in range(t):
        path[traced, loc] = 1.0
        loc = parents[traced, loc]
    return DifferentiableSearch(
        histories=histories.reshape(b, n, n),
        path_maps=path.reshape(b, n, n),
        parents=parents,
        reached=reached,
        iterations=t + 1,
    )


def search_results(
    search, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, device: torch.device, batch_size: int
) -> SearchResult:
    """A differentiable search's answers as a `SearchResult`, without gradients: `search(obstacles (b, N, N) float
    1/0, starts, goals) -> DifferentiableSearch` (a module's `search`) on checked inputs, `batch_size` maps at a time
    on `device`; the paths are the chains of parents, `[start]` with termination `step_limit` where the goal was not
    reached. On the CPU the maps are split between threads of one torch thread each: the search's many small steps
    gain nothing from PyTorch's own threads and lose much to their synchronisation on a busy machine."""
    parts: dict[int, SearchResult] = {}

    def run(lo: int, hi: int) -> None:
        with torch.no_grad():
            for i in range(lo, hi, batch_size):
                sl = slice(i, min(hi, i + batch_size))
                out = search(
                    torch.from_numpy(obstacles[sl].astype(np.float32)).to(device),
                    torch.from_numpy(starts[sl]).to(device),
                    torch.from_numpy(goals[sl]).to(device),
                )
                reached = out.reached.cpu().numpy()
                plan = PlanResult.from_paths(out.paths(starts[sl], goals[sl]), np.where(reached, GOAL, STEP_LIMIT))
                expanded = out.histories.detach().cpu().numpy() > 0.5
                parts[i] = SearchResult(paths=plan.paths, termination=plan.termination, expanded=expanded)

    if device.type != "cpu":
        run(0, len(obstacles))
    else:
        with torch_threads(1):
            over_maps(len(obstacles), run)
    return SearchResult.concat([parts[i] for i in sorted(parts)])


def differentiable_astar(
    cost_maps: torch.Tensor,
    free: torch.Tensor,
    starts: torch.Tensor,
    goals: torch.Tensor,
    g_ratio: float = 0.5,
    tmax: float = 1.0,
    solved_gradients: bool = False,
) -> DifferentiableSearch:
    """The authors' differentiable A* on B maps (module docstring).

    Args:
        cost_maps: `(B, N, N)` float32 guidance costs (the encoder's; 1 on free cells gives vanilla A*).
        free: `(B, N, N)` float 1 on free cells, 0 on obstacles (the authors' map design / obstacle map).
        starts, goals: `(B, 2)` int64 `(row, col)`.
        g_ratio: f = g_ratio * g + (1 - g_ratio) * h.
        tmax: the share of the N * N cells the search may select (the authors' Tmax: 0.25 in training, 1 to plan).
        solved_gradients: training as the authors' batched loop trains (`vinadv neural-astar train`): a map whose
            search reached its goal goes on adding the softmax's straight-through term `y - detach(y)` (0 in value)
            to its history, off its goal cell (their history is clamped to [0, 1]: the re-selected goal's sum is 2,
            where the clamp passes no gradient), until every map of the batch is solved or Tmax. Values are the same
            either way; only the gradient with respect to the cost maps differs.
    """
    b, n = cost_maps.shape[0], cost_maps.shape[-1]
    device = cost_maps.device
    cells = n * n
    rows = torch.arange(b, device=device)
    cost = cost_maps.reshape(b, cells)
    h = authors_heuristic(goals, n).reshape(b, cells) + cost
    free_flat = free.detach().reshape(b, cells) > 0.5
    goal_idx, (open_, closed, g, parents, histories, active, reached) = search_state(starts, goals, n, cost.dtype)
    deltas = torch.as_tensor(ACTION_DELTAS, device=device)  # the 8 Moore neighbours
    temperature = math.sqrt(n)
    steps = int(tmax * n * n)
    t = 0
    for t in range(steps):  # noqa: B007 (the last t backtracks, as the authors' code)
        f = g_ratio * g + (1 - g_ratio) * h
        e = torch.exp(-1 * f / temperature) * open_.clone()  # a copy: autograd keeps it, open_ changes in place
        total = e.sum(dim=-1, keepdim=True)
        is_open = open_ > 0
        empty = active & ~is_open.any(dim=-1)  # nothing left to open: the goal cannot be reached
        if bool(empty.any()):
            active = active & ~empty
            if not bool(active.any()):
                break
        underflow = total[:, 0] == 0
        y = e / torch.where(underflow[:, None], torch.ones_like(total), total)
        selected = y.detach().argmax(dim=-1)  # the first index of the largest share
        selected = smallest_f_where_tiny(selected, e, f, is_open, active)
        hard = torch.zeros_like(y)
        hard[rows, selected] = 1.0
        histories = histories + (hard + (y - y.detach())) * active[:, None]
        if solved_gradients and bool(reached.any()):
            done = reached[:, None] & (torch.arange(cells, device=device)[None, :] != goal_idx[:, None])
            histories = histories + (y - y.detach()) * done
        active = close_selected(selected, active, closed, reached, goal_idx)
        if not bool(active.any()):
            break
        ex = rows[active]
        sel = selected[active]
        r, c = sel // n, sel % n
        nr, nc = r[:, None] + deltas[None, :, 0], c[:, None] + deltas[None, :, 1]
        inside = (nr >= 0) & (nr < n) & (nc >= 0) & (nc < n)
        nb = nr.clamp(0, n - 1) * n + nc.clamp(0, n - 1)
        g2 = (g[ex, sel] + cost.detach()[ex, sel])[:, None]
        relax(open_, closed, g, parents, ex, sel, nb, inside & free_flat[ex[:, None], nb], g2)
    return traced_search(parents, histories, reached, goal_idx, rows, t)


class NeuralAstarPaths(nn.Module):
    """The saliency attack's module: `forward(obstacles (B, N, N) float 1/0, starts (B, 2), goals (B, 2)) -> (B, N, N)`
    path map, 1 on the goal and its chain of parents, 0 elsewhere in value.

    Its gradient is the search history's on the path's cells: `path + (H - detach(H)) * path`, where H is the
    straight-through history of the differentiable search, differentiable through the guidance cost map with respect
    to the encoder's input map (1 - obstacles). The authors' path map itself is built from detached parents and has no
    gradient; every cell of a reached path was selected once, so its history is the selection's softmax share, the
    straight-through signal of that cell. Obstacles also gate which cells open; that part is not differentiable.
    """

    def __init__(self, model: NeuralAstar, tmax: float = 1.0):
        super().__init__()
        self.model = model
        self.tmax = tmax

    def search(self, obstacles: torch.Tensor, starts: torch.Tensor, goals: torch.Tensor) -> DifferentiableSearch:
        """The differentiable search with the model's guidance cost maps."""
        cost = self.model(obstacles, starts, goals)
        cfg = self.model.config
        return differentiable_astar(cost, 1.0 - obstacles, starts, goals, cfg.g_ratio, self.tmax)

    def forward(self, obstacles: torch.Tensor, starts: torch.Tensor, goals: torch.Tensor) -> torch.Tensor:
        out = self.search(obstacles, starts, goals)
        path = out.path_maps
        return path + (out.histories - out.histories.detach()) * path
