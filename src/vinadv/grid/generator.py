"""Random grid worlds in the style of the original VIN data generator (Tamar et al. 2016).

A map is built from `randint(1, max_obs)` placement attempts, each a filled rectangle (width and height
`ceil(u * max_size)`) or a filled disc (radius `ceil(u * max_size)`) at a uniform position; an attempt that
would cover the goal is skipped. A one-cell border is always an obstacle. At 28x28 (max_obs 50, max_size 2)
about 30% of the cells are obstacles, border included. Other sizes scale `max_obs` with the area and
`max_size` with the side (see `default_obstacle_params`).

Generation is vectorised over maps and runs in chunks of `CHUNK` maps, each from its own seed
`(seed, chunk)`: a dataset of n maps is the first n maps of the infinite stream for that seed, so it does not
depend on n being larger, and chunks can be made anywhere (a cluster worker) without a shared RNG.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.grid.shortest_paths import expert_paths_from, shortest_distances

CHUNK = 512
MIN_SIZE = 8
MIN_START_MOVES = 2


def default_obstacle_params(size: int) -> tuple[int, int]:
    """`(max_obs, max_size)` for an N x N map: 50 and 2 at 28, scaled by area and side, at least 1 each."""
    max_obs = max(1, round(50 * (size / 28) ** 2))
    max_size = max(1, round(2 * size / 28))
    return max_obs, max_size


def _draw_obstacles(rng: np.random.Generator, n: int, size: int, goals: np.ndarray, max_obs: int, max_size: int):
    attempts = rng.integers(1, max_obs, size=n, endpoint=True)
    is_disc = rng.random((n, max_obs)) < 0.5
    top = rng.integers(0, size, (n, max_obs))
    left = rng.integers(0, size, (n, max_obs))
    # ceil(u * max_size) with u in [0, 1) is 0 only when u == 0 exactly; clamp to one cell.
    height = np.maximum(1, np.ceil(rng.random((n, max_obs)) * max_size)).astype(np.int64)
    width = np.maximum(1, np.ceil(rng.random((n, max_obs)) * max_size)).astype(np.int64)
    radius = np.maximum(1, np.ceil(rng.random((n, max_obs)) * max_size)).astype(np.int64)

    rows = np.arange(size)[None, None, :, None]
    cols = np.arange(size)[None, None, None, :]
    t, lft = top[..., None, None], left[..., None, None]
    rect = (rows >= t) & (rows < t + height[..., None, None]) & (cols >= lft) & (cols < lft + width[..., None, None])
    disc = (rows - t) ** 2 + (cols - lft) ** 2 <= radius[..., None, None] ** 2
    shapes = np.where(is_disc[..., None, None], disc, rect)
    shapes &= (np.arange(max_obs)[None, :] < attempts[:, None])[..., None, None]
    covers_goal = shapes[np.arange(n), :, goals[:, 0], goals[:, 1]]
    shapes &= ~covers_goal[..., None, None]
    obstacles = shapes.any(axis=1)
    obstacles[:, 0, :] = obstacles[:, -1, :] = obstacles[:, :, 0] = obstacles[:, :, -1] = True
    return obstacles


def _generate_chunk(seed: tuple[int, ...], chunk: int, size: int, n_starts: int, corner_cutting: bool, max_obs: int,
                    max_size: int):
    rng = np.random.default_rng([*seed, chunk])
    goals = rng.integers(1, size - 1, (CHUNK, 2))
    obstacles = _draw_obstacles(rng, CHUNK, size, goals, max_obs, max_size)
    dist, moves = shortest_distances(obstacles, goals, corner_cutting)
    eligible = (moves >= MIN_START_MOVES).reshape(CHUNK, -1)
    # n_starts distinct eligible cells, uniformly: the smallest random keys among eligible cells.
    keys = np.where(eligible, rng.random(eligible.shape), np.inf)
    picks = np.argsort(keys, axis=1)[:, :n_starts]
    ok = eligible.sum(axis=1) >= n_starts
    starts = np.stack(np.divmod(picks, size), axis=-1)
    return obstacles[ok], goals[ok], starts[ok], dist[ok]


def generate_maps(
    n: int,
    size: int = 28,
    seed: int | Sequence[int] = 0,
    n_starts: int = 7,
    corner_cutting: bool = True,
    max_obs: int | None = None,
    max_size: int | None = None,
) -> MapSet:
    """Generate `n` maps of `size x size` with `n_starts` starts each and their expert (optimal) paths.

    Deterministic for `(seed, size, n_starts, corner_cutting, max_obs, max_size)`; maps where fewer than
    `n_starts` cells can reach the goal in at least 2 moves are dropped and replaced from the stream.
    `seed` may be a sequence of ints (say `(seed, shard)`) for independent streams.
    """
    seeds = (int(seed),) if np.isscalar(seed) else tuple(int(s) for s in seed)
    if n < 0:
        raise InputError(f"n must be >= 0, got {n}", "n")
    if size < MIN_SIZE:
        raise InputError(f"size must be >= {MIN_SIZE}, got {size}", "size")
    if n_starts < 1:
        raise InputError(f"n_starts must be >= 1, got {n_starts}", "n_starts")
    default_obs, default_size = default_obstacle_params(size)
    max_obs = default_obs if max_obs is None else max_obs
    max_size = default_size if max_size is None else max_size
    if max_obs < 1 or max_size < 1:
        raise InputError(f"max_obs and max_size must be >= 1, got {max_obs} and {max_size}")

    parts: list[tuple[np.ndarray, ...]] = []
    have, chunk = 0, 0
    while have < n:
        part = _generate_chunk(seeds, chunk, size, n_starts, corner_cutting, max_obs, max_size)
        parts.append(part)
        have += len(part[0])
        chunk += 1
        if chunk > 64 and have == 0:
            raise InputError(f"could not place {n_starts} starts on any {size}x{size} map; use fewer (n_starts)",
                             "n_starts")
    if parts:
        obstacles, goals, starts, dist = (np.concatenate(x)[:n] for x in zip(*parts))
    else:
        obstacles = np.zeros((0, size, size), dtype=bool)
        goals = np.zeros((0, 2), dtype=np.int64)
        starts = np.zeros((0, n_starts, 2), dtype=np.int64)
        dist = np.zeros((0, size, size))
    costs, expert = expert_paths_from(dist, obstacles, goals, starts, corner_cutting)
    return MapSet(
        obstacles=obstacles,
        goals=goals.astype(np.int64),
        starts=starts.astype(np.int64),
        expert_costs=costs,
        expert=expert,
        corner_cutting=corner_cutting,
        seed=seeds[0] if len(seeds) == 1 else -1,
    )


def obstacle_fraction(obstacles: np.ndarray) -> float:
    """Mean fraction of obstacle cells, border included."""
    return float(np.mean(obstacles)) if obstacles.size else math.nan
