"""Plain references for the Neural A* tests, written from the paper's equations, independent of vinadv's code.

- `plain_encoder`: the encoder as functional PyTorch calls on the checkpoint's tensors (conv, batch norm with the
  running statistics, ReLU, sigmoid), the input built here ("m+": the map with 1 on free cells, and the start map plus
  the goal map).
- `literal_search`: the published search, one map at a time, as a literal loop (a Python loop over the 8 neighbours of
  the selected cell), in float32 PyTorch arithmetic: h = chebyshev + 0.001 euclid + cost, f = 0.5 g + 0.5 h, the
  selected cell is the first index of the largest exp(-f / sqrt(N)) * open divided by its sum, its free neighbours
  get g = g[sel] + cost[sel] when neither open nor closed or when open with a larger g.
- `mazes_test_split`: the MP dataset's mazes test split (arr_8..11), 1 = free, with one start per map drawn here:
  uniformly (NumPy's default_rng(seed)) among the free cells that reach the goal (stored distance above -1024,
  the file's mark of obstacles and unreachable cells) other than the goal.
"""

from __future__ import annotations

import math

import numpy as np
import torch
import torch.nn.functional as F

from tests.needs import public_data

CHECKPOINT = "neural-astar/mazes_032_moore_c8.ckpt"
MAZES = "mpd/mazes_032_moore_c8.npz"


def checkpoint_state() -> dict[str, torch.Tensor]:
    return torch.load(public_data(CHECKPOINT), map_location="cpu", weights_only=True)["state_dict"]


def mazes_test_split(seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`(free (100, 32, 32) bool, starts (100, 2), goals (100, 2))` of the mazes test split (module doc)."""
    data = np.load(public_data(MAZES))
    free = data["arr_8"] > 0.5
    goals = np.argwhere(data["arr_9"][:, 0] > 0.5)[:, 1:]
    dist = data["arr_11"][:, 0]
    rng = np.random.default_rng(seed)
    starts = []
    for b in range(len(free)):
        cells = np.argwhere(free[b] & (dist[b] > -1024) & (dist[b] < 0))
        starts.append(cells[rng.integers(len(cells))])
    return free, np.asarray(starts, dtype=np.int64), goals.astype(np.int64)


def plain_encoder(state: dict[str, torch.Tensor], free: np.ndarray, starts, goals) -> torch.Tensor:
    """`(B, N, N)` guidance costs: the checkpoint's encoder as functional calls (module doc); `starts` None marks
    the goal alone in the second channel."""
    x_map = torch.from_numpy(free.astype(np.float32))
    marks = torch.zeros_like(x_map)
    for b, (gr, gc) in enumerate(goals):
        marks[b, gr, gc] += 1.0
        if starts is not None:
            marks[b, starts[b][0], starts[b][1]] += 1.0
    x = torch.stack([x_map, marks], dim=1)
    p = "planner.encoder.model."
    for conv in (0, 3, 6, 9, 12):
        bn = conv + 1
        x = F.conv2d(x, state[f"{p}{conv}.weight"], state[f"{p}{conv}.bias"], padding=1)
        x = F.batch_norm(
            x,
            state[f"{p}{bn}.running_mean"],
            state[f"{p}{bn}.running_var"],
            state[f"{p}{bn}.weight"],
            state[f"{p}{bn}.bias"],
            training=False,
            eps=1e-5,
        )
        if conv != 12:
            x = F.relu(x)
    return torch.sigmoid(x)[:, 0]


def literal_search(cost: torch.Tensor, free: np.ndarray, start, goal, budget: int | None = None):
    """One search (module doc) on a `(N, N)` float32 cost map and `(N, N)` bool free map. Returns `(path, expanded,
    reached)`: the path start..goal as a list of `(row, col)` (`[start]` when not reached), the `(N, N)` bool map
    of the selected cells, and whether the goal was selected. `budget`: at most that many selections."""
    n = cost.shape[-1]
    rows = torch.arange(n, dtype=torch.float32)[:, None].expand(n, n)
    cols = torch.arange(n, dtype=torch.float32)[None, :].expand(n, n)
    dx = torch.abs(rows - float(goal[0]))
    dy = torch.abs(cols - float(goal[1]))
    chebyshev = (dx + dy) - torch.minimum(dx, dy)
    euclid = torch.sqrt(dx**2 + dy**2)
    h = (chebyshev + 0.001 * euclid + cost).reshape(-1)
    c = cost.reshape(-1)
    g = torch.zeros(n * n)
    open_ = torch.zeros(n * n)
    closed = set()
    parent = {}
    s, t = int(start[0]) * n + int(start[1]), int(goal[0]) * n + int(goal[1])
    open_[s] = 1.0
    expanded = np.zeros((n, n), dtype=bool)
    for _ in range(budget if budget is not None else n * n):
        if float(open_.sum()) == 0:
            break
        f = 0.5 * g + 0.5 * h
        e = torch.exp(-1 * f / math.sqrt(n)) * open_
        y = e / e.sum()
        v = int(torch.argmax(y))  # the first index of the largest value
        closed.add(v)
        expanded[v // n, v % n] = True
        if v == t:
            return parents_chain(parent, s, t, n), expanded, True
        open_[v] = 0.0
        for u, _, _ in free_neighbours(free, v, n):
            g2 = g[v] + c[v]
            if (open_[u] == 0 and u not in closed) or (open_[u] == 1 and g[u] > g2):
                g[u] = g2
                open_[u] = 1.0
                parent[u] = v
    return [(int(start[0]), int(start[1]))], expanded, False


def parents_chain(parent: dict, s: int, t: int, n: int) -> list[tuple[int, int]]:
    """The cells of the parents' chain from the start index `s` to the goal index `t` on `n x n` maps, start first."""
    path = [t]
    while path[-1] != s:
        path.append(parent[path[-1]])
    return [(u // n, u % n) for u in reversed(path)]


def free_neighbours(free: np.ndarray, v: int, n: int):
    """The free cells among the eight around the cell index `v` (corners cut), row-major: `(index, dr, dc)`."""
    r, col = divmod(v, n)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            rr, cc = r + dr, col + dc
            if (dr, dc) == (0, 0) or not (0 <= rr < n and 0 <= cc < n) or not free[rr, cc]:
                continue
            yield rr * n + cc, dr, dc
