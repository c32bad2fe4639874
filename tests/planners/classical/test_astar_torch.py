"""The search kernel against the Neural A* authors' differentiable A* as PyTorch computes it, on the MP dataset.

The oracle restates, tensor for tensor, the forward pass of their `DifferentiableAstar` at evaluation (Tmax 1; public
repository omron-sinicx/neural-astar, branch minimal): float32 on the CPU, the whole batch at once, the selection by
`argmax` of `exp(-f / sqrt N)` normalised by its sum, the 3x3 neighbour filter as a grouped convolution. Slow: about
a thousand batched steps.
"""

import math

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from tests.needs import public_data
from vinadv.planners.classical.astar import AStarPlanner, best_first_search

pytestmark = pytest.mark.slow


def authors_forward(cost, free, starts, goals, g_ratio=0.5):
    """Histories and path maps `(B, N, N)` of the authors' search, computed as their module does."""
    b, n = free.shape[0], free.shape[1]
    idx = torch.arange(b)
    start_maps = torch.zeros(b, n, n)
    start_maps[idx, starts[:, 0], starts[:, 1]] = 1
    goal_maps = torch.zeros(b, n, n)
    goal_maps[idx, goals[:, 0], goals[:, 1]] = 1
    kernel = torch.ones(1, 1, 3, 3)
    kernel[0, 0, 1, 1] = 0
    kernel = kernel.repeat_interleave(b, 0)

    def neighbours(x):
        return F.conv2d(x.unsqueeze(0), kernel, padding=1, groups=b).squeeze(0)

    rows, cols = torch.meshgrid(torch.arange(n), torch.arange(n), indexing="ij")
    loc = torch.stack([rows, cols]).float().reshape(2, -1).unsqueeze(0)
    goal_loc = torch.einsum("kij,bij->bk", torch.stack([rows, cols]).float(), goal_maps).unsqueeze(-1)
    diff = (loc - goal_loc).abs()
    h = diff.sum(1) - diff.min(1)[0]
    euclid = torch.sqrt(((loc - goal_loc) ** 2).sum(1))
    h = (h + 0.001 * euclid).reshape(b, n, n) + cost
    g = torch.zeros(b, n, n)
    open_maps, histories = start_maps.clone(), torch.zeros(b, n, n)
    parents = torch.ones(b, n * n, dtype=torch.long) * goal_maps.reshape(b, -1).argmax(-1, keepdim=True)
    for t in range(n * n):  # noqa: B007 (t, the last step, bounds the backtracking below, as theirs)
        f = g_ratio * g + (1 - g_ratio) * h
        value = (torch.exp(-1 * f / math.sqrt(n)) * open_maps).reshape(b, -1)
        selected_index = (value / value.sum(-1, keepdim=True)).max(-1)[1]
        selected = torch.zeros(b, n * n)
        selected[idx, selected_index] = 1
        selected = selected.reshape(b, n, n)
        unsolved = ((selected * goal_maps).sum((1, 2), keepdim=True) < 1e-8).float()
        histories = torch.clamp(histories + selected, 0, 1)
        open_maps = torch.clamp(open_maps - unsolved * selected, 0, 1)
        near = neighbours(selected) * free
        g2 = neighbours((g + cost) * selected)
        update = ((1 - open_maps) * (1 - histories) + open_maps * (g > g2)) * near
        g = g2 * update + g * (1 - update)
        open_maps = torch.clamp(open_maps + update, 0, 1)
        flat = update.reshape(b, -1).long()
        parents = selected_index[:, None] * flat + parents * (1 - flat)
        if torch.all(unsolved.flatten() == 0):
            break
    paths = goal_maps.clone().reshape(b, -1)
    at = parents[idx, goals[:, 0] * n + goals[:, 1]]
    for _ in range(t):
        paths[idx, at] = 1
        at = parents[idx, at]
    return histories.numpy().astype(bool), paths.reshape(b, n, n).numpy().astype(bool)


def problems(family: str, count: int, seed: int):
    with np.load(public_data(f"mpd/{family}_032_moore_c8.npz")) as data:
        free = data["arr_8"][:count].astype(np.float32)
        goals = np.argwhere(data["arr_9"][:count, 0] == 1)[:, 1:]
        reachable = data["arr_11"][:count, 0] > -32 * 32  # the file's distance: -H*W where the goal is out of reach
    rng = np.random.default_rng(seed)
    starts = []
    for f, g in zip(reachable, goals):
        cells = np.argwhere(f)
        starts.append(rng.choice(cells[(cells != g).any(axis=1)]))
    return free, np.array(starts), goals


@pytest.mark.parametrize("family", ["mazes", "forest", "single_bugtrap"])
def test_vanilla_astar_expands_what_the_authors_search_expands_on_mp_maps(family):
    torch.set_num_threads(1)
    free, starts, goals = problems(family, 60, seed=1)
    want_hist, want_paths = authors_forward(torch.from_numpy(free), torch.from_numpy(free), starts, goals)
    ours = AStarPlanner(32, "moore").plan_paths(free == 0, starts, goals)
    assert ours.reached.all()
    assert np.array_equal(ours.expanded, want_hist)
    for i in range(len(free)):
        mask = np.zeros((32, 32), bool)
        mask[tuple(ours.paths[i].T)] = True
        assert np.array_equal(mask, want_paths[i]), i


def test_a_guidance_cost_map_is_searched_as_the_authors_search_it():
    torch.set_num_threads(1)
    free, starts, goals = problems("mazes", 40, seed=2)
    rng = np.random.default_rng(3)
    cost = rng.random(free.shape).astype(np.float32)  # a Neural A* encoder's output lies in (0, 1)
    for g_ratio in (0.5, 0.2):
        want_hist, want_paths = authors_forward(torch.from_numpy(cost), torch.from_numpy(free), starts, goals, g_ratio)
        ours = best_first_search(cost, free == 0, starts, goals, g_ratio, "moore", exact=False)
        assert np.array_equal(ours.expanded, want_hist)
        for i in range(len(free)):
            mask = np.zeros((32, 32), bool)
            mask[tuple(ours.paths[i].T)] = True
            assert np.array_equal(mask, want_paths[i]), i
