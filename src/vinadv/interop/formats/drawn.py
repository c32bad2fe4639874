"""Maps drawn by hand, read from a file: `ascii` (vinadv's own small text format, `vinadv.grid.drawn`: `#` or `@`
an obstacle, `.` free, `S` a start, `G` the goal) and `png` (an image: a pixel darker than half grey, below 128 of
255 once made grey by Pillow's `convert("L")`, is an obstacle; the start and goal are given, `start` and `goal` as
`ROW,COL`). Either is padded with obstacles into a square (`pad_to` N for a planner of size N); the movement model
and corner cutting are asked for (default octile, corner cutting allowed). Read only: export refuses them.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from vinadv.errors import InputError, one_line
from vinadv.grid.drawn import MAX_SIDE, drawn_map_set, from_ascii
from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import DEFAULT_MOVES
from vinadv.interop.formats.files import ascii_text, check_file

MAX_FILE_BYTES = 64 * 2**20
#: a grey level below this is an obstacle
DARK = 128
MOVES = ("octile", "moore", "news")


def _refuse(path: str, split: str | None, starts: int | None) -> None:
    if starts is not None:
        raise InputError(f"{path}: a drawn map brings its own starts; starts cannot be set", "starts")


def read_ascii(
    path: str,
    split: str | None,
    starts: int | None,
    seed: int,
    moves: str | None = None,
    *,
    pad_to: int | None = None,
    corner_cutting: bool | None = None,
) -> tuple[MapSet, dict]:
    """The one map drawn in the ASCII file at `path` (`vinadv.grid.drawn`)."""
    check_file(path, MAX_FILE_BYTES)
    _refuse(path, split, starts)
    text = ascii_text(path, Path(path).read_bytes())
    maps = from_ascii(
        text,
        pad_to=pad_to,
        corner_cutting=True if corner_cutting is None else corner_cutting,
        moves=moves or DEFAULT_MOVES,
        where=path,
    )
    return maps, _info(maps)


def _info(maps: MapSet) -> dict:
    return {
        "maps": 1,
        "size": maps.size,
        "starts_per_map": maps.n_starts,
        "maps_padded": 0,
        "corner_cutting": maps.corner_cutting,
        "expert_paths": f"vinadv's own (Dijkstra, {maps.moves} moves)",
    }


def parse_cell(value, name: str) -> tuple[int, int]:
    """`ROW,COL` (text, or a pair of ints) as a cell."""
    if isinstance(value, str):
        found = re.fullmatch(r"\s*([0-9]{1,6})\s*,\s*([0-9]{1,6})\s*", value)
        if not found:
            raise InputError(f"{name} {one_line(value[:30])!r}: expected ROW,COL", name)
        return int(found.group(1)), int(found.group(2))
    try:
        r, c = (int(v) for v in value)
    except (TypeError, ValueError):
        raise InputError(f"{name} {value!r}: expected ROW,COL", name) from None
    return r, c


def read_png(
    path: str,
    split: str | None,
    starts: int | None,
    seed: int,
    moves: str | None = None,
    *,
    start=None,
    goal=None,
    pad_to: int | None = None,
    corner_cutting: bool | None = None,
) -> tuple[MapSet, dict]:
    """The map drawn in the image at `path` (module docstring), with `start` and `goal` (`ROW,COL`)."""
    from PIL import Image, UnidentifiedImageError

    check_file(path, MAX_FILE_BYTES)
    _refuse(path, split, starts)
    if start is None or goal is None:
        raise InputError(f"{path}: give start and goal (ROW,COL): an image draws neither", "start", "goal")
    start_cell, goal_cell = parse_cell(start, "start"), parse_cell(goal, "goal")
    try:
        with Image.open(path) as image:
            if max(image.size) > MAX_SIDE:
                raise InputError(f"{path}: {image.size[0]}x{image.size[1]} pixels, more than {MAX_SIDE} a side")
            grey = np.asarray(image.convert("L"))
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError, Image.DecompressionBombError) as exc:
        raise InputError(f"{path}: not a readable image ({one_line(str(exc))[:120]})") from None
    obstacles = grey < DARK
    maps = drawn_map_set(
        obstacles,
        goal_cell,
        [start_cell],
        pad_to=pad_to,
        corner_cutting=True if corner_cutting is None else corner_cutting,
        moves=moves or DEFAULT_MOVES,
        where=path,
    )
    return maps, _info(maps)


def write_refused(name: str):
    def write(maps: MapSet, path: Path, split: str) -> dict:
        raise InputError(f"format {name} is read only: export to movingai, or draw the map with `maps show`")

    return write
