"""Writers of the kentsommer, avivt and GPPN layouts for the format tests.

They follow the layouts as the issue and docs/guide/interop.md state them, cell by cell in plain Python, so the
importers are checked against an independent reading of the layout, not against the exporters.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.io

from vinadv.grid import MapSet

# (d_row, d_col) in vinadv's order N,S,E,W,NE,NW,SE,SW and in GPPN's N,E,W,S,NE,NW,SE,SW, written out again here.
OURS = [(-1, 0), (1, 0), (0, 1), (0, -1), (-1, 1), (-1, -1), (1, 1), (1, -1)]
GPPN = [(-1, 0), (0, 1), (0, -1), (1, 0), (-1, 1), (-1, -1), (1, 1), (1, -1)]


def trajectories(maps, keep=None):
    """[(map, path list of (r, c))] of every start, in order; `keep(i, s)` may leave some out."""
    out = []
    for i in range(len(maps)):
        for s in range(maps.n_starts):
            if keep is None or keep(i, s):
                out.append((i, [tuple(map(int, c)) for c in maps.expert_path(i, s)]))
    return out


def kentsommer_arrays(maps, trajs, prior=0.0):
    x, s1, s2, labels = [], [], [], []
    n = maps.size
    for i, path in trajs:
        for (r, c), (r2, c2) in zip(path[:-1], path[1:]):
            img = np.zeros((2, n, n), np.float32)
            img[0] = maps.obstacles[i]
            img[1] = prior
            img[1, maps.goals[i, 0], maps.goals[i, 1]] = 10
            x.append(img)
            s1.append([r])
            s2.append([c])
            labels.append([OURS.index((r2 - r, c2 - c))])
    return [
        np.array(x).reshape(-1, 2, n, n),
        np.array(s1).reshape(-1, 1),
        np.array(s2).reshape(-1, 1),
        np.array(labels).reshape(-1, 1),
    ]


def write_kentsommer(path, maps, train_trajs, test_trajs, prior=0.0):
    np.savez(path, *kentsommer_arrays(maps, train_trajs, prior), *kentsommer_arrays(maps, test_trajs, prior))


def write_avivt_test(path, maps, trajs):
    n = maps.size
    im, value, paths = [], [], np.empty((len(trajs), 1), dtype=object)
    for row, (i, path_cells) in enumerate(trajs):
        free = np.zeros(n * n, np.uint8)
        val = np.full(n * n, -1, np.int16)
        for r in range(n):
            for c in range(n):
                free[c * n + r] = 0 if maps.obstacles[i, r, c] else 1  # column-major, as MATLAB unrolls
        val[maps.goals[i, 1] * n + maps.goals[i, 0]] = 10
        im.append(free)
        value.append(val)
        paths[row, 0] = np.array(path_cells, np.uint8) + 1
    scipy.io.savemat(path, {"all_im_data": np.array(im), "all_value_data": np.array(value), "all_states_xy": paths})


def write_avivt_train(path, maps, trajs):
    n = maps.size
    im, value, xy, labels = [], [], [], []
    for i, path_cells in trajs:
        for (r, c), (r2, c2) in zip(path_cells[:-1], path_cells[1:]):
            im.append([0 if maps.obstacles[i, rr, cc] else 1 for rr in range(n) for cc in range(n)])  # row-major
            value.append([10 if (rr, cc) == tuple(maps.goals[i]) else 0 for rr in range(n) for cc in range(n)])
            xy.append([r, c])
            labels.append([OURS.index((r2 - r, c2 - c))])
    scipy.io.savemat(
        path,
        {
            k: np.array(v, np.uint8)
            for k, v in dict(im_data=im, value_data=value, state_xy_data=xy, label_data=labels).items()
        },
    )


def gppn_policy(obstacles, goal):
    """One-hot (8, 1, n, n): BFS with every Moore move of cost 1, the lowest GPPN index among optimal actions."""
    n = len(obstacles)
    dist = {tuple(goal): 0}
    frontier = [tuple(goal)]
    while frontier:
        nxt = []
        for r, c in frontier:
            for dr, dc in GPPN:
                rr, cc = r + dr, c + dc
                if 0 <= rr < n and 0 <= cc < n and not obstacles[rr][cc] and (rr, cc) not in dist:
                    dist[(rr, cc)] = dist[(r, c)] + 1
                    nxt.append((rr, cc))
        frontier = nxt
    policy = np.zeros((8, 1, n, n), np.float32)
    for (r, c), d in dist.items():
        for a, (dr, dc) in enumerate(GPPN):
            if d > 0 and dist.get((r + dr, c + dc), math.inf) == d - 1 and 0 <= r + dr < n and 0 <= c + dc < n:
                policy[a, 0, r, c] = 1
                break
    return policy


def gppn_generator_policy(free, goal, mechanism, rng):
    """The arrays GPPN's own generator (lileee/gated-path-planning-networks, `generate_dataset.py`) writes for one
    maze, written from its description in plain Python: `(policy (A, 1, n, n), value (n, n))`. Its Dijkstra gives
    every reachable cell minus its move count (every move costs 1; a move into a wall or off the grid stays put)
    and every other cell `-n*n`; its policy, at EVERY cell (walls, walled-off cells and the goal included), is one
    of the actions whose resulting cell has the largest value, picked at random: at the goal that is any move that
    stays put (into a wall) or the goal itself, at a wall or walled-off cell anything."""
    n = len(free)
    order = GPPN[:4] if mechanism == "news" else GPPN

    def step(r, c, dr, dc):
        rr, cc = r + dr, c + dc
        return (rr, cc) if 0 <= rr < n and 0 <= cc < n and free[rr][cc] else (r, c)

    value = np.full((n, n), -float(n * n))
    value[goal] = 0.0
    frontier = [tuple(goal)]
    while frontier:
        nxt = []
        for r, c in frontier:
            for dr, dc in order:  # moves are symmetric: a predecessor is a neighbour
                rr, cc = step(r, c, dr, dc)
                if value[rr, cc] == -n * n:
                    value[rr, cc] = value[r, c] - 1
                    nxt.append((rr, cc))
        frontier = nxt
    policy = np.zeros((len(order), 1, n, n), np.float32)
    for r in range(n):
        for c in range(n):
            vals = [value[step(r, c, dr, dc)] for dr, dc in order]
            best = [a for a, v in enumerate(vals) if v == max(vals)]
            policy[best[rng.integers(len(best))], 0, r, c] = 1
    return policy, value


def write_gppn_generated(path, obstacles, goals, mechanism, seed=0):
    """A file as GPPN's generator writes it (`np.savez_compressed` of train, valid, test x mazes 1 = free, goal maps,
    optimal policies; float32), the maps in the test split, the others empty."""
    n = obstacles.shape[1]
    rng = np.random.default_rng(seed)
    a = 4 if mechanism == "news" else 8
    goal_maps = np.zeros((len(goals), 1, n, n), np.float32)
    goal_maps[np.arange(len(goals)), 0, goals[:, 0], goals[:, 1]] = 1
    free = (~obstacles).astype(np.float32)
    policies = np.array([gppn_generator_policy(f, tuple(g), mechanism, rng)[0] for f, g in zip(free, goals)])
    empty = [np.zeros((0, n, n), np.float32), np.zeros((0, 1, n, n), np.float32), np.zeros((0, a, 1, n, n), np.float32)]
    np.savez_compressed(path, *empty, *empty, free, goal_maps, policies)
    return policies


def gppn_arrays(obstacles, goals):
    n = obstacles.shape[1]
    goal_maps = np.zeros((len(goals), 1, n, n), np.float32)
    for i, (r, c) in enumerate(goals):
        goal_maps[i, 0, r, c] = 1
    return [
        (~obstacles).astype(np.float32),
        goal_maps,
        np.array([gppn_policy(o, g) for o, g in zip(obstacles, goals)]).reshape(-1, 8, 1, n, n),
    ]


def write_gppn(path, obstacles, goals, split="test"):
    n = obstacles.shape[1]
    empty = [np.zeros((0, n, n)), np.zeros((0, 1, n, n)), np.zeros((0, 8, 1, n, n))]
    parts = {"train": empty, "valid": empty, "test": empty}
    parts[split] = gppn_arrays(obstacles, goals)
    np.savez(path, *parts["train"], *parts["valid"], *parts["test"])


def assert_same_maps(got: MapSet, want: MapSet, counts=None):
    np.testing.assert_array_equal(got.obstacles, want.obstacles)
    np.testing.assert_array_equal(got.goals, want.goals)
    mask = got.start_mask
    if counts is not None:
        np.testing.assert_array_equal(mask.sum(axis=1), counts)
    np.testing.assert_array_equal(got.starts[mask], want.starts[:, : got.n_starts][mask])
    np.testing.assert_allclose(got.expert_costs[mask], want.expert_costs[:, : got.n_starts][mask])
