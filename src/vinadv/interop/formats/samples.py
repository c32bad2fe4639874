"""What the three layouts share: foreign samples regrouped into maps and trajectories, the file's expert paths
reconciled with vinadv's, drawn starts, and the per-step samples of a MapSet to write.

Samples are regrouped into maps (a new map starts where the image or goal changes from the previous sample/row)
and trajectories (a new one starts where a state is not the previous state plus its labelled move). A map's
starts are the first cells of its trajectories (a trajectory from a cell an earlier trajectory of its map started
from is dropped, counted in `trajectories_repeated_start`: a maps file's starts differ); expert costs are
vinadv's (Dijkstra, diagonal cost sqrt 2, corner cutting allowed as in all three codebases) and the expert paths
the file's own where they are optimal under that model (so their labels are kept), vinadv's where not; how many
were optimal is reported.
Maps with fewer trajectories than others are padded explicitly (`MapSet.start_counts`).
"""

from __future__ import annotations

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.actions import ACTION_DELTAS
from vinadv.grid.generator import MIN_START_MOVES
from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import DEFAULT_MOVES, move_model
from vinadv.grid.paths import PackedPaths
from vinadv.grid.selection import smallest_first
from vinadv.grid.shortest_paths import COST_TOL, expert_paths_from, shortest_distances
from vinadv.interop.formats.files import ForeignArrays

GOAL_VALUE = 10  # the goal prior of the kentsommer port and avivt's files
_CHUNK = 4096


def refuse_starts(f: ForeignArrays, starts: int | None) -> None:
    """Refuse a `starts` option for file `f`, whose trajectories bring their own starts."""
    if starts is not None:
        raise InputError(f"{f.path}: has its own trajectories, whose first cells are the starts; starts cannot be set")


def new_rows(rows: np.ndarray) -> np.ndarray:
    """`(m,)` bool: row i differs from row i - 1 (row 0 counts as new); compared in chunks to bound memory."""
    flat = rows.reshape(len(rows), int(np.prod(rows.shape[1:])))
    new = np.ones(len(flat), dtype=bool)
    for i in range(1, len(flat), _CHUNK):
        j = min(i + _CHUNK, len(flat))
        new[i:j] = (flat[i:j] != flat[i - 1 : j - 1]).any(axis=1)
    return new


def decode_images(
    f: ForeignArrays,
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


def regroup(states: np.ndarray, labels: np.ndarray, new_map: np.ndarray):
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


def from_trajectories(
    f: ForeignArrays,
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
    # a trajectory from a cell an earlier trajectory of its map started from: a maps file's starts differ, so the
    # first is kept and the repeat dropped (counted), instead of writing a file `MapSet.load` refuses
    first = cells[offsets[:-1]]
    key = (traj_map * size + first[:, 0]) * size + first[:, 1]
    keep = np.zeros(t, dtype=bool)
    keep[np.unique(key, return_index=True)[1]] = True
    repeated = int(t - keep.sum())
    if repeated:
        kept = PackedPaths(cells.astype(np.int16), offsets).take(np.flatnonzero(keep))
        cells, offsets, traj_map = kept.cells.astype(np.int64), kept.offsets, traj_map[keep]
        t = len(offsets) - 1
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
    maps = padded_map_set(obstacles, goals, starts, costs, expert, counts, s, seed=-1)
    info = {
        "maps": n,
        "size": size,
        "trajectories": t,
        "trajectories_repeated_start": repeated,
        "starts_per_map": s,
        "maps_padded": int((counts < s).sum()),
        "file_paths_optimal": int(optimal.sum()),
        "expert_paths": "the file's own where optimal under vinadv's model (diagonal cost sqrt 2), "
        "vinadv's Dijkstra for the others",
    }
    return maps, info


def padded_map_set(
    obstacles: np.ndarray,
    goals: np.ndarray,
    starts: np.ndarray,
    costs: np.ndarray,
    expert: PackedPaths,
    counts: np.ndarray,
    per_map: int,
    seed: int,
    moves: str = DEFAULT_MOVES,
) -> MapSet:
    """The MapSet (corner cutting allowed, movement model `moves`) of imported maps whose map i has `counts[i]` real
    starts of `per_map`: `start_counts` marks the padding where some map has fewer."""
    return MapSet(
        obstacles=obstacles,
        goals=goals,
        starts=starts,
        expert_costs=costs,
        expert=expert,
        corner_cutting=True,
        seed=seed,
        start_counts=counts.astype(np.int64) if len(counts) and counts.min() < per_map else None,
        moves=moves,
    )


def with_drawn_starts(
    obstacles: np.ndarray, goals: np.ndarray, k: int, seed: int, moves: str = DEFAULT_MOVES
) -> tuple[MapSet, dict]:
    """A MapSet of the movement model `moves` with up to `k` distinct starts per map drawn uniformly (seeded) among
    cells at least MIN_START_MOVES moves from the goal; maps with fewer such cells keep all of them (padded), maps
    with none are left out and counted."""
    n, size = obstacles.shape[0], obstacles.shape[1]
    dist, counts_of_moves = shortest_distances(obstacles, goals, True, moves)
    eligible = (counts_of_moves >= MIN_START_MOVES).reshape(n, size * size)
    keys = np.where(eligible, np.random.default_rng(seed).random(eligible.shape), np.inf)
    picks = smallest_first(keys, k)
    counts = np.minimum(eligible.sum(axis=1), k)
    keep = counts > 0
    starts = np.stack(np.divmod(picks, size), axis=-1).astype(np.int64)
    pad = np.arange(k)[None, :] >= counts[:, None]
    starts[pad] = np.repeat(goals[:, None, :], k, axis=1)[pad]
    obstacles, goals, starts, dist, counts = obstacles[keep], goals[keep], starts[keep], dist[keep], counts[keep]
    costs, expert = expert_paths_from(dist, obstacles, goals, starts, True, moves)
    maps = padded_map_set(obstacles, goals, starts, costs, expert, counts, k, seed=int(seed), moves=moves)
    info = {
        "maps": int(keep.sum()),
        "size": size,
        "starts_per_map": k,
        "starts_seed": int(seed),
        "maps_padded": int((counts < k).sum()),
        "maps_left_out_no_start": int((~keep).sum()),
        "expert_paths": f"vinadv's own (Dijkstra, {move_model(moves).name} moves: {move_model(moves).description}), "
        "from starts drawn with the seed",
    }
    return maps, info


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


def goal_images(maps: MapSet, idx: np.ndarray, background: float, goal: float, dtype) -> np.ndarray:
    """The goal images of maps `idx`: `(len(idx), M, M)` of `dtype`, `goal` at the goal, `background` elsewhere."""
    out = np.full((len(idx), maps.size, maps.size), background, dtype=dtype)
    out[np.arange(len(idx)), maps.goals[idx, 0], maps.goals[idx, 1]] = goal
    return out
