"""Random grid worlds in the style of the original VIN data generator (Tamar et al. 2016).

A map is built from `randint(1, max_obs)` placement attempts, each a filled rectangle (width and height
`ceil(u * max_size)`) or a filled disc (radius `ceil(u * max_size)`) at a uniform position; an attempt that
would cover the goal is skipped. A one-cell border is always an obstacle. At 28x28 (max_obs 50, max_size 2)
about 30% of the cells are obstacles, border included. Other sizes scale `max_obs` with the area and
`max_size` with the side (see `default_obstacle_params`).

Generation is vectorised over maps and runs in chunks of `chunk_maps(size)` maps (`CHUNK` = 512 up to about
30x30, fewer on larger maps, so that one chunk's working memory stays near `CHUNK_BYTES`), each from its own seed
`(seed, chunk)`: a dataset of n maps is the first n maps of the infinite stream for that seed and size, so it does
not depend on n being larger, and chunks can be made anywhere (a cluster worker) without a shared RNG.

The shapes are painted one by one over their bounding boxes (compiled with Numba), from the same draws as the
original vectorised formulation (every attempt tested against every cell), so the maps are those it made.

Limits (InputError naming them, before any work): `n_starts` past the cells a start can be on (`start_cells`), a size
where one map's working memory (~`WORK_BYTES_PER_CELL` bytes per cell, measured with tracemalloc) exceeds half the
available memory (about 9,000x9,000 with 24 GiB available), and an `n` whose maps would take more than half the
available memory (the output is held in memory).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence

import numba
import numpy as np

from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import DEFAULT_MOVES, check_moves
from vinadv.grid.paths import PackedPaths
from vinadv.grid.selection import smallest_first
from vinadv.grid.shortest_paths import expert_paths_from, shortest_distances

CHUNK = 512
#: a chunk's working memory target: `CHUNK` maps up to ~30x30, then fewer maps per chunk
CHUNK_BYTES = 256 << 20
#: `chunk_maps`'s divisor per (map, placement attempt, cell). It fixes how many maps a chunk (one seed) holds, so it
#: is part of the stream's definition and never changes (it was the working memory of the vectorised placement)
STREAM_BYTES_PER_CELL = 6
#: peak working memory of generation per (map, cell), measured with tracemalloc at sizes 200 and 400: 142 bytes
WORK_BYTES_PER_CELL = 142
#: bytes per placement attempt of one map (its seven drawn numbers)
ATTEMPT_BYTES = 56
MIN_SIZE = 8
MIN_START_MOVES = 2


def available_memory() -> int:
    """Bytes of memory available to this process now (MemAvailable; physical memory where that is unknown)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def chunk_maps(size: int, max_obs: int | None = None) -> int:
    """Maps per generator chunk on `size x size` maps: `CHUNK`, or fewer on large maps (`STREAM_BYTES_PER_CELL`)."""
    max_obs = default_obstacle_params(size)[0] if max_obs is None else max_obs
    return int(max(1, min(CHUNK, CHUNK_BYTES // (STREAM_BYTES_PER_CELL * max_obs * size * size))))


def map_bytes(size: int, n_starts: int) -> int:
    """Bytes one generated map holds in memory (obstacles, goal, starts, costs, expert paths of ~2N cells), twice:
    the chunks and their concatenation exist together for a moment."""
    return 2 * (size * size + 16 + n_starts * (16 + 8 + 8 + 2 * size * 4))


def check_limits(n: int, size: int, n_starts: int, max_obs: int) -> None:
    """Refuse (InputError) a size whose single map, or an `n` whose maps, would not fit half the available memory."""
    avail = available_memory()

    def work(side: int, attempts: int) -> int:  # one map's working memory: its cells and its shapes' draws
        return WORK_BYTES_PER_CELL * side * side + ATTEMPT_BYTES * attempts

    if work(size, max_obs) > avail // 2:
        largest = math.isqrt(avail // 2 // WORK_BYTES_PER_CELL)
        while largest > MIN_SIZE and work(largest, default_obstacle_params(largest)[0]) > avail // 2:
            largest -= 1 + largest // 16
        raise InputError(
            f"size {size}: generating one {size}x{size} map needs {_gib(work(size, max_obs))} of memory "
            f"({size * size:,} cells, {max_obs:,} placement attempts), more than half the {_gib(avail)} "
            f"available; the limit here is about size {largest}",
            "size",
            "size",
        )
    need = n * map_bytes(size, n_starts)
    if need > avail // 2:
        fits = avail // 2 // map_bytes(size, n_starts)
        raise InputError(
            f"n {n:,}: {n:,} maps of {size}x{size} need about {_gib(need)} of memory, more than half "
            f"the {_gib(avail)} available; the limit here is about n {fits:,} per file (make several "
            "files with different seed)",
            "n",
            "n",
            "seed",
        )


def _gib(n_bytes: int) -> str:
    return f"{n_bytes / 2**30:,.1f} GiB" if n_bytes >= 2**30 / 10 else f"{n_bytes / 2**20:,.0f} MiB"


def start_cells(size: int) -> int:
    """The most starts a `size x size` map can hold: its interior cells (the border is an obstacle) less the goal and
    the cells one move from it (a start is `MIN_START_MOVES` = 2 moves away; a goal in a corner of the interior has
    at least two such cells under every movement model). More is refused before any map is made, where it would
    otherwise draw maps until the generator gives up."""
    return max(0, (size - 2) ** 2 - 3)


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

    obstacles = np.zeros((n, size, size), dtype=np.bool_)
    _paint_shapes(attempts, is_disc, top, left, height, width, radius, goals.astype(np.int64), obstacles)
    obstacles[:, 0, :] = obstacles[:, -1, :] = obstacles[:, :, 0] = obstacles[:, :, -1] = True
    return obstacles


@numba.njit(cache=True)
def _paint_shapes(attempts, is_disc, top, left, height, width, radius, goals, out):
    """Paint map `b`'s first `attempts[b]` shapes into `out[b]` (clipped to the map), skipping a shape that covers
    the goal: a disc is the cells within Euclidean `radius` of `(top, left)`, a rectangle `height x width` cells from
    `(top, left)` down and right. Only the cells in each shape's bounding box are visited."""
    size = out.shape[1]
    for b in range(out.shape[0]):
        gr, gc = goals[b, 0], goals[b, 1]
        for k in range(attempts[b]):
            t, lf = top[b, k], left[b, k]
            if is_disc[b, k]:
                r2 = radius[b, k] * radius[b, k]
                if (gr - t) ** 2 + (gc - lf) ** 2 <= r2:
                    continue
                for i in range(max(0, t - radius[b, k]), min(size, t + radius[b, k] + 1)):
                    for j in range(max(0, lf - radius[b, k]), min(size, lf + radius[b, k] + 1)):
                        if (i - t) ** 2 + (j - lf) ** 2 <= r2:
                            out[b, i, j] = True
            else:
                h, w = height[b, k], width[b, k]
                if t <= gr < t + h and lf <= gc < lf + w:
                    continue
                for i in range(t, min(size, t + h)):
                    for j in range(lf, min(size, lf + w)):
                        out[b, i, j] = True


def _generate_chunk(
    seed: tuple[int, ...],
    chunk: int,
    size: int,
    n_starts: int,
    corner_cutting: bool,
    max_obs: int,
    max_size: int,
    count: int,
    moves: str = DEFAULT_MOVES,
):
    """Chunk `chunk` of the stream: its `count` maps, less those without `n_starts` eligible starts, with their
    expert paths (computed here, so that no chunk's distance maps outlive it)."""
    rng = np.random.default_rng([*seed, chunk])
    goals = rng.integers(1, size - 1, (count, 2))
    obstacles = _draw_obstacles(rng, count, size, goals, max_obs, max_size)
    dist, counts = shortest_distances(obstacles, goals, corner_cutting, moves)
    eligible = (counts >= MIN_START_MOVES).reshape(count, -1)
    # n_starts distinct eligible cells, uniformly: the smallest random keys among eligible cells.
    keys = rng.random(eligible.shape)
    keys[~eligible] = np.inf
    picks = smallest_first(keys, n_starts)
    starts = np.stack(np.divmod(picks, size), axis=-1).astype(np.int64)
    goals = goals.astype(np.int64)
    ok = np.count_nonzero(eligible, axis=1) >= n_starts
    if not ok.all():  # usually every map is kept: no copies then
        obstacles, goals, starts, dist = obstacles[ok], goals[ok], starts[ok], dist[ok]
    costs, expert = expert_paths_from(dist, obstacles, goals, starts, corner_cutting, moves)
    return obstacles, goals, starts, costs, expert


def generate_maps(
    n: int,
    size: int = 28,
    seed: int | Sequence[int] = 0,
    n_starts: int = 7,
    corner_cutting: bool = True,
    max_obs: int | None = None,
    max_size: int | None = None,
    progress: Callable[[int], None] | None = None,
    moves: str = DEFAULT_MOVES,
) -> MapSet:
    """Generate `n` maps of `size x size` with `n_starts` starts each and their expert (optimal) paths under the
    movement model `moves` (`vinadv.grid.moves`).

    Deterministic for `(seed, size, n_starts, corner_cutting, max_obs, max_size, moves)`; maps where fewer than
    `n_starts` cells can reach the goal in at least 2 moves are dropped and replaced from the stream. Each chunk's
    obstacles and goals do not depend on `moves`; its starts do (2 moves of that model), and so which maps it keeps.
    `seed` may be a sequence of ints (say `(seed, shard)`) for independent streams. `progress(k)` is called with
    the number of maps each chunk added. A size or `n` that cannot fit in memory is refused (`check_limits`).
    """
    seeds = (int(seed),) if np.isscalar(seed) else tuple(int(s) for s in seed)
    moves = check_moves(moves, corner_cutting)
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
    most = start_cells(size)
    if n_starts > most:
        raise InputError(
            f"n_starts {n_starts}: a {size}x{size} map has at most {most} cells a start can be on (its interior, "
            f"less the goal and the cells one move from it)",
            "n_starts",
        )
    check_limits(n, size, n_starts, max_obs)
    count = chunk_maps(size, max_obs)

    parts: list[tuple[np.ndarray, ...]] = []
    have, chunk = 0, 0
    while have < n:
        part = _generate_chunk(seeds, chunk, size, n_starts, corner_cutting, max_obs, max_size, count, moves)
        parts.append(part)
        have += len(part[0])
        chunk += 1
        if progress is not None and len(part[0]):
            progress(min(len(part[0]), n - (have - len(part[0]))))
        if chunk * count > 64 * CHUNK and have == 0:
            raise InputError(
                f"could not place {n_starts} starts on any {size}x{size} map; use fewer (n_starts)", "n_starts"
            )
    if parts:
        obstacles, goals, starts, costs = (np.concatenate(x)[:n] for x in zip(*(p[:4] for p in parts)))
        expert = PackedPaths.concat([p[4] for p in parts]).take(slice(0, n * n_starts))
    else:
        obstacles = np.zeros((0, size, size), dtype=bool)
        goals = np.zeros((0, 2), dtype=np.int64)
        starts = np.zeros((0, n_starts, 2), dtype=np.int64)
        costs, expert = np.zeros((0, n_starts)), PackedPaths.empty()
    return MapSet(
        obstacles=obstacles,
        goals=goals.astype(np.int64),
        starts=starts.astype(np.int64),
        expert_costs=costs,
        expert=expert,
        corner_cutting=corner_cutting,
        seed=seeds[0] if len(seeds) == 1 else -1,
        moves=moves,
    )


def obstacle_fraction(obstacles: np.ndarray) -> float:
    """Mean fraction of obstacle cells, border included."""
    return float(np.mean(obstacles)) if obstacles.size else math.nan
