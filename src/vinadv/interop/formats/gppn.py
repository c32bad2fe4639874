"""The GPPN layout (`.npz`, the Gated Path Planning Network's data).

`arr_0..8` = train, valid, test x (mazes `(n, M, M)` 1 = free, goal maps `(n, O, M, M)` 1.0 at the goal, optimal
policies `(n, A, O, M, M)` one-hot, order N,E,W,S,NE,NW,SE,SW). GPPN's two mechanisms are vinadv's movement models
(`vinadv.grid.moves`): `moore` (A = 8, every move costs 1, a diagonal needs only its destination free) and `news`
(A = 4, N,E,W,S, cost 1). No starts: they are drawn, seeded.

What the import checks: the arrays' shapes and values (0/1 mazes, one goal per map on a free cell, one-hot
policies), and that at every cell that can reach the goal, the goal excepted, the file's action is an optimal move
of the file's model (GPPN's generator writes arbitrary actions at the goal, at walls and at walled-off cells, so
those are not read). The maps keep GPPN's model: `moore` for 8 actions, `news` for 4; `moves` may say `octile` for
an 8-action file (its expert costs are then vinadv's sqrt 2, the file's policy checked as `moore`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import move_model
from vinadv.grid.shortest_paths import optimal_actions, shortest_distances
from vinadv.interop.formats.files import ForeignArrays, load_npz
from vinadv.interop.formats.samples import decode_images, goal_images, with_drawn_starts

#: GPPN's Moore order N,E,W,S,NE,NW,SE,SW as vinadv action indices (vinadv: N,S,E,W,NE,NW,SE,SW); its NEWS order
#: is the first four.
GPPN_TO_VINADV = np.array([0, 2, 3, 1, 4, 5, 6, 7])
#: GPPN's mechanism of each action count: the movement model its files are read as
MECHANISMS = {8: "moore", 4: "news"}
#: the splits read, and the index of the first array (mazes) of each of their parts
SPLITS = {"train": (0,), "valid": (3,), "test": (6,), "all": (0, 3, 6)}


def read(path: str, split: str | None, starts: int | None, seed: int, moves: str | None = None) -> tuple[MapSet, dict]:
    """The maps of `split` (default test) of the file at `path`, with `starts` (default 7) drawn per map with
    `seed`, of the file's movement model (`moves` None) or `moves`: `(MapSet, info)`."""
    return _read(load_npz(path), split or "test", starts, seed, moves)


def _read(f: ForeignArrays, split: str, starts: int | None, seed: int, moves: str | None) -> tuple[MapSet, dict]:
    obstacles_l, goals_l, found = [], [], set()
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
        mechanism = MECHANISMS.get(policies.shape[1])
        if mechanism is None:
            raise f.fail(names[2], f"has {policies.shape[1]} actions, expected 8 (GPPN's moore) or 4 (GPPN's news)")
        if n == 0:  # an empty split says nothing of the file's model
            obstacles_l.append(np.zeros((0, m, m), bool))
            goals_l.append(np.zeros((0, 2), np.int64))
            continue
        found.add(mechanism)
        if moves is not None and move_model(moves).n_actions != policies.shape[1]:
            raise f.fail(
                names[2],
                f"has {policies.shape[1]} actions (GPPN's {mechanism}); moves {moves!r} has "
                f"{move_model(moves).n_actions}",
            )
        obstacles, goals = decode_gppn_arrays(f, names, mazes, goal_maps, policies, mechanism)
        obstacles_l.append(obstacles)
        goals_l.append(goals)
    if len(found) > 1:
        raise f.fail(f"arr_{SPLITS[split][-1] + 2}", "has another action count than the split before it")
    model = moves if moves is not None else (found.pop() if found else "moore")
    obstacles, goals = np.concatenate(obstacles_l), np.concatenate(goals_l)
    maps, info = with_drawn_starts(obstacles, goals, 7 if starts is None else starts, seed, move_model(model).name)
    return maps, {
        "split": split,
        "movement": f"{maps.moves} ({move_model(maps.moves).description}); the file's policies are checked "
        "(an optimal move at every cell that reaches the goal, the goal excepted), not used",
        **info,
    }


def decode_gppn_arrays(
    f: ForeignArrays,
    names: list[str],
    mazes: np.ndarray,
    goal_maps: np.ndarray,
    policies: np.ndarray,
    mechanism: str,
) -> tuple[np.ndarray, np.ndarray]:
    """`(obstacles (n, M, M), goals (n, 2))` of GPPN's arrays, the ones the MP dataset keeps too: mazes `(n, M, M)`
    (1 = free), goal maps `(n, 1, M, M)` (1 at the goal) and one-hot policies `(n, A, 1, M, M)` of `mechanism`,
    the arrays `names` of `f`. Refused (one line naming the array) where a value is not GPPN's or a policy's action
    is not optimal (`check_policies`)."""
    if not np.isin(goal_maps, (0, 1)).all():
        raise f.fail(names[1], "has values other than 0 and 1 (GPPN: 1.0 at the goal)")
    obstacles, goals = decode_images(
        f, names[0], mazes, names[1], goal_maps[:, 0], one_is_free=True, goal_value=1, background=(0,)
    )
    if not np.isin(policies, (0, 1)).all() or np.any(policies.sum(axis=1) > 1):
        raise f.fail(names[2], "has values other than one-hot 0 and 1 (one optimal action per cell)")
    check_policies(f, names[2], obstacles, goals, policies[:, :, 0], mechanism)
    return obstacles, goals


def check_policies(
    f: ForeignArrays, name: str, obstacles: np.ndarray, goals: np.ndarray, policies: np.ndarray, mechanism: str
) -> None:
    """Refuse (one line naming the array) a policy `(n, A, M, M)` whose action, at a cell that can reach the goal
    (the goal excepted), is not an optimal move of GPPN's `mechanism` (corner cutting allowed, as GPPN's)."""
    a = policies.shape[1]
    ours = np.zeros(policies.shape[:1] + policies.shape[2:] + (a,), dtype=bool)
    ours[..., GPPN_TO_VINADV[:a]] = np.moveaxis(policies, 1, -1).astype(bool)
    dist, _ = shortest_distances(obstacles, goals, True, mechanism)
    optimal = optimal_actions(dist, obstacles, True, mechanism)[..., :a]
    read = np.isfinite(dist) & (dist > 0)  # reaches the goal, is not the goal
    bad = read & ~(ours & optimal).any(axis=-1)
    if bad.any():
        i, r, c = (int(v) for v in np.argwhere(bad)[0])
        held = "no action" if not ours[i, r, c].any() else f"GPPN action {int(np.argmax(policies[i, :, r, c]))}"
        raise f.fail(
            name,
            f"has {held} at map {i} cell ({r}, {c}), not an optimal {mechanism} move to the goal (is the action "
            "order, the maze polarity or the mechanism different?)",
        )


def unit_cost_distances(obstacles: np.ndarray, goals: np.ndarray, moves: str = "moore") -> np.ndarray:
    """Moves to the goal when every move costs 1 (GPPN's models: `moore`, or `news`), corner cutting allowed:
    `(n, M, M)` float64, inf where the goal cannot be reached."""
    return shortest_distances(obstacles, goals, True, moves)[0]


def unit_cost_policies(maps: MapSet) -> np.ndarray:
    """GPPN's optimal policies `(n, A, 1, M, M)` float32 one-hot: the maps' `moore` or `news` moves (`moore` for
    `octile` maps: GPPN has no sqrt 2), all of cost 1, corner cutting allowed, the lowest GPPN action index among
    the optimal ones; none at the goal, walls and unreachable cells."""
    mechanism = "news" if maps.moves == "news" else "moore"
    a = move_model(mechanism).n_actions
    dist = unit_cost_distances(maps.obstacles, maps.goals, mechanism)
    optimal = optimal_actions(dist, maps.obstacles, True, mechanism)[..., GPPN_TO_VINADV[:a]]
    first = np.argmax(optimal, axis=-1)
    one_hot = (np.arange(a) == first[..., None]) & optimal.any(axis=-1, keepdims=True)
    return np.moveaxis(one_hot, -1, 1)[:, :, None].astype(np.float32)


def write(maps: MapSet, path: Path, split: str) -> dict:
    """Write the mazes to `split` (train|valid|test), the others empty, with GPPN's optimal policies (every move
    cost 1: 4 actions for `news` maps, else 8; `octile` maps are written as GPPN's `moore`). Returns the counts
    written: maps."""
    s = maps.size
    a = 4 if maps.moves == "news" else 8
    arrays = [
        np.zeros((0, s, s), np.float32),
        np.zeros((0, 1, s, s), np.float32),
        np.zeros((0, a, 1, s, s), np.float32),
    ] * 3
    at = SPLITS[split][0]
    idx = np.arange(len(maps))
    arrays[at : at + 3] = [
        (~maps.obstacles).astype(np.float32),
        goal_images(maps, idx, 0, 1, np.float32)[:, None],
        unit_cost_policies(maps),
    ]
    with open(path, "wb") as fh:
        np.savez_compressed(fh, *arrays)
    return {"maps": len(maps)}
