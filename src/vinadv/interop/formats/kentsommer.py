"""The kentsommer layout (the common PyTorch port of the VIN, `.npz`).

`arr_0..3` train and `arr_4..7` test, each X `(m, 2, s, s)` (channel 0: 1 = obstacle; channel 1: goal prior, 10 at
the goal, 0 or -1 elsewhere), S1 `(m, 1)` row, S2 `(m, 1)` col, labels `(m, 1)` in vinadv's action order
N,S,E,W,NE,NW,SE,SW. One sample per step of an expert trajectory, the goal itself not a sample.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vinadv.grid.mapset import MapSet
from vinadv.interop.formats.files import ForeignArrays, load_npz
from vinadv.interop.formats.samples import (
    GOAL_VALUE,
    decode_images,
    expert_steps,
    from_trajectories,
    new_rows,
    refuse_starts,
    regroup,
)

#: the splits read, and the index of the first array (X) of each of their parts
SPLITS = {"train": (0,), "test": (4,), "all": (0, 4)}


def read(path: str, split: str | None, starts: int | None, seed: int) -> tuple[MapSet, dict]:
    """The maps of `split` (default test) of the file at `path`: `(MapSet, info)`. Its trajectories bring their
    starts, so `starts` is refused; `seed` is not used."""
    return _read(load_npz(path), split or "test", starts)


def _read(f: ForeignArrays, split: str, starts: int | None) -> tuple[MapSet, dict]:
    refuse_starts(f, starts)
    parts = []
    for first in SPLITS[split]:
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
        new_map = new_rows(x)
        images = x[new_map]
        obstacles, goals = decode_images(
            f,
            names[0],
            images[:, 0],
            names[0],
            images[:, 1],
            one_is_free=False,
            goal_value=GOAL_VALUE,
            background=(0, -1),
        )
        first, cells, offsets = regroup(states, labels, new_map)
        obstacles_l.append(obstacles)
        goals_l.append(goals)
        map_l.append(np.cumsum(new_map)[first] - 1 + n_before)
        cells_l.append(cells)
        lengths_l.append(np.diff(offsets))
        n_before += len(obstacles)
    offsets = np.r_[0, np.cumsum(np.concatenate(lengths_l))].astype(np.int64)
    cells_name = "/".join(f"arr_{first + i}" for first in SPLITS[split] for i in (1, 2, 3))
    maps, info = from_trajectories(
        f,
        f"{cells_name} (S1, S2, labels)",
        np.concatenate(obstacles_l),
        np.concatenate(goals_l),
        np.concatenate(map_l).astype(np.int64),
        np.concatenate(cells_l),
        offsets,
    )
    return maps, {"split": split, "samples": int(sum(len(p[3]) for p in parts)), **info}


def write(maps: MapSet, path: Path, split: str) -> dict:
    """Write the samples (every step of every real start's expert path) to `split` (train|test), the other split
    empty; goal prior 10 at the goal, 0 elsewhere. Returns the counts written: maps, samples."""
    s = maps.size
    map_of_step, states, labels, _ = expert_steps(maps)
    x = np.zeros((len(states), 2, s, s), np.float32)
    x[:, 0] = maps.obstacles[map_of_step]
    x[np.arange(len(states)), 1, maps.goals[map_of_step, 0], maps.goals[map_of_step, 1]] = GOAL_VALUE
    filled = [x, states[:, :1], states[:, 1:], labels[:, None]]
    empty = [np.zeros((0, 2, s, s), np.float32)] + [np.zeros((0, 1), np.int64)] * 3
    arrays = filled + empty if split == "train" else empty + filled
    with open(path, "wb") as fh:
        np.savez_compressed(fh, *arrays)
    return {"maps": len(maps), "samples": len(states)}
