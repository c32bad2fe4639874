"""Plain references for the TransPath tests, written from the authors' code (AIRI-Institute/TransPath: models/,
modules/, data/hmaps.py), independent of vinadv's.

- `example_tasks`: the authors' six example tasks (`heatmap_<i>_{f,h,k}.xml`), read as their `OODMaps` does: the
  grid (1 = obstacle), start `(starty, startx)`, goal `(goaly, goalx)`, and the file's target values.
- `plain_forward`: the authors' `Autoencoder.forward` as functional PyTorch calls on the state dict's tensors
  (conv, group norm, x * sigmoid(x), layer norm, attention by einsum, GELU, nearest upsampling, tanh), then
  `(output + 1) / 2`, the input built here (`cf`: map and goal map; `f`: map and start map + goal map).
- `literal_search`: their `DifferentiableDiagAstar` at evaluation, one map at a time, as a literal loop over the 8
  neighbours of the selected cell, in float32 PyTorch arithmetic written as theirs: octile h = min(dx, dy) * 2**0.5 +
  |dx - dy|; `cf`: h / where(k > 0.1, k, 0.1), f = 0.5 g + (1 - 0.5 + 0.001) h, the selected cell the first index of
  the largest exp(-f / sqrt(64)) * open divided by its sum; `f`: f = 0.5 g + 0.5 h, the open cells with f <= min f *
  f_w, the selected cell the first index of the largest exp(focal) over them divided by its sum. A neighbour (in the
  grid, free; a diagonal needing only its destination free, as theirs) gets g = g[sel] + (1 or float32 sqrt 2) when
  neither open nor closed, or open with a larger g. Counts the selections where the largest value was shared by
  several cells (float32 ties: the row-major first wins).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import torch
import torch.nn.functional as F

from tests.needs import public_data
from tests.planners.neural_astar.literal import free_neighbours, parents_chain

WEIGHTS = {"cf": "transpath/cf.pth", "f": "transpath/focal.pth"}
TARGET = {"cf": "k", "f": "f"}


def state(mode: str) -> dict[str, torch.Tensor]:
    return torch.load(public_data(WEIGHTS[mode]), map_location="cpu", weights_only=True)


def _grid(node) -> np.ndarray:
    return np.array([[float(v) for v in row.text.split()] for row in node])


def example_tasks(kind: str = "k") -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """`(obstacles (6, 64, 64) bool, starts (6, 2), goals (6, 2), targets (6, 64, 64))` of the six example tasks; the
    targets of the `kind` files (`f` focal values, `h` cost-to-go, `k` correction factors)."""
    obstacles, starts, goals, targets = [], [], [], []
    for i in range(6):
        root = ET.parse(public_data(f"transpath/heatmap_{i}_{kind}.xml")).getroot()
        m = root[0]
        obstacles.append(_grid(m[6]) == 1)
        starts.append((int(m[1].text), int(m[0].text)))
        goals.append((int(m[3].text), int(m[2].text)))
        targets.append(_grid(root[1][2]))
    return np.array(obstacles), np.array(starts, dtype=np.int64), np.array(goals, dtype=np.int64), np.array(targets)


def _swish(x):
    return x * torch.sigmoid(x)


def _resblock(s, p, x):
    h = F.group_norm(x, 32, s[f"{p}.norm1.weight"], s[f"{p}.norm1.bias"], eps=1e-6)
    h = F.conv2d(_swish(h), s[f"{p}.conv1.weight"], s[f"{p}.conv1.bias"], padding=1)
    h = F.group_norm(h, 32, s[f"{p}.norm2.weight"], s[f"{p}.norm2.bias"], eps=1e-6)
    h = F.conv2d(_swish(h), s[f"{p}.conv2.weight"], s[f"{p}.conv2.bias"], padding=1)
    return x + h


def _attention(s, p, x):
    b, n, _ = x.shape
    q, k, v = (F.linear(x, s[f"{p}.to_{t}.weight"]) for t in "qkv")
    q, k, v = (t.reshape(b, n, 4, 16).permute(0, 2, 1, 3).reshape(b * 4, n, 16) for t in (q, k, v))
    sim = torch.einsum("b i d, b j d -> b i j", q, k) * 16**-0.5
    out = torch.einsum("b i j, b j d -> b i d", sim.softmax(dim=-1), v)
    out = out.reshape(b, 4, n, 16).permute(0, 2, 1, 3).reshape(b, n, 64)
    return F.linear(out, s[f"{p}.to_out.0.weight"], s[f"{p}.to_out.0.bias"])


def _pos(s, p, x):
    return x + F.linear(s[f"{p}.grid"], s[f"{p}.linear.weight"], s[f"{p}.linear.bias"]).moveaxis(3, 1)


def plain_forward(s: dict[str, torch.Tensor], obstacles: np.ndarray, starts, goals) -> torch.Tensor:
    """`(B, 1, 64, 64)`: `(Autoencoder(inputs) + 1) / 2` (module doc); `starts` None: the goal map alone."""
    x_map = torch.from_numpy(obstacles.astype(np.float32))
    marks = torch.zeros_like(x_map)
    for b, (gr, gc) in enumerate(goals):
        marks[b, gr, gc] = 1.0
    if starts is not None:
        for b, (sr, sc) in enumerate(starts):
            marks[b, sr, sc] += 1.0
    x = torch.stack([x_map, marks], dim=1)
    x = F.conv2d(x, s["encoder.layers.0.weight"], s["encoder.layers.0.bias"], padding=2)
    for i in (1, 2, 3):
        x = _resblock(s, f"encoder.layers.{i}.0", x)
        x = F.conv2d(
            F.pad(x, (0, 1, 0, 1)),
            s[f"encoder.layers.{i}.1.conv.weight"],
            s[f"encoder.layers.{i}.1.conv.bias"],
            stride=2,
        )
    x = _pos(s, "pos", x)
    b, c, hh, ww = x.shape
    x_in = x
    x = F.group_norm(x, 32, s["transformer.norm.weight"], s["transformer.norm.bias"], eps=1e-6)
    x = F.conv2d(x, s["transformer.proj_in.weight"], s["transformer.proj_in.bias"])
    x = x.permute(0, 2, 3, 1).reshape(b, hh * ww, c)
    for i in range(4):
        p = f"transformer.transformer_blocks.{i}"

        def ln(t, j, p=p):
            return F.layer_norm(t, (64,), s[f"{p}.norm{j}.weight"], s[f"{p}.norm{j}.bias"])

        x = _attention(s, f"{p}.attn1", ln(x, 1)) + x
        x = _attention(s, f"{p}.attn2", ln(x, 2)) + x
        hidden = F.gelu(F.linear(ln(x, 3), s[f"{p}.ff.net.0.0.weight"], s[f"{p}.ff.net.0.0.bias"]))
        x = F.linear(hidden, s[f"{p}.ff.net.2.weight"], s[f"{p}.ff.net.2.bias"]) + x
    x = x.reshape(b, hh, ww, c).permute(0, 3, 1, 2)
    x = F.conv2d(x, s["transformer.proj_out.weight"], s["transformer.proj_out.bias"]) + x_in
    x = _pos(s, "decoder_pos", x)
    for i in (0, 1, 2):
        x = _resblock(s, f"decoder.layers.{i}.0", x)
        x = F.interpolate(x, scale_factor=2.0, mode="nearest")
        x = F.conv2d(x, s[f"decoder.layers.{i}.1.conv.weight"], s[f"decoder.layers.{i}.1.conv.bias"], padding=1)
    x = _swish(F.group_norm(x, 32, s["decoder.norm.weight"], s["decoder.norm.bias"], eps=1e-6))
    x = torch.tanh(F.conv2d(x, s["decoder.conv_out.weight"], s["decoder.conv_out.bias"], padding=1))
    return (x + 1) / 2


def literal_search(values: torch.Tensor, free: np.ndarray, start, goal, mode: str, f_w: float = 100):
    """One search (module doc) with the network's `(N, N)` float32 values (`cf`: correction factors; `f`: focal
    values) on the `(N, N)` bool free map. Returns `(path, expanded, reached, ties)`: the path start..goal as a list
    of `(row, col)` (`[start]` when not reached), the `(N, N)` bool map of the selected cells, whether the goal was
    selected, and the number of selections where the largest value was shared by several cells."""
    n = values.shape[-1]
    loc = torch.stack(torch.meshgrid(torch.arange(n), torch.arange(n), indexing="ij")).to(torch.float32)
    goal_loc = torch.tensor([float(goal[0]), float(goal[1])])[:, None, None]
    dxdy = torch.abs(loc - goal_loc)
    h = dxdy.min(dim=0)[0] * (2**0.5) + torch.abs(dxdy[0] - dxdy[1])
    if mode == "cf":
        thr = torch.tensor(0.1)
        h = h / torch.where(values > thr, values, thr)
    h = h.reshape(-1)
    focal_exp = torch.exp(values).reshape(-1)
    diagonal = np.float32(torch.tensor(2**0.5, dtype=torch.float32).item())  # the authors' cost filter's value
    g = torch.zeros(n * n)
    open_ = torch.zeros(n * n)
    g_, open_np = g.numpy(), open_.numpy()  # the same memory: the neighbour loop reads and writes float32 scalars
    closed, parent = set(), {}
    s, t = int(start[0]) * n + int(start[1]), int(goal[0]) * n + int(goal[1])
    open_[s] = 1.0
    expanded = np.zeros((n, n), dtype=bool)
    ties = 0
    for _ in range(n * n):
        if float(open_.sum()) == 0:
            break
        if mode == "cf":
            f = 0.5 * g + (1 - 0.5 + 0.001) * h
            e = torch.exp(-1 * f / math.sqrt(n)) * open_
        else:
            f = 0.5 * g + (1 - 0.5) * h
            lowest = (f * open_ + (open_ == 0) * n**2).min()
            e = focal_exp * torch.where((f <= lowest * f_w) * (open_ == 1), 1.0, 0.0)
        y = e / e.sum()
        v = int(torch.argmax(y))  # the first index of the largest value
        ties += int((y == y[v]).sum()) > 1
        closed.add(v)
        expanded[v // n, v % n] = True
        if v == t:
            return parents_chain(parent, s, t, n), expanded, True, ties
        open_np[v] = 0.0
        for u, dr, dc in free_neighbours(free, v, n):
            g2 = g_[v] + (diagonal if dr and dc else np.float32(1.0))  # float32 + float32
            if (open_np[u] == 0 and u not in closed) or (open_np[u] == 1 and g_[u] > g2):
                g_[u] = g2
                open_np[u] = 1.0
                parent[u] = v
    return [(int(start[0]), int(start[1]))], expanded, False, ties
