"""Maps of other VIN/GPPN code read into a MapSet and written back out.

Layouts (the conventions checked against the real files in README.md, "Using data and models from other VIN/GPPN
code"):

- `kentsommer` (the common PyTorch port, `.npz`): `arr_0..3` train and `arr_4..7` test, each
  X `(m, 2, s, s)` (channel 0: 1 = obstacle; channel 1: goal prior, 10 at the goal, 0 or -1 elsewhere),
  S1 `(m, 1)` row, S2 `(m, 1)` col, labels `(m, 1)` in vinadv's action order N,S,E,W,NE,NW,SE,SW. One sample per
  step of an expert trajectory, the goal itself not a sample.
- `avivt` (the VIN authors' `.mat`, scipy.io): the test layout `all_im_data (n, s*s)` (1 = free),
  `all_value_data (n, s*s)` (10 at the goal, -1 elsewhere), `all_states_xy (n, 1)` cells of `(L, 2)` 1-based
  `(row, col)` optimal paths, images unrolled in column-major (MATLAB) order; and the training layout, per sample
  `im_data`, `value_data` (10 at the goal, 0 elsewhere), `state_xy_data (m, 2)` 0-based `(row, col)`,
  `label_data (m, 1)` in vinadv's action order, images unrolled in row-major order, plus the same samples shuffled
  into batches of 10 (`batch_im_data`, `batch_value_data`, `state_x_data`, `state_y_data`, `batch_label_data`).
- `gppn` (`.npz`): `arr_0..8` = train, valid, test x (mazes `(n, M, M)` 1 = free, goal maps `(n, O, M, M)` 1.0 at
  the goal, optimal policies `(n, A, O, M, M)` one-hot, Moore order N,E,W,S,NE,NW,SE,SW, diagonal cost 1). No
  starts: they are drawn, seeded.

Samples are regrouped into maps (a new map starts where the image or goal changes from the previous sample/row)
and trajectories (a new one starts where a state is not the previous state plus its labelled move). A map's
starts are the first cells of its trajectories; expert costs are vinadv's (Dijkstra, diagonal cost sqrt 2, corner
cutting allowed as in all three codebases) and the expert paths the file's own where they are optimal under that
model (so their labels are kept), vinadv's where not; how many were optimal is reported.
Maps with fewer trajectories than others are padded explicitly (`MapSet.start_counts`).
"""

from __future__ import annotations

import os
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.actions import ACTION_DELTAS
from vinadv.grid.generator import MIN_START_MOVES
from vinadv.grid.mapset import MapSet
from vinadv.grid.paths import PackedPaths
from vinadv.grid.shortest_paths import (
    COST_TOL,
    _dijkstra_batch,
    expert_paths_from,
    shortest_distances,
    valid_moves,
)

FORMATS = ("kentsommer", "avivt", "gppn")
SPLITS = {"kentsommer": ("train", "test", "all"), "avivt": ("train", "test"), "gppn": ("train", "valid", "test", "all")}
GOAL_VALUE = 10  # the goal prior of the kentsommer port and avivt's files
#: GPPN's Moore order N,E,W,S,NE,NW,SE,SW as vinadv action indices (vinadv: N,S,E,W,NE,NW,SE,SW).
GPPN_TO_VINADV = np.array([0, 2, 3, 1, 4, 5, 6, 7])
KENTSOMMER_SPLITS = {"train": (0,), "test": (4,), "all": (0, 4)}
GPPN_SPLITS = {"train": (0,), "valid": (3,), "test": (6,), "all": (0, 3, 6)}
_CHUNK = 4096


class _Arrays:
    """The arrays of one foreign file, with checks whose errors name the file and the array."""

    def __init__(self, path: str | os.PathLike, data: dict[str, Any]):
        self.path, self.data = str(path), data

    def fail(self, name: str, problem: str) -> InputError:
        return InputError(f"{self.path}: array '{name}' {problem}")

    def has(self, name: str) -> bool:
        return name in self.data

    def get(self, name: str, ndim: int, shape: tuple[int | None, ...] = ()) -> np.ndarray:
        if name not in self.data:
            raise InputError(f"{self.path}: array '{name}' is missing (has {sorted(self.data)[:12]})")
        arr = np.asarray(self.data[name])
        if arr.dtype.kind not in "biuf":
            raise self.fail(name, f"has dtype {arr.dtype}, expected numbers")
        if arr.ndim != ndim:
            raise self.fail(name, f"has shape {arr.shape}, expected {ndim} dimensions")
        for axis, want in enumerate(shape):
            if want is not None and arr.shape[axis] != want:
                raise self.fail(name, f"has shape {arr.shape}, expected size {want} on axis {axis}")
        return arr

    def integers(self, name: str, arr: np.ndarray, lo: int, hi: int) -> np.ndarray:
        """`arr` as int64, every value an integer in `lo..hi`."""
        if arr.size and (np.any(arr != np.round(arr)) or arr.min() < lo or arr.max() > hi):
            raise self.fail(name, f"has values outside the integers {lo}..{hi}")
        return arr.astype(np.int64)


def _load_npz(path: str) -> _Arrays:
    if not os.path.exists(path):
        raise InputError(f"{path}: no such file")
    if not zipfile.is_zipfile(path):
        raise InputError(f"{path}: not an .npz file (not a zip archive)")
    try:
        with np.load(path, allow_pickle=False) as npz:
            return _Arrays(path, {k: npz[k] for k in npz.files})
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise InputError(f"{path}: not a readable .npz file ({exc})") from None


def _load_mat(path: str) -> _Arrays:
    import scipy.io

    if not os.path.exists(path):
        raise InputError(f"{path}: no such file")
    try:
        data = scipy.io.loadmat(path)
    except (ValueError, OSError, TypeError, NotImplementedError) as exc:
        raise InputError(f"{path}: not a readable MATLAB .mat file ({exc})") from None
    return _Arrays(path, {k: v for k, v in data.items() if not k.startswith("__")})


# ---------------------------------------------------------------------------------------------------------- import


def read_maps(
    path: str | os.PathLike, format: str, split: str | None = None, starts: int | None = None, seed: int = 0
) -> tuple[MapSet, dict]:
    """Read maps in another codebase's layout: `(MapSet, info)`; `info` says what was found and done.

    Args:
        format: 'kentsommer', 'avivt' or 'gppn'.
        split: kentsommer train|test|all (default test); gppn train|valid|test|all (default test); avivt
            train|test, the layout (default: the one the file has).
        starts: starts per map where the file has none (gppn, avivt's batched-only layout; default 7); files
            with trajectories take theirs and refuse `starts`.
        seed: seed of the drawn starts.

    Raises InputError naming the file and array for a missing array, a wrong shape, other polarity, a goal value
    or label out of range, or a path that is not a legal move sequence to the goal.
    """
    if format not in FORMATS:
        raise InputError(f"format must be one of {', '.join(FORMATS)}, got {format!r}")
    if split is not None and split not in SPLITS[format]:
        raise InputError(f"split must be one of {', '.join(SPLITS[format])} for format {format}, got {split!r}")
    if starts is not None and starts < 1:
        raise InputError(f"starts must be >= 1, got {starts}")
    path = str(path)
    if format == "kentsommer":
        maps, info = _read_kentsommer(_load_npz(path), split or "test", starts)
    elif format == "avivt":
        maps, info = _read_avivt(_load_mat(path), split, starts, seed)
    else:
        maps, info = _read_gppn(_load_npz(path), split or "test", starts, seed)
    return maps, {"format": format, "file": path, **info}


def import_maps(
    path: str | os.PathLike, format: str, split: str | None = None, starts: int | None = None, seed: int = 0
) -> MapSet:
    """`read_maps` without the info dict."""
    return read_maps(path, format, split, starts, seed)[0]


def _no_starts_option(f: _Arrays, starts: int | None) -> None:
    if starts is not None:
        raise InputError(f"{f.path}: has its own trajectories, whose first cells are the starts; starts cannot be set")


def _new_rows(rows: np.ndarray) -> np.ndarray:
    """`(m,)` bool: row i differs from row i - 1 (row 0 counts as new); compared in chunks to bound memory."""
    flat = rows.reshape(len(rows), int(np.prod(rows.shape[1:])))
    new = np.ones(len(flat), dtype=bool)
    for i in range(1, len(flat), _CHUNK):
        j = min(i + _CHUNK, len(flat))
        new[i:j] = (flat[i:j] != flat[i - 1 : j - 1]).any(axis=1)
    return new


def _decode_images(
    f: _Arrays,
    image_name: str,
    image: np.ndarray,
    value_name: str,
    value: np.ndarray,
    one_is_free: bool,
    goal_value: float,
    background: tuple[float, ...],
):
    """Obstacles `(k, s, s)` bool and goals `(k, 2)` from map images `(k, s, s)` and goal images `(k, s, s)`."""
    if image.size and not np.isin(image, (0, 1)).all():
        raise f.fail(image_name, "has values other than 0 and 1")
    is_goal = value == goal_value
    is_goal_flat = is_goal.reshape(len(value), value.shape[-2] * value.shape[-1])
    per_map = is_goal_flat.sum(axis=1)
    if np.any(per_map != 1):
        i = int(np.flatnonzero(per_map != 1)[0])
        raise f.fail(value_name, f"has {per_map[i]} cells equal to {goal_value:g} in map {i}, expected one goal")
    if not np.isin(value[~is_goal], background).all():
        raise f.fail(value_name, f"has values other than {goal_value:g} (goal) and {background} elsewhere")
    obstacles = image == 0 if one_is_free else image == 1
    flat_goal = np.argmax(is_goal_flat, axis=1)
    goals = np.stack(np.divmod(flat_goal, value.shape[-1]), axis=-1).astype(np.int64)
    if len(goals) and obstacles[np.arange(len(goals)), goals[:, 0], goals[:, 1]].any():
        meaning = "1 = free" if one_is_free else "1 = obstacle"
        raise f.fail(image_name, f"has the goal on an obstacle; expected {meaning}: is the polarity reversed?")
    return obstacles, goals


def _regroup(states: np.ndarray, labels: np.ndarray, new_map: np.ndarray):
    """Per-step samples -> trajectories: `(traj_first_sample (T,), cells, offsets)`.

    A trajectory ends where the next sample is not this state plus its labelled move (or is on another map);
    its last cell is the last sample's state plus its move (the goal, checked later).
    """
    m = len(states)
    if m == 0:
        return np.zeros(0, np.int64), np.zeros((0, 2), np.int64), np.zeros(1, np.int64)
    after = states + ACTION_DELTAS[labels]
    cont = (after[:-1] == states[1:]).all(axis=1) & ~new_map[1:]
    first = np.flatnonzero(np.r_[True, ~cont])
    last = np.r_[first[1:], m] - 1
    cells = np.insert(states, last + 1, after[last], axis=0)
    offsets = np.zeros(len(first) + 1, dtype=np.int64)
    np.cumsum(np.diff(np.r_[first, m]) + 1, out=offsets[1:])
    return first, cells, offsets


def _from_trajectories(
    f: _Arrays,
    cells_name: str,
    obstacles: np.ndarray,
    goals: np.ndarray,
    traj_map: np.ndarray,
    cells: np.ndarray,
    offsets: np.ndarray,
) -> tuple[MapSet, dict]:
    """A MapSet whose starts are the first cells of the given trajectories (`traj_map` non-decreasing)."""
    n, size = obstacles.shape[0], obstacles.shape[1]
    t = len(offsets) - 1
    lengths = np.diff(offsets)
    if np.any(lengths < 2):
        raise f.fail(cells_name, "has a trajectory of one cell (a start on the goal)")
    if cells.size and (cells.min() < 0 or cells.max() >= size):
        raise f.fail(cells_name, f"has a state outside the {size}x{size} grid")
    owner = traj_map[np.repeat(np.arange(t), lengths)]
    if obstacles[owner, cells[:, 0], cells[:, 1]].any():
        raise f.fail(cells_name, "has a state on an obstacle: is the polarity of the map images reversed?")
    step = np.abs(np.diff(cells, axis=0)).max(axis=1)
    inside = np.ones(len(step), dtype=bool)
    inside[offsets[1:-1] - 1] = False  # the last cell of a trajectory makes no move
    if np.any(inside & (step != 1)):
        raise f.fail(cells_name, "has a step that is not one of the 8 moves (is the action order different?)")
    if np.any(cells[offsets[1:] - 1] != goals[traj_map]):
        raise f.fail(cells_name, "has a trajectory that does not end at its map's goal")
    counts = np.bincount(traj_map, minlength=n)
    if np.any(counts == 0):
        raise f.fail(cells_name, f"has no trajectory for map {int(np.flatnonzero(counts == 0)[0])}")
    s = int(counts.max()) if n else 1
    rank = np.arange(t) - np.r_[0, np.cumsum(counts)[:-1]][traj_map]
    starts = np.repeat(goals[:, None, :], s, axis=1)  # padding: the goal, marked by start_counts
    starts[traj_map, rank] = cells[offsets[:-1]]
    dist, _ = shortest_distances(obstacles, goals)
    costs, own = expert_paths_from(dist, obstacles, goals, starts)
    theirs = PackedPaths(cells.astype(np.int16), offsets)
    optimal = np.abs(theirs.costs() - costs[traj_map, rank]) <= COST_TOL
    # The file's own path where it is optimal under vinadv's model (its labels kept), vinadv's where not.
    source = np.arange(n * s)
    slot = traj_map * s + rank
    source[slot[optimal]] = n * s + np.flatnonzero(optimal)
    expert = PackedPaths.concat([own, theirs]).take(source)
    maps = _padded_map_set(obstacles, goals, starts, costs, expert, counts, s, seed=-1)
    info = {
        "maps": n,
        "size": size,
        "trajectories": t,
        "starts_per_map": s,
        "maps_padded": int((counts < s).sum()),
        "file_paths_optimal": int(optimal.sum()),
        "expert_paths": "the file's own where optimal under vinadv's model (diagonal cost sqrt 2), "
        "vinadv's Dijkstra for the others",
    }
    return maps, info


def _padded_map_set(
    obstacles: np.ndarray,
    goals: np.ndarray,
    starts: np.ndarray,
    costs: np.ndarray,
    expert: PackedPaths,
    counts: np.ndarray,
    per_map: int,
    seed: int,
) -> MapSet:
    """The MapSet (corner cutting allowed) of imported maps whose map i has `counts[i]` real starts of `per_map`:
    `start_counts` marks the padding where some map has fewer."""
    return MapSet(
        obstacles=obstacles,
        goals=goals,
        starts=starts,
        expert_costs=costs,
        expert=expert,
        corner_cutting=True,
        seed=seed,
        start_counts=counts.astype(np.int64) if len(counts) and counts.min() < per_map else None,
    )


def _with_drawn_starts(obstacles: np.ndarray, goals: np.ndarray, k: int, seed: int) -> tuple[MapSet, dict]:
    """A MapSet with up to `k` distinct starts per map drawn uniformly (seeded) among cells at least
    MIN_START_MOVES moves from the goal; maps with fewer such cells keep all of them (padded), maps with none are
    left out and counted."""
    n, size = obstacles.shape[0], obstacles.shape[1]
    dist, moves = shortest_distances(obstacles, goals)
    eligible = (moves >= MIN_START_MOVES).reshape(n, size * size)
    keys = np.where(eligible, np.random.default_rng(seed).random(eligible.shape), np.inf)
    picks = np.argsort(keys, axis=1, kind="stable")[:, :k]
    counts = np.minimum(eligible.sum(axis=1), k)
    keep = counts > 0
    starts = np.stack(np.divmod(picks, size), axis=-1).astype(np.int64)
    pad = np.arange(k)[None, :] >= counts[:, None]
    starts[pad] = np.repeat(goals[:, None, :], k, axis=1)[pad]
    obstacles, goals, starts, dist, counts = obstacles[keep], goals[keep], starts[keep], dist[keep], counts[keep]
    costs, expert = expert_paths_from(dist, obstacles, goals, starts)
    maps = _padded_map_set(obstacles, goals, starts, costs, expert, counts, k, seed=int(seed))
    info = {
        "maps": int(keep.sum()),
        "size": size,
        "starts_per_map": k,
        "starts_seed": int(seed),
        "maps_padded": int((counts < k).sum()),
        "maps_left_out_no_start": int((~keep).sum()),
        "expert_paths": "vinadv's own (Dijkstra, diagonal cost sqrt 2), from starts drawn with the seed",
    }
    return maps, info


def _read_kentsommer(f: _Arrays, split: str, starts: int | None) -> tuple[MapSet, dict]:
    _no_starts_option(f, starts)
    parts = []
    for first in KENTSOMMER_SPLITS[split]:
        names = [f"arr_{first + i}" for i in range(4)]
        x = f.get(names[0], 4)
        m, s = x.shape[0], x.shape[2]
        if x.shape[1:] != (2, s, s):
            raise f.fail(names[0], f"has shape {x.shape}, expected (m, 2, s, s)")
        rows, cols, labels = (f.get(name, 2, (m, 1))[:, 0] for name in names[1:])
        rows = f.integers(names[1], rows, 0, s - 1)
        cols = f.integers(names[2], cols, 0, s - 1)
        labels = f.integers(names[3], labels, 0, 7)
        parts.append((names, x, np.stack([rows, cols], axis=1), labels))
    if len({p[1].shape[2] for p in parts}) > 1:
        raise f.fail("arr_4", f"has maps of size {parts[1][1].shape[2]}, the training maps {parts[0][1].shape[2]}")
    obstacles_l, goals_l, map_l, cells_l, lengths_l, n_before = [], [], [], [], [], 0
    for names, x, states, labels in parts:
        new_map = _new_rows(x)
        images = x[new_map]
        obstacles, goals = _decode_images(
            f,
            names[0],
            images[:, 0],
            names[0],
            images[:, 1],
            one_is_free=False,
            goal_value=GOAL_VALUE,
            background=(0, -1),
        )
        first, cells, offsets = _regroup(states, labels, new_map)
        obstacles_l.append(obstacles)
        goals_l.append(goals)
        map_l.append(np.cumsum(new_map)[first] - 1 + n_before)
        cells_l.append(cells)
        lengths_l.append(np.diff(offsets))
        n_before += len(obstacles)
    offsets = np.r_[0, np.cumsum(np.concatenate(lengths_l))].astype(np.int64)
    cells_name = "/".join(f"arr_{first + i}" for first in KENTSOMMER_SPLITS[split] for i in (1, 2, 3))
    maps, info = _from_trajectories(
        f,
        f"{cells_name} (S1, S2, labels)",
        np.concatenate(obstacles_l),
        np.concatenate(goals_l),
        np.concatenate(map_l).astype(np.int64),
        np.concatenate(cells_l),
        offsets,
    )
    return maps, {"split": split, "samples": int(sum(len(p[3]) for p in parts)), **info}


def _side(f: _Arrays, name: str, cells: int) -> int:
    s = int(round(np.sqrt(cells)))
    if s * s != cells or s < 3:
        raise f.fail(name, f"has rows of {cells} cells, not a square map of at least 3x3")
    return s


def _avivt_maps(
    f: _Arrays,
    prefix: str,
    im: np.ndarray,
    value: np.ndarray,
    s: int,
    order: str = "C",
    background: tuple[float, ...] = (0, -1),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The maps of avivt's sample rows: `im` and `value` (the arrays `{prefix}im_data` and `{prefix}value_data`,
    one `(s * s)` map image (1 = free) and goal image a row, unrolled in `order`). Returns which rows start a new
    map `(m,)` bool, and the obstacles `(k, s, s)` and goals `(k, 2)` of those k maps."""
    new_map = _new_rows(np.concatenate([im, value], axis=1))
    obstacles, goals = _decode_images(
        f,
        f"{prefix}im_data",
        im[new_map].reshape(-1, s, s, order=order),
        f"{prefix}value_data",
        value[new_map].reshape(-1, s, s, order=order),
        one_is_free=True,
        goal_value=GOAL_VALUE,
        background=background,
    )
    return new_map, obstacles, goals


def _read_avivt(f: _Arrays, split: str | None, starts: int | None, seed: int) -> tuple[MapSet, dict]:
    if split is None:
        split = "test" if f.has("all_im_data") else "train"
    if split == "test":
        _no_starts_option(f, starts)
        im = f.get("all_im_data", 2)
        n = im.shape[0]
        s = _side(f, "all_im_data", im.shape[1])
        value = f.get("all_value_data", 2, (n, s * s))
        paths = f.data.get("all_states_xy")
        if paths is None:
            raise InputError(f"{f.path}: array 'all_states_xy' is missing (has {sorted(f.data)[:12]})")
        paths = np.asarray(paths)
        if paths.dtype != object or paths.shape != (n, 1):
            raise f.fail("all_states_xy", f"has shape {paths.shape} and dtype {paths.dtype}, expected ({n}, 1) cells")
        cells_list = []
        for p in paths[:, 0]:  # one small array per map: (L, 2)
            p = np.asarray(p)
            if p.ndim != 2 or p.shape[1] != 2 or p.dtype.kind not in "iuf":
                raise f.fail("all_states_xy", f"holds a path of shape {p.shape}, expected (L, 2) cells")
            cells_list.append(p)
        # MATLAB unrolls column-major: a row of all_im_data is the map's columns one after another.
        new_map, obstacles, goals = _avivt_maps(f, "all_", im, value, s, order="F", background=(-1, 0))
        lengths = np.array([len(p) for p in cells_list], dtype=np.int64)
        offsets = np.r_[0, np.cumsum(lengths)].astype(np.int64)
        cells = f.integers("all_states_xy", np.concatenate(cells_list), 1, s) - 1 if n else np.zeros((0, 2), int)
        maps, info = _from_trajectories(f, "all_states_xy", obstacles, goals, np.cumsum(new_map) - 1, cells, offsets)
        return maps, {"layout": "test", **info}
    if f.has("im_data"):
        _no_starts_option(f, starts)
        im = f.get("im_data", 2)
        m = im.shape[0]
        s = _side(f, "im_data", im.shape[1])
        value = f.get("value_data", 2, (m, s * s))
        states = f.integers("state_xy_data", f.get("state_xy_data", 2, (m, 2)), 0, s - 1)
        labels = f.integers("label_data", f.get("label_data", 2, (m, 1))[:, 0], 0, 7)
        new_map, obstacles, goals = _avivt_maps(f, "", im, value, s)
        first, cells, offsets = _regroup(states, labels, new_map)
        maps, info = _from_trajectories(
            f, "state_xy_data with label_data", obstacles, goals, np.cumsum(new_map)[first] - 1, cells, offsets
        )
        return maps, {"layout": "train", "samples": m, **info}
    # Only the batched arrays: their states are shuffled in batches of 10, so trajectories cannot be recovered.
    im = f.get("batch_im_data", 2)
    s = _side(f, "batch_im_data", im.shape[1])
    value = f.get("batch_value_data", 2, (im.shape[0], s * s))
    _, obstacles, goals = _avivt_maps(f, "batch_", im, value, s)
    maps, info = _with_drawn_starts(obstacles, goals, 7 if starts is None else starts, seed)
    return maps, {"layout": "train (batched arrays only: shuffled states, starts drawn)", **info}


def _read_gppn(f: _Arrays, split: str, starts: int | None, seed: int) -> tuple[MapSet, dict]:
    obstacles_l, goals_l = [], []
    for first in GPPN_SPLITS[split]:
        names = [f"arr_{first + i}" for i in range(3)]
        mazes = f.get(names[0], 3)
        n, m = mazes.shape[0], mazes.shape[1]
        if mazes.shape[2] != m or m < 3:
            raise f.fail(names[0], f"has shape {mazes.shape}, expected (n, M, M) mazes")
        goal_maps = f.get(names[1], 4, (n, None, m, m))
        if goal_maps.shape[1] != 1:
            raise f.fail(
                names[1], f"has {goal_maps.shape[1]} orientations; vinadv plans without orientation (O = 1 only)"
            )
        policies = f.get(names[2], 5, (n, None, 1, m, m))
        if policies.shape[1] == 4:
            raise f.fail(
                names[2],
                "has 4 actions (GPPN's 'news' mechanism); vinadv plans with 8 moves only (--moves 4 is not supported)",
            )
        if policies.shape[1] != 8:
            raise f.fail(names[2], f"has {policies.shape[1]} actions, expected 8 (GPPN's 'moore' mechanism)")
        if not np.isin(goal_maps, (0, 1)).all():
            raise f.fail(names[1], "has values other than 0 and 1 (GPPN: 1.0 at the goal)")
        obstacles, goals = _decode_images(
            f, names[0], mazes, names[1], goal_maps[:, 0], one_is_free=True, goal_value=1, background=(0,)
        )
        if not np.isin(policies, (0, 1)).all():
            raise f.fail(names[2], "has values other than 0 and 1 (one-hot optimal actions)")
        # GPPN's policy, in vinadv's action order: every action it takes at a cell that can reach the goal must be
        # a legal move (what it holds at walls and walled-off cells is not defined, so not checked).
        ours = np.moveaxis(policies[:, :, 0], 1, -1)[..., np.argsort(GPPN_TO_VINADV)].astype(bool)
        reachable = np.isfinite(shortest_distances(obstacles, goals)[0])
        if np.any(ours & ~valid_moves(obstacles) & reachable[..., None]):
            raise f.fail(
                names[2],
                "takes an action into a wall or off the grid (is the action order or the maze polarity different?)",
            )
        obstacles_l.append(obstacles)
        goals_l.append(goals)
    obstacles, goals = np.concatenate(obstacles_l), np.concatenate(goals_l)
    maps, info = _with_drawn_starts(obstacles, goals, 7 if starts is None else starts, seed)
    return maps, {
        "split": split,
        "movement": "GPPN's diagonal cost 1 replaced by vinadv's sqrt 2 for the expert "
        "paths; GPPN's policies are checked, not used",
        **info,
    }


# ---------------------------------------------------------------------------------------------------------- export


def expert_steps(maps: MapSet) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every step of the real starts' expert paths: `(map (k,), states (k, 2), labels (k,), traj_of_map)`.

    `traj_of_map` `(T,)` is the map index of each real path, in order.
    """
    real = maps.start_mask.reshape(-1)
    idx = np.flatnonzero(real)
    lengths = maps.expert.lengths
    owner = np.repeat(np.arange(len(lengths)), lengths)
    cells = maps.expert.cells.astype(np.int64)
    is_step = np.ones(len(cells), dtype=bool)
    is_step[maps.expert.offsets[1:] - 1] = False  # the goal is not a sample
    is_step &= real[owner]
    moves = np.diff(cells, axis=0, append=cells[-1:])
    code = (moves[:, 0] + 1) * 3 + (moves[:, 1] + 1)
    label_of = np.full(9, -1)
    label_of[(ACTION_DELTAS[:, 0] + 1) * 3 + ACTION_DELTAS[:, 1] + 1] = np.arange(len(ACTION_DELTAS))
    return owner[is_step] // maps.n_starts, cells[is_step], label_of[code[is_step]], idx // maps.n_starts


def _goal_images(maps: MapSet, idx: np.ndarray, background: float, goal: float, dtype) -> np.ndarray:
    out = np.full((len(idx), maps.size, maps.size), background, dtype=dtype)
    out[np.arange(len(idx)), maps.goals[idx, 0], maps.goals[idx, 1]] = goal
    return out


def unit_cost_distances(obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """Moves to the goal when every Moore move costs 1 (GPPN's model), corner cutting allowed: `(n, M, M)`
    float64, inf where the goal cannot be reached."""
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    dist = np.empty(obstacles.shape)
    moves = np.empty(obstacles.shape, dtype=np.int32)
    if len(obstacles):
        _dijkstra_batch(
            obstacles,
            np.ascontiguousarray(goals, np.int64),
            True,
            ACTION_DELTAS,
            np.ones(len(ACTION_DELTAS)),
            dist,
            moves,
        )
    return dist


def _unit_cost_policies(maps: MapSet) -> np.ndarray:
    """GPPN's optimal policies `(n, 8, 1, M, M)` float32 one-hot: Moore moves all of cost 1, corner cutting
    allowed, the lowest GPPN action index among the optimal ones; none at the goal, walls and unreachable cells."""
    obstacles = maps.obstacles
    dist = unit_cost_distances(obstacles, maps.goals)
    n, m = maps.size, maps.size
    padded = np.full((len(dist), n + 2, m + 2), np.inf)
    padded[:, 1:-1, 1:-1] = dist
    legal = valid_moves(obstacles)
    target = np.where(np.isfinite(dist) & (dist > 0), dist - 1, np.nan)
    optimal = np.zeros(dist.shape + (8,), dtype=bool)
    for g, a in enumerate(GPPN_TO_VINADV):
        dr, dc = ACTION_DELTAS[a]
        optimal[..., g] = legal[..., a] & (padded[:, 1 + dr : 1 + dr + n, 1 + dc : 1 + dc + m] == target)
    first = np.argmax(optimal, axis=-1)
    one_hot = (np.arange(8) == first[..., None]) & optimal.any(axis=-1, keepdims=True)
    return np.moveaxis(one_hot, -1, 1)[:, :, None].astype(np.float32)


def export_maps(maps: MapSet, path: str | os.PathLike, format: str, split: str | None = None) -> dict:
    """Write `maps` in another codebase's layout; returns a summary dict.

    kentsommer: the samples (every step of every real start's expert path) go to `split` (train|test, default
    test), the other split is written empty; goal prior 10 at the goal, 0 elsewhere. avivt: `split` test (default)
    writes the test layout (one row per real start), train the per-sample training arrays (no batched arrays).
    gppn: the mazes go to `split` (train|valid|test, default test), the others are empty; the policies are
    GPPN's (diagonal cost 1).
    """
    if format not in FORMATS:
        raise InputError(f"format must be one of {', '.join(FORMATS)}, got {format!r}")
    allowed = tuple(s for s in SPLITS[format] if s != "all")
    split = split or "test"
    if split not in allowed:
        raise InputError(f"split must be one of {', '.join(allowed)} to export format {format}, got {split!r}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    s = maps.size
    if format == "gppn":
        arrays = [
            np.zeros((0, s, s), np.float32),
            np.zeros((0, 1, s, s), np.float32),
            np.zeros((0, 8, 1, s, s), np.float32),
        ] * 3
        at = {"train": 0, "valid": 3, "test": 6}[split]
        idx = np.arange(len(maps))
        arrays[at : at + 3] = [
            (~maps.obstacles).astype(np.float32),
            _goal_images(maps, idx, 0, 1, np.float32)[:, None],
            _unit_cost_policies(maps),
        ]
        with open(path, "wb") as fh:
            np.savez_compressed(fh, *arrays)
        return {"format": format, "out": str(path), "split": split, "maps": len(maps)}
    map_of_step, states, labels, traj_map = expert_steps(maps)
    if format == "kentsommer":
        x = np.zeros((len(states), 2, s, s), np.float32)
        x[:, 0] = maps.obstacles[map_of_step]
        x[np.arange(len(states)), 1, maps.goals[map_of_step, 0], maps.goals[map_of_step, 1]] = GOAL_VALUE
        filled = [x, states[:, :1], states[:, 1:], labels[:, None]]
        empty = [np.zeros((0, 2, s, s), np.float32)] + [np.zeros((0, 1), np.int64)] * 3
        arrays = filled + empty if split == "train" else empty + filled
        with open(path, "wb") as fh:
            np.savez_compressed(fh, *arrays)
        return {"format": format, "out": str(path), "split": split, "maps": len(maps), "samples": len(states)}
    import scipy.io

    small = np.uint8 if s <= 255 else np.uint16
    if split == "test":
        free = (~maps.obstacles[traj_map]).reshape(len(traj_map), -1, order="F").astype(np.uint8)
        value = _goal_images(maps, traj_map, -1, GOAL_VALUE, np.int16).reshape(len(traj_map), -1, order="F")
        real = np.flatnonzero(maps.start_mask.reshape(-1))
        cells = np.empty((len(real), 1), dtype=object)
        for row, k in enumerate(real):  # a MATLAB cell array: one (L, 2) path per row
            cells[row, 0] = (maps.expert[k] + 1).astype(small)
        data = {"all_im_data": free, "all_value_data": value, "all_states_xy": cells}
    else:
        data = {
            "im_data": (~maps.obstacles[map_of_step]).reshape(len(states), -1).astype(np.uint8),
            "value_data": _goal_images(maps, map_of_step, 0, GOAL_VALUE, np.uint8).reshape(len(states), -1),
            "state_xy_data": states.astype(small),
            "label_data": labels[:, None].astype(np.uint8),
        }
    scipy.io.savemat(str(path), data, do_compression=True)
    return {
        "format": format,
        "out": str(path),
        "split": split,
        "maps": len(maps),
        "rows" if split == "test" else "samples": len(traj_map) if split == "test" else len(states),
    }
