"""Content checks of maps, paths and pairs against DESIGN.md (the contract), vectorised over the whole file.

Loaders check shapes and dtypes (`vinadv.npzfile`) and then call one function here: `check_maps`, `check_paths`,
`check_pairs`. A violation raises InputError naming the file, the field, the problem and the first offending map,
path or pair, so a file that would be stored wrong is refused at the door. What is checked:

- cells: starts, goals and added obstacles on the grid; starts and goals free; a start is not its goal; the starts
  of one map distinct.
- paths: every cell on the grid and free on its map, consecutive cells neighbours (one move of the map set's
  movement model: 8-neighbours, 4-neighbours on `news`; without corner cutting, not diagonally between obstacles),
  the first cell the path's start; a path that reached its goal (termination `goal`) ends there and one that did
  not does not (DESIGN.md: it reaches the goal when its last cell is the goal).
- pairs: the adversarial map is the original plus exactly the added cells (K >= 1), distinct, each free and
  neither the start nor the goal; for a pair of edit `remove`, the original minus exactly the freed cells, distinct,
  each an obstacle of the original map and none a border wall (`border_walls`).

Maps without a border wall are legitimate (the grid edge is a wall): no border is required.
"""

from __future__ import annotations

import os

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.moves import DEFAULT_MOVES, move_model
from vinadv.grid.paths import PackedPaths


def fail(where: str | os.PathLike, field: str, problem: str, what: str, index) -> InputError:
    """The InputError for `field` of file `where`: `problem`, first at `what` `index` (say, pair 3)."""
    return InputError(f"{where}: field '{field}' {problem} ({what} {int(index)})")


def _first(bad: np.ndarray) -> int | None:
    found = np.flatnonzero(bad)
    return int(found[0]) if len(found) else None


def _check(bad: np.ndarray, where, field: str, problem: str, what: str) -> None:
    first = _first(bad)
    if first is not None:
        raise fail(where, field, problem, what, first)


def check_cells(where, field: str, cells: np.ndarray, size: int, what: str) -> None:
    """`cells (..., 2)` on the `size x size` grid; `what` names the leading index (map, pair)."""
    cells = np.asarray(cells).reshape(len(cells), -1, 2) if len(cells) else np.zeros((0, 1, 2), dtype=np.int64)
    off = ((cells < 0) | (cells >= size)).any(axis=(1, 2))
    _check(off, where, field, f"has a cell outside the {size}x{size} grid", what)


def check_paths(
    where,
    field: str,
    paths: PackedPaths,
    size: int,
    *,
    obstacles: np.ndarray | None = None,
    owner: np.ndarray | None = None,
    starts: np.ndarray | None = None,
    goals: np.ndarray | None = None,
    reached: np.ndarray | None = None,
    corner_cutting: bool = True,
    what: str = "path",
    numbers: np.ndarray | None = None,
    moves: str = DEFAULT_MOVES,
) -> None:
    """Check the n `paths` (their layout is checked by `PackedPaths` itself).

    Path i lies on map `obstacles[owner[i]]` (`owner` default: i); `starts (n, 2)`: its first cell; `goals (n, 2)`
    with `reached (n,)` bool: it ends on its goal exactly when reached. Errors name path `numbers[i]` (default i)
    as `what`. Each check is skipped when its array is None. `moves`: the movement model the steps must follow.
    """
    n = len(paths)
    if n <= 0:
        return
    cells, offsets = paths.cells.astype(np.int64), paths.offsets
    numbers = np.arange(n) if numbers is None else np.asarray(numbers)
    path_of = paths.owners()  # the path of each cell

    def check(bad_path: np.ndarray, problem: str) -> None:
        first = _first(bad_path)
        if first is not None:
            raise fail(where, field, problem, what, numbers[first])

    def per_path(bad_cell: np.ndarray) -> np.ndarray:
        return np.bincount(path_of[bad_cell], minlength=n) > 0

    off = ((cells < 0) | (cells >= size)).any(axis=1)
    check(per_path(off), f"has a cell outside the {size}x{size} grid")
    if len(cells) > 1:
        step = cells[1:] - cells[:-1]
        move = np.ones(len(step), dtype=bool)
        move[offsets[1:-1] - 1] = False  # the last cell of a path makes no move
        if move_model(moves).n_actions == 8:
            jump = move & (np.abs(step).max(axis=1) != 1)
            check(per_path(np.append(jump, False)), "has consecutive cells that are not 8-neighbours (a jump)")
        else:
            jump = move & (np.abs(step).sum(axis=1) != 1)
            check(
                per_path(np.append(jump, False)),
                f"has consecutive cells that are not 4-neighbours (a jump; the file says {moves!r} moves)",
            )
    if obstacles is not None:
        maps = path_of if owner is None else np.asarray(owner)[path_of]
        blocked = obstacles[maps, cells[:, 0], cells[:, 1]]
        check(per_path(blocked), "has a cell on an obstacle")
        if not corner_cutting and len(cells) > 1:
            diagonal = move & (step[:, 0] != 0) & (step[:, 1] != 0)
            k = np.flatnonzero(diagonal)
            src, m = cells[k], maps[k]
            squeezed = obstacles[m, src[:, 0] + step[k, 0], src[:, 1]] | obstacles[m, src[:, 0], src[:, 1] + step[k, 1]]
            bad = np.zeros(len(cells), dtype=bool)
            bad[k[squeezed]] = True
            check(per_path(bad), "has a diagonal move between obstacles (the file says no corner cutting)")
    if starts is not None:
        check((cells[offsets[:-1]] != np.asarray(starts)).any(axis=1), "does not start at its start")
    if goals is not None and reached is not None:
        at_goal = (cells[offsets[1:] - 1] == np.asarray(goals)).all(axis=1)
        check(
            at_goal != np.asarray(reached, dtype=bool),
            "disagrees with its termination: a path reaches the goal exactly when its last cell is the goal",
        )


def check_maps(
    where,
    obstacles: np.ndarray,
    goals: np.ndarray,
    starts: np.ndarray,
    expert: PackedPaths,
    corner_cutting: bool = True,
    start_counts: np.ndarray | None = None,
    moves: str = DEFAULT_MOVES,
) -> None:
    """A maps file's content: `obstacles (n, N, N)`, `goals (n, 2)`, `starts (n, S, 2)`, `expert` paths (n*S) made
    of `moves`; `start_counts (n,)`: map i's slots from `start_counts[i]` on are padding (a start on the goal, see
    `MapSet`)."""
    n, size = len(obstacles), obstacles.shape[-1] if obstacles.ndim == 3 else 0
    if n == 0:
        return
    s = starts.shape[1]
    check_cells(where, "goals", goals, size, "map")
    check_cells(where, "starts", starts, size, "map")
    idx = np.arange(n)
    _check(obstacles[idx, goals[:, 0], goals[:, 1]], where, "goals", "has a goal on an obstacle", "map")
    if s:
        _check(
            obstacles[idx[:, None], starts[..., 0], starts[..., 1]].any(axis=1),
            where,
            "starts",
            "has a start on an obstacle",
            "map",
        )
        real = np.ones((n, s), bool) if start_counts is None else np.arange(s)[None, :] < start_counts[:, None]
        _check(
            ((starts == goals[:, None, :]).all(axis=2) & real).any(axis=1),
            where,
            "starts",
            "has a start on the goal",
            "map",
        )
        # padded slots sort last and out of the way of the real starts' duplicates
        flat = np.sort(np.where(real, starts[..., 0] * size + starts[..., 1], size * size + np.arange(s)), axis=1)
        _check((np.diff(flat, axis=1) == 0).any(axis=1), where, "starts", "has the same start twice", "map")
    check_paths(
        where,
        "expert_cells",
        expert,
        size,
        obstacles=obstacles,
        owner=np.repeat(idx, s),
        starts=starts.reshape(-1, 2),
        goals=np.repeat(goals, s, axis=0),
        reached=np.ones(n * s, dtype=bool),
        corner_cutting=corner_cutting,
        what="path",
        moves=moves,
    )


def border_walls(obstacles: np.ndarray) -> np.ndarray:
    """`(B, N, N)` bool: the cells of the outer ring of each map of `obstacles (B, N, N)` whose outer ring is all
    obstacles (a map with a border wall, as the generator makes them); all False for a map without one. A border
    wall is never removed (`vocabulary.REMOVE`): a freed border cell opens the world onto the grid's edge."""
    obstacles = np.asarray(obstacles, dtype=bool)
    ring = np.zeros(obstacles.shape[1:], dtype=bool)
    ring[[0, -1], :] = True
    ring[:, [0, -1]] = True
    walled = (obstacles | ~ring).all(axis=(1, 2))
    return ring[None] & walled[:, None, None]


def check_pairs(
    where,
    obstacles_o: np.ndarray,
    obstacles_a: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    added: np.ndarray,
    paths: dict,
    terms: dict,
    corner_cutting: bool = True,
    moves: str = DEFAULT_MOVES,
    removes: np.ndarray | None = None,
) -> None:
    """A pairs file's content: maps `(n, N, N)`, `starts`/`goals` `(n, 2)`, `added` `(n, K, 2)` (or `(n, 2)`, K = 1),
    `paths[side]` (`PackedPaths`) and `terms[side] (n,)` termination names for side "o" (original map) and "a"
    (adversarial map), made of `moves`; `removes (n,)` bool: the pairs of edit `remove` (default none). The added
    cells of a pair are K distinct cells, free on the original map, none the start or the goal, and the adversarial
    map is the original plus exactly them; the freed cells of a `remove` pair are K distinct obstacle cells of the
    original map, none a border wall (`border_walls`), and the adversarial map is the original minus exactly them
    (reachability is not checked here: see `vinadv.attacks.validity.valid_additions` and `valid_removals`)."""
    n, size = len(obstacles_o), obstacles_o.shape[-1]
    if n == 0:
        return
    added = np.asarray(added).reshape(n, -1, 2)
    for name, cells in (("starts", starts), ("goals", goals), ("added", added)):
        check_cells(where, name, cells, size, "pair")
    idx = np.arange(n)
    _check(obstacles_o[idx, starts[:, 0], starts[:, 1]], where, "starts", "has a start on an obstacle", "pair")
    _check(obstacles_o[idx, goals[:, 0], goals[:, 1]], where, "goals", "has a goal on an obstacle", "pair")
    _check((starts == goals).all(axis=1), where, "starts", "has a start on its goal", "pair")
    removes = np.zeros(n, dtype=bool) if removes is None else np.asarray(removes, dtype=bool)
    _check((added == starts[:, None]).all(axis=2).any(axis=1), where, "added", "is on the start", "pair")
    _check((added == goals[:, None]).all(axis=2).any(axis=1), where, "added", "is on the goal", "pair")
    on_obstacle = obstacles_o[idx[:, None], added[..., 0], added[..., 1]]
    _check(~removes & on_obstacle.any(axis=1), where, "added", "is already an obstacle on the original map", "pair")
    _check(removes & ~on_obstacle.all(axis=1), where, "added", "frees a cell that is no obstacle (edit remove)", "pair")
    walls = border_walls(obstacles_o)[idx[:, None], added[..., 0], added[..., 1]]
    _check(removes & walls.any(axis=1), where, "added", "frees a border wall cell (edit remove)", "pair")
    flat = np.sort(added[..., 0] * size + added[..., 1], axis=1)
    _check((np.diff(flat, axis=1) == 0).any(axis=1), where, "added", "has the same cell twice", "pair")
    expected = obstacles_o.copy()
    expected[idx[:, None], added[..., 0], added[..., 1]] = ~removes[:, None]
    _check(
        (obstacles_a != expected).any(axis=(1, 2)),
        where,
        "obstacles_a",
        "is not obstacles_o plus (edit add) or minus (edit remove) exactly the cells 'added'",
        "pair",
    )
    for side, obstacles in (("o", obstacles_o), ("a", obstacles_a)):
        check_paths(
            where,
            f"path_{side}_cells",
            paths[side],
            size,
            obstacles=obstacles,
            starts=starts,
            goals=goals,
            reached=np.asarray(terms[side]) == "goal",
            corner_cutting=corner_cutting,
            what="pair",
            moves=moves,
        )
