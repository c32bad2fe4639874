"""The avivt layout (the VIN authors' MATLAB `.mat` files, read and written with scipy.io).

The test layout: `all_im_data (n, s*s)` (1 = free), `all_value_data (n, s*s)` (10 at the goal, -1 elsewhere),
`all_states_xy (n, 1)` cells of `(L, 2)` 1-based `(row, col)` optimal paths, images unrolled in column-major
(MATLAB) order. The training layout, per sample: `im_data`, `value_data` (10 at the goal, 0 elsewhere),
`state_xy_data (m, 2)` 0-based `(row, col)`, `label_data (m, 1)` in vinadv's action order, images unrolled in
row-major order, plus the same samples shuffled into batches of 10 (`batch_im_data`, `batch_value_data`,
`state_x_data`, `state_y_data`, `batch_label_data`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.interop.formats.files import ForeignArrays, load_mat
from vinadv.interop.formats.samples import (
    GOAL_VALUE,
    decode_images,
    expert_steps,
    from_trajectories,
    goal_images,
    new_rows,
    refuse_starts,
    regroup,
    with_drawn_starts,
)

#: the layouts read and written (`split`): the file's own one when reading without a split
SPLITS = ("train", "test")


def read(path: str, split: str | None, starts: int | None, seed: int) -> tuple[MapSet, dict]:
    """The maps of the file at `path` in layout `split` (default: the one the file has): `(MapSet, info)`.
    `starts` per map (default 7) and `seed` draw the starts of a file with only the batched arrays; files with
    trajectories refuse `starts`."""
    return _read(load_mat(path), split, starts, seed)


def _side(f: ForeignArrays, name: str, cells: int) -> int:
    """The side s of the square maps whose rows in array `name` have `cells` = s * s cells."""
    s = int(round(np.sqrt(cells)))
    if s * s != cells or s < 3:
        raise f.fail(name, f"has rows of {cells} cells, not a square map of at least 3x3")
    return s


def _maps_of_rows(
    f: ForeignArrays,
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
    new_map = new_rows(np.concatenate([im, value], axis=1))
    obstacles, goals = decode_images(
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


#: the arrays of each layout the file may have: the test layout, the training layout's per-sample arrays and its
#: batches (a training file may have either or both)
TEST_ARRAYS = ("all_im_data", "all_value_data", "all_states_xy")
SAMPLE_ARRAYS = ("im_data", "value_data", "state_xy_data", "label_data")
BATCH_ARRAYS = ("batch_im_data", "batch_value_data", "state_x_data", "state_y_data", "batch_label_data")


def _layout(f: ForeignArrays) -> str:
    """The layout the file looks like, test or train: the one with the most of its arrays, so that a file missing
    one array is told which (of its layout) is missing. InputError when it has none of either."""
    test = sum(f.has(name) for name in TEST_ARRAYS)
    train = max(sum(f.has(name) for name in SAMPLE_ARRAYS), sum(f.has(name) for name in BATCH_ARRAYS))
    if not test and not train:
        raise InputError(
            f"{f.path}: none of the arrays of avivt's layouts (test: {', '.join(TEST_ARRAYS)}; train: "
            f"{', '.join(SAMPLE_ARRAYS)} or {', '.join(BATCH_ARRAYS)}); has {sorted(f.data)[:12]}"
        )
    return "test" if test >= train else "train"


def _read(f: ForeignArrays, split: str | None, starts: int | None, seed: int) -> tuple[MapSet, dict]:
    if split is None:
        split = _layout(f)
    if split == "test":
        refuse_starts(f, starts)
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
        new_map, obstacles, goals = _maps_of_rows(f, "all_", im, value, s, order="F", background=(-1, 0))
        lengths = np.array([len(p) for p in cells_list], dtype=np.int64)
        offsets = np.r_[0, np.cumsum(lengths)].astype(np.int64)
        cells = f.integers("all_states_xy", np.concatenate(cells_list), 1, s) - 1 if n else np.zeros((0, 2), int)
        maps, info = from_trajectories(f, "all_states_xy", obstacles, goals, np.cumsum(new_map) - 1, cells, offsets)
        return maps, {"layout": "test", **info}
    if any(f.has(name) for name in SAMPLE_ARRAYS):  # the per-sample arrays, or some of them (one renamed)
        refuse_starts(f, starts)
        im = f.get("im_data", 2)
        m = im.shape[0]
        s = _side(f, "im_data", im.shape[1])
        value = f.get("value_data", 2, (m, s * s))
        states = f.integers("state_xy_data", f.get("state_xy_data", 2, (m, 2)), 0, s - 1)
        labels = f.integers("label_data", f.get("label_data", 2, (m, 1))[:, 0], 0, 7)
        new_map, obstacles, goals = _maps_of_rows(f, "", im, value, s)
        first, cells, offsets = regroup(states, labels, new_map)
        maps, info = from_trajectories(
            f, "state_xy_data with label_data", obstacles, goals, np.cumsum(new_map)[first] - 1, cells, offsets
        )
        return maps, {"layout": "train", "samples": m, **info}
    # Only the batched arrays: their states are shuffled in batches of 10, so trajectories cannot be recovered.
    im = f.get("batch_im_data", 2)
    s = _side(f, "batch_im_data", im.shape[1])
    value = f.get("batch_value_data", 2, (im.shape[0], s * s))
    _, obstacles, goals = _maps_of_rows(f, "batch_", im, value, s)
    maps, info = with_drawn_starts(obstacles, goals, 7 if starts is None else starts, seed)
    return maps, {"layout": "train (batched arrays only: shuffled states, starts drawn)", **info}


def write(maps: MapSet, path: Path, split: str) -> dict:
    """Write the test layout (`split` test: one row per real start) or the per-sample training arrays (train; no
    batched arrays). Returns the counts written: maps, and rows (test) or samples (train)."""
    import scipy.io

    s = maps.size
    map_of_step, states, labels, traj_map = expert_steps(maps)
    small = np.uint8 if s <= 255 else np.uint16
    if split == "test":
        free = (~maps.obstacles[traj_map]).reshape(len(traj_map), -1, order="F").astype(np.uint8)
        value = goal_images(maps, traj_map, -1, GOAL_VALUE, np.int16).reshape(len(traj_map), -1, order="F")
        real = np.flatnonzero(maps.start_mask.reshape(-1))
        cells = np.empty((len(real), 1), dtype=object)
        for row, k in enumerate(real):  # a MATLAB cell array: one (L, 2) path per row
            cells[row, 0] = (maps.expert[k] + 1).astype(small)
        data = {"all_im_data": free, "all_value_data": value, "all_states_xy": cells}
    else:
        data = {
            "im_data": (~maps.obstacles[map_of_step]).reshape(len(states), -1).astype(np.uint8),
            "value_data": goal_images(maps, map_of_step, 0, GOAL_VALUE, np.uint8).reshape(len(states), -1),
            "state_xy_data": states.astype(small),
            "label_data": labels[:, None].astype(np.uint8),
        }
    scipy.io.savemat(str(path), data, do_compression=True)
    if split == "test":
        return {"maps": len(maps), "rows": len(traj_map)}
    return {"maps": len(maps), "samples": len(states)}
