"""The MP dataset layout (`.npz`: the motion-planning benchmark of Neural A*, made by the planning-datasets
generator, github.com/omron-sinicx/planning-datasets).

`arr_0..11` = train, valid, test x (maps `(n, M, M)` 1 = free; goals `(n, 1, M, M)` one-hot; optimal actions
`(n, 8, 1, M, M)` one-hot in GPPN's Moore order N,E,W,S,NE,NW,SE,SW; the negative shortest distance to the goal
`(n, 1, M, M)`, `-M*M` at obstacles and at cells that cannot reach the goal). Moves are `moore` (every move costs 1)
and a diagonal move needs only its destination free (the generator's neighbour function checks nothing else), so
the maps cut corners.

What the import checks, each mismatch one line naming the array: 0/1 maps, one goal per map on a free cell,
one-hot actions that are an optimal `moore` move at every cell that reaches the goal (the goal excepted: the
generator writes an arbitrary action there, as at walls and walled-off cells), and the distances: exactly vinadv's
`moore` expert costs (Dijkstra, corner cutting allowed) where the goal is reachable, `-M*M` elsewhere. Before that,
the arrays' headers (`files.check_npz_sizes`) and `--starts` (at most a map's `M*M` cells) are bounded before anything
is allocated for them; a split of 0 maps reads as none.

Starts (the file has none) are drawn as the Neural A* loader draws them (github.com/omron-sinicx/neural-astar,
`utils/data.py`), a rule that wins over vinadv's own start rule for these maps: over the cells whose stored
distance is above the map's minimum (obstacles and walled-off cells excluded), NumPy's default (linear) percentile
gives the bands 55-70, 70-85 and 85-100 of the distance to the goal, bounds inclusive; a band is chosen at random,
then a cell in it, both uniformly, seeded. A band without a cell is skipped (the loader would fail there); a map
whose bands are all empty is left out and counted. The loader draws one start per map (a new one at each visit);
with `--starts K` the K starts of a map are distinct, as a maps file's starts must be: each is drawn by that rule
and a start that repeats an earlier start of its map is drawn again by the same rule (in rounds, until the K
differ). So `--starts 1` draws the loader's start (the same starts as before starts were made distinct). A map
with fewer cells in its bands than K keeps all of them (row-major order) and is padded (`MapSet.start_counts`),
counted in `maps_padded`, as the other imports' start rule (`samples.with_drawn_starts`) does.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.grid.shortest_paths import expert_paths_from, shortest_distances
from vinadv.interop.formats.files import ForeignArrays, load_npz
from vinadv.interop.formats.gppn import decode_gppn_arrays, unit_cost_policies
from vinadv.interop.formats.samples import goal_images, padded_map_set
from vinadv.seeds import check_seed

#: the splits read, and the index of the first array (maps) of each
SPLITS = {"train": 0, "valid": 4, "test": 8}
#: the loader's percentiles of the negative distance: bands 55-70, 70-85, 85-100 of the distance to the goal
PERCENTILES = (45.0, 30.0, 15.0, 0.0)
MOVES = "moore"


def read(path: str, split: str | None, starts: int | None, seed: int, moves: str | None = None) -> tuple[MapSet, dict]:
    """The maps of `split` (default test) of the file at `path` with `starts` (default 1) per map drawn by the
    Neural A* rule with `seed`: `(MapSet, info)`. `moves` None or `moore` (`read_maps` refuses others)."""
    check_seed(seed)
    split = split or "test"
    names = tuple(f"arr_{SPLITS[split] + i}" for i in range(4))  # the split's arrays only: train is 8x the others
    return _read(load_npz(path, names), split, 1 if starts is None else starts, seed)


def _read(f: ForeignArrays, split: str, k: int, seed: int) -> tuple[MapSet, dict]:
    first = SPLITS[split]
    names = [f"arr_{first + i}" for i in range(4)]
    maps = f.get(names[0], 3)
    n, m = maps.shape[0], maps.shape[1]
    if maps.shape[2] != m or m < 3:
        raise f.fail(names[0], f"has shape {maps.shape}, expected (n, M, M) maps")
    if k > m * m:  # before the starts are drawn: distinct starts of a map are at most its cells
        raise InputError(f"n_starts {k}: more than the {m * m} cells of the file's {m}x{m} maps", "n_starts")
    goal_maps = f.get(names[1], 4, (n, 1, m, m))
    policies = f.get(names[2], 5, (n, 8, 1, m, m))
    stored = f.get(names[3], 4, (n, 1, m, m))[:, 0].astype(np.float64)
    obstacles, goals = decode_gppn_arrays(f, names, maps, goal_maps, policies, MOVES)
    dist, _ = shortest_distances(obstacles, goals, True, MOVES)
    check_distances(f, names[3], stored, dist)
    bands = start_bands(stored)
    drawn, counts = draw_starts(bands, k, np.random.default_rng(seed))
    keep = counts > 0
    obstacles, goals, dist, drawn, counts = obstacles[keep], goals[keep], dist[keep], drawn[keep], counts[keep]
    starts = np.stack(np.divmod(drawn, m), axis=-1).astype(np.int64)
    pad = np.arange(k)[None, :] >= counts[:, None]  # a map with fewer band cells than k: its slots past them
    starts[pad] = np.repeat(goals[:, None, :], k, axis=1)[pad]
    costs, expert = expert_paths_from(dist, obstacles, goals, starts, True, MOVES)
    out = padded_map_set(obstacles, goals, starts, costs, expert, counts, k, seed=int(seed), moves=MOVES)
    return out, {
        "split": split,
        "maps": int(keep.sum()),
        "size": m,
        "starts_per_map": k,
        "starts_seed": int(seed),
        "starts_rule": "Neural A*'s: a percentile band of the distance (55-70, 70-85, 85-100) at random, then a cell; "
        "a repeat of an earlier start of the map drawn again",
        "maps_padded": int((counts < k).sum()),
        "maps_left_out_no_start": int((~keep).sum()),
        "expert_paths": "vinadv's own (Dijkstra, moore moves: every move costs 1, corner cutting allowed); the "
        "file's distances checked equal",
    }


def check_distances(f: ForeignArrays, name: str, stored: np.ndarray, dist: np.ndarray) -> None:
    """Refuse (one line naming the array) stored negative distances `(n, M, M)` other than `-dist` where the goal
    is reachable and `-M*M` elsewhere (the generator's value for cells it never reached)."""
    unreached = -float(dist.shape[1] * dist.shape[2])
    want = np.where(np.isfinite(dist), -dist, unreached)
    bad = stored != want
    if bad.any():
        i, r, c = (int(v) for v in np.argwhere(bad)[0])
        raise f.fail(
            name,
            f"has {stored[i, r, c]:g} at map {i} cell ({r}, {c}), vinadv's moore distance says {want[i, r, c]:g} "
            f"({int(bad.sum())} cells differ; distances are negative, {unreached:g} where the goal is not reached)",
        )


def start_bands(stored: np.ndarray) -> np.ndarray:
    """`(n, 3, M*M)` bool: the cells of each map in the loader's three bands (55-70, 70-85, 85-100 percent of the
    distance), from the stored negative distances `(n, M, M)`: over the values above the map's minimum, NumPy's
    default percentiles 45, 30, 15, 0 of the negative distance bound the bands, inclusive."""
    flat = stored.reshape(len(stored), stored.shape[1] * stored.shape[2])  # (0, M*M) for an empty split
    low = flat.min(axis=1, keepdims=True) if len(flat) else np.zeros((0, 1))
    above = flat > low
    values = np.where(above, flat, np.nan)
    rows = above.any(axis=1)
    th = np.full((len(flat), len(PERCENTILES)), np.nan)
    if rows.any():
        # nanpercentile: each row's percentiles of its values above the minimum, as np.percentile of those alone
        th[rows] = np.nanpercentile(values[rows], PERCENTILES, axis=1).T
    upper, lower = th[:, :-1, None], th[:, 1:, None]
    return above[:, None, :] & (flat[:, None, :] >= lower) & (flat[:, None, :] <= upper)


def draw_starts(bands: np.ndarray, k: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """`(drawn (n, k) flat cell indices, counts (n,) int64)`: K distinct starts per map by the loader's rule.

    First round: `u = rng.random((n, k, 2))`; for each map and slot `u[..., 0]` picks one of the map's non-empty bands
    (in band order), `u[..., 1]` a cell of it (row-major), both uniformly (`_pick`). Then, while some slot repeats an
    earlier slot of its map, those slots (in row-major order of (map, slot)) are drawn again the same way, with
    `rng.random((repeats, 2))`. A map with fewer cells in its bands (their union: bounds are inclusive, so a cell on
    a bound is in two) than k gets them all in row-major order, the rest of its row 0; `counts` is k, that number,
    or 0 for a map without a non-empty band (not kept)."""
    n, k = len(bands), int(k)
    counts = bands.sum(axis=2)  # (n, 3)
    in_bands = bands.any(axis=1)  # (n, M*M)
    n_cells = in_bands.sum(axis=1)
    cells = np.argsort(~bands, axis=2, kind="stable")  # (n, 3, M*M): each band's cells first, row-major
    drawn = _pick(cells, counts, rng.random((n, k, 2)))
    full = n_cells >= k  # maps whose k starts can differ: redraw their repeats
    while True:
        repeat = _repeats(drawn) & full[:, None]
        if not repeat.any():
            break
        rows, slots = np.nonzero(repeat)
        drawn[rows, slots] = _pick(cells[rows], counts[rows], rng.random((len(rows), 1, 2)))[:, 0]
    few = np.flatnonzero(~full & (n_cells > 0))
    if len(few):  # all their band cells, row-major, first in the row
        order = np.argsort(~in_bands[few], axis=1, kind="stable")[:, :k]
        drawn[few] = np.where(np.arange(k)[None, :] < n_cells[few, None], order, 0)
    out_counts = np.minimum(n_cells, k).astype(np.int64)
    return np.where(out_counts[:, None] > 0, drawn, 0), out_counts


def _repeats(drawn: np.ndarray) -> np.ndarray:
    """`(n, k)` bool: the slots of `drawn (n, k)` that equal an earlier slot of their row (a stable sort puts equal
    values in slot order, so every one but the first of a run repeats an earlier one; memory O(n k), not O(n k^2))."""
    order = np.argsort(drawn, axis=1, kind="stable")
    ranked = np.take_along_axis(drawn, order, axis=1)
    later = np.zeros(drawn.shape, dtype=bool)
    later[:, 1:] = ranked[:, 1:] == ranked[:, :-1]
    out = np.zeros(drawn.shape, dtype=bool)
    np.put_along_axis(out, order, later, axis=1)
    return out


def _pick(cells: np.ndarray, counts: np.ndarray, u: np.ndarray) -> np.ndarray:
    """`(m, j)` flat cell indices, one per uniform pair `u (m, j, 2)`: `u[..., 0]` one of the map's non-empty bands
    (cell counts `counts (m, 3)`), `u[..., 1]` a cell of it, the band's cells being the first `counts` of `cells
    (m, 3, C)` (row-major); a map without a non-empty band 0."""
    nonempty = counts > 0
    n_bands = nonempty.sum(axis=1)  # (m,)
    which = np.minimum((u[..., 0] * n_bands[:, None]).astype(np.int64), np.maximum(n_bands - 1, 0)[:, None])
    # the which-th non-empty band: the first band whose running count of non-empty bands exceeds `which`
    band = np.argmax(np.cumsum(nonempty, axis=1)[:, None, :] > which[..., None], axis=2)  # (m, j)
    rows = np.arange(len(cells))[:, None]
    size = counts[rows, band]
    rank = np.minimum((u[..., 1] * size).astype(np.int64), np.maximum(size - 1, 0))
    drawn = cells[rows, band, rank]  # the rank-th cell of the band, row-major
    return np.where((n_bands > 0)[:, None], drawn, 0)


def write(maps: MapSet, path: Path, split: str) -> dict:
    """Write `moore` maps (corner cutting allowed: the layout's) to `split` (train|valid|test), the others empty:
    maps, goals, optimal actions (GPPN's order, the lowest index of the optimal ones; none at the goal, walls and
    walled-off cells) and negative distances (`-M*M` where the goal is not reached). Returns the counts: maps."""
    if not maps.corner_cutting:
        raise InputError("maps: the MP layout's moves cut corners; these maps do not (corner_cutting False)")
    s = maps.size
    empty = [
        np.zeros((0, s, s), np.float32),
        np.zeros((0, 1, s, s)),
        np.zeros((0, 8, 1, s, s)),
        np.zeros((0, 1, s, s)),
    ]
    arrays = empty * 3
    dist, _ = shortest_distances(maps.obstacles, maps.goals, True, MOVES)
    at = SPLITS[split]
    arrays[at : at + 4] = [
        (~maps.obstacles).astype(np.float32),
        goal_images(maps, np.arange(len(maps)), 0, 1, np.float64)[:, None],
        unit_cost_policies(maps).astype(np.float64),
        np.where(np.isfinite(dist), -dist, -float(s * s))[:, None],
    ]
    with open(path, "wb") as fh:
        np.savez_compressed(fh, *arrays)
    return {"maps": len(maps)}
