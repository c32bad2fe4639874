"""The GPPN layout (`.npz`, the Gated Path Planning Network's data).

`arr_0..8` = train, valid, test x (mazes `(n, M, M)` 1 = free, goal maps `(n, O, M, M)` 1.0 at the goal, optimal
policies `(n, A, O, M, M)` one-hot, Moore order N,E,W,S,NE,NW,SE,SW, diagonal cost 1). No starts: they are drawn,
seeded.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vinadv.grid.actions import ACTION_DELTAS
from vinadv.grid.mapset import MapSet
from vinadv.grid.shortest_paths import dijkstra_batch, shortest_distances, valid_moves
from vinadv.interop.formats.files import ForeignArrays, load_npz
from vinadv.interop.formats.samples import decode_images, goal_images, with_drawn_starts

#: GPPN's Moore order N,E,W,S,NE,NW,SE,SW as vinadv action indices (vinadv: N,S,E,W,NE,NW,SE,SW).
GPPN_TO_VINADV = np.array([0, 2, 3, 1, 4, 5, 6, 7])
#: the splits read, and the index of the first array (mazes) of each of their parts
SPLITS = {"train": (0,), "valid": (3,), "test": (6,), "all": (0, 3, 6)}


def read(path: str, split: str | None, starts: int | None, seed: int) -> tuple[MapSet, dict]:
    """The maps of `split` (default test) of the file at `path`, with `starts` (default 7) drawn per map with
    `seed`: `(MapSet, info)`."""
    return _read(load_npz(path), split or "test", starts, seed)


def _read(f: ForeignArrays, split: str, starts: int | None, seed: int) -> tuple[MapSet, dict]:
    obstacles_l, goals_l = [], []
    for first in SPLITS[split]:
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
        obstacles, goals = decode_images(
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
    maps, info = with_drawn_starts(obstacles, goals, 7 if starts is None else starts, seed)
    return maps, {
        "split": split,
        "movement": "GPPN's diagonal cost 1 replaced by vinadv's sqrt 2 for the expert "
        "paths; GPPN's policies are checked, not used",
        **info,
    }


def unit_cost_distances(obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """Moves to the goal when every Moore move costs 1 (GPPN's model), corner cutting allowed: `(n, M, M)`
    float64, inf where the goal cannot be reached."""
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    dist = np.empty(obstacles.shape)
    moves = np.empty(obstacles.shape, dtype=np.int32)
    if len(obstacles):
        dijkstra_batch(
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


def write(maps: MapSet, path: Path, split: str) -> dict:
    """Write the mazes to `split` (train|valid|test), the others empty, with GPPN's optimal policies (diagonal cost
    1). Returns the counts written: maps."""
    s = maps.size
    arrays = [
        np.zeros((0, s, s), np.float32),
        np.zeros((0, 1, s, s), np.float32),
        np.zeros((0, 8, 1, s, s), np.float32),
    ] * 3
    at = SPLITS[split][0]
    idx = np.arange(len(maps))
    arrays[at : at + 3] = [
        (~maps.obstacles).astype(np.float32),
        goal_images(maps, idx, 0, 1, np.float32)[:, None],
        _unit_cost_policies(maps),
    ]
    with open(path, "wb") as fh:
        np.savez_compressed(fh, *arrays)
    return {"maps": len(maps)}
