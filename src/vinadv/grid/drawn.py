"""Maps drawn by hand: a grid of obstacles with a goal and starts, made into a MapSet of one map.

The ASCII drawing (`from_ascii`, `vinadv maps import --format ascii`): one line a row, `#` or `@` an obstacle, `.` a
free cell, `S` a start (one or more: the starts in row-major order), `G` the goal (exactly one); blank lines before
and after the drawing and spaces at the ends of lines are ignored, and every row has the same width. This is
vinadv's own small format, not the Moving AI `.map` grid (where `S` and `G` are terrain).

A drawing that is not square, or smaller than `pad_to`, is padded with obstacles below and to the right into a
square of side `max(H, W, pad_to)`, so that a small drawing can be planned by a planner of size N (`pad_to` N);
the padding is the maps' frozen cells, which no attack adds to or frees (`MapSet.frozen`).
Expert paths are vinadv's (Dijkstra under the movement model and corner-cutting rule asked for); a start that cannot
reach the goal is refused, naming the start.
"""

from __future__ import annotations

import numpy as np

from vinadv.errors import InputError, one_line
from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import DEFAULT_MOVES, check_moves
from vinadv.grid.shortest_paths import expert_paths_from, shortest_distances

#: the largest side of a drawn map
MAX_SIDE = 4096
OBSTACLE_CHARS = "#@"
FREE_CHARS = ".SG"


def parse_ascii(text: str, where: str = "drawing") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`(obstacles (H, W) bool, goal (2,), starts (S, 2))` of an ASCII drawing; InputError naming `where`, the line
    and the column of what is wrong."""
    lines = [line.rstrip() for line in text.replace("\r\n", "\n").split("\n")]
    first = next((i for i, line in enumerate(lines) if line), None)
    if first is None:
        raise InputError(f"{where}: no rows drawn (# or @ obstacles, . free, S starts, G the goal)")
    last = max(i for i, line in enumerate(lines) if line)
    rows = lines[first : last + 1]
    width = len(rows[0])
    if len(rows) > MAX_SIDE or width > MAX_SIDE:
        raise InputError(f"{where}: {len(rows)} rows of {width}, more than {MAX_SIDE} a side")
    for i, row in enumerate(rows):
        if len(row) != width:
            raise InputError(f"{where}: line {first + i + 1} has {len(row)} characters, line {first + 1} has {width}")
        bad = next((c for c, ch in enumerate(row) if ch not in OBSTACLE_CHARS + FREE_CHARS), None)
        if bad is not None:
            raise InputError(
                f"{where}: line {first + i + 1} column {bad + 1} is {one_line(row[bad])!r}, expected # or @ "
                "(obstacle), . (free), S (start) or G (goal)"
            )
    chars = np.array([list(row) for row in rows])
    goals = np.argwhere(chars == "G")
    if len(goals) != 1:
        raise InputError(f"{where}: has {len(goals)} goals (G), expected one")
    starts = np.argwhere(chars == "S")
    if len(starts) == 0:
        raise InputError(f"{where}: has no start (S)")
    return np.isin(chars, list(OBSTACLE_CHARS)), goals[0].astype(np.int64), starts.astype(np.int64)


def pad_to_square(obstacles: np.ndarray, pad_to: int | None = None, where: str = "drawing") -> np.ndarray:
    """`obstacles (H, W)` padded with obstacles below and to the right into a square of side `max(H, W, pad_to)`."""
    h, w = obstacles.shape
    side = max(h, w)
    if pad_to is not None:
        if isinstance(pad_to, bool) or not side <= pad_to <= MAX_SIDE:
            raise InputError(f"pad_to {pad_to}: {where} is {h}x{w}, so pad_to must be in {side}..{MAX_SIDE}", "pad_to")
        side = pad_to
    if side < 3:
        raise InputError(f"{where}: {h}x{w} is smaller than 3x3, the smallest map (pad_to makes it larger)", "pad_to")
    out = np.ones((side, side), dtype=bool)
    out[:h, :w] = obstacles
    return out


def drawn_map_set(
    obstacles: np.ndarray,
    goal,
    starts,
    *,
    pad_to: int | None = None,
    corner_cutting: bool = True,
    moves: str = DEFAULT_MOVES,
    where: str = "drawing",
) -> MapSet:
    """The MapSet of one drawn map: `obstacles (H, W)` bool, `goal (row, col)` and `starts (S, 2)`, padded (module
    docstring); a goal or start off the grid or on an obstacle, a repeated start or one that cannot reach the goal is
    refused, naming `where` and the cell."""
    moves = check_moves(moves, corner_cutting)
    obstacles = np.asarray(obstacles, dtype=bool)
    h, w = obstacles.shape
    goal = np.asarray(goal, dtype=np.int64).reshape(2)
    starts = np.asarray(starts, dtype=np.int64).reshape(-1, 2)
    for what, cell in (("goal", goal), *(("start", s) for s in starts)):
        r, c = (int(v) for v in cell)
        if not (0 <= r < h and 0 <= c < w):
            raise InputError(f"{where}: {what} ({r}, {c}) is outside the {h}x{w} map", what)
        if obstacles[r, c]:
            raise InputError(f"{where}: {what} ({r}, {c}) is on an obstacle", what)
    if len(starts) == 0:
        raise InputError(f"{where}: no start", "start")
    if (starts == goal).all(axis=1).any():
        raise InputError(f"{where}: a start is the goal ({int(goal[0])}, {int(goal[1])})", "start")
    if len(np.unique(starts, axis=0)) != len(starts):
        raise InputError(f"{where}: the same start twice", "start")
    square = pad_to_square(obstacles, pad_to, where)[None]
    dist, _ = shortest_distances(square, goal[None], corner_cutting, moves)
    far = ~np.isfinite(dist[0, starts[:, 0], starts[:, 1]])
    if far.any():
        r, c = (int(v) for v in starts[np.flatnonzero(far)[0]])
        raise InputError(f"{where}: the start ({r}, {c}) cannot reach the goal ({moves} moves)", "start")
    costs, expert = expert_paths_from(dist, square, goal[None], starts[None], corner_cutting, moves)
    padding = np.ones(square.shape, dtype=bool)
    padding[:, :h, :w] = False  # the drawing's own cells; the rest no attack may edit (`MapSet.frozen`)
    return MapSet(
        obstacles=square,
        goals=goal[None],
        starts=starts[None],
        expert_costs=costs,
        expert=expert,
        corner_cutting=bool(corner_cutting),
        seed=-1,
        moves=moves,
        frozen=padding if padding.any() else None,
    )


def from_ascii(
    text: str,
    *,
    pad_to: int | None = None,
    corner_cutting: bool = True,
    moves: str = DEFAULT_MOVES,
    where: str = "drawing",
) -> MapSet:
    """The MapSet of one map drawn in ASCII (module docstring)."""
    obstacles, goal, starts = parse_ascii(text, where)
    return drawn_map_set(
        obstacles, goal, starts, pad_to=pad_to, corner_cutting=corner_cutting, moves=moves, where=where
    )
