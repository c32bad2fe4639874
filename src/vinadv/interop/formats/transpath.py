"""The TransPath authors' XML tasks (AIRI-Institute/TransPath, `maps/heatmap_<i>_<t>.xml`, read as their `OODMaps`):
one task a file, in `<root><map>`: `startx`, `starty`, `goalx`, `goaly` (x the column, y the row), `width`, `height`
and a `grid` of `height` `row` elements of `width` numbers separated by spaces, 1 an obstacle and 0 free; beside it,
in `<root><heatmap>`, the file's target values (`_f` the focal values, `_h` the exact cost-to-go, `_k` the correction
factors), a grid of the same shape, checked (finite numbers) but not kept.

Several files are read at once (`vinadv maps import --format transpath FILE...`): each distinct task (grid, start and
goal) is one map with one start, in the order first met; files that hold the same task (the `_f`, `_h` and `_k` files
of one example) count once. Maps are octile, with corner cutting (the authors' rule) unless asked otherwise; a grid
that is not square is padded with obstacles into a square (`pad_to`, as the drawn maps). Expert paths are vinadv's own
(Dijkstra). Read only: export refuses it.

A file is refused in one line naming it and the element: more than `MAX_FILE_BYTES`, a document type declaration
(entities are never expanded), XML that is not well formed, a missing or repeated element, a number that is not one,
a grid of another shape than its `width` and `height`, a cell other than 0 or 1, a start or goal off the grid or on an
obstacle, a start that cannot reach its goal.
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from vinadv.errors import InputError, one_line
from vinadv.grid.drawn import MAX_SIDE, drawn_map_set
from vinadv.grid.mapset import MapSet
from vinadv.interop.formats.files import check_file

#: the largest file read (the authors' 64x64 tasks are about 40 kB)
MAX_FILE_BYTES = 64 * 2**20
MOVES = ("octile",)
_INT = re.compile(r"\s*([0-9]{1,6})\s*")
_DECLARATION = re.compile(rb"<!\s*(DOCTYPE|ENTITY)", re.IGNORECASE)


def _text(node: ET.Element, name: str, path: str, where: str) -> str:
    found = node.findall(name)
    if len(found) != 1:
        raise InputError(f"{path}: {'no' if not found else 'more than one'} <{name}> in <{where}>", name)
    return found[0].text or ""


def _int(node: ET.Element, name: str, path: str, where: str) -> int:
    text = _text(node, name, path, where)
    found = _INT.fullmatch(text)
    if not found:
        raise InputError(f"{path}: <{where}><{name}> {one_line(text[:30])!r} is not a whole number >= 0", name)
    return int(found.group(1))


def _grid(node: ET.Element, path: str, where: str, cells: bool) -> np.ndarray:
    """The `(height, width)` grid of `<where>`: 0/1 cells (`cells`) or finite numbers."""
    width, height = _int(node, "width", path, where), _int(node, "height", path, where)
    if not (1 <= width <= MAX_SIDE and 1 <= height <= MAX_SIDE):
        raise InputError(f"{path}: <{where}> is {width}x{height}, expected 1..{MAX_SIDE} a side", "width")
    grids = node.findall("grid")
    if len(grids) != 1:
        raise InputError(f"{path}: {'no' if not grids else 'more than one'} <grid> in <{where}>", "grid")
    rows = list(grids[0])
    if len(rows) != height or any(row.tag != "row" for row in rows):
        raise InputError(f"{path}: <{where}><grid> holds {len(rows)} elements, expected {height} <row>", "grid")
    out = np.empty((height, width), dtype=np.float64)
    for i, row in enumerate(rows):
        words = (row.text or "").split()
        if len(words) != width:
            raise InputError(f"{path}: <{where}> row {i} has {len(words)} values, expected {width}", "row")
        try:
            values = [float(w) for w in words]
        except ValueError:
            bad = next(w for w in words if not _is_float(w))
            raise InputError(f"{path}: <{where}> row {i}: {one_line(bad[:20])!r} is not a number", "row") from None
        out[i] = values
    if cells:
        bad = ~np.isin(out, (0.0, 1.0))
        if bad.any():
            r, c = (int(v) for v in np.argwhere(bad)[0])
            raise InputError(f"{path}: <{where}> cell ({r}, {c}) is {float(out[r, c])!r}, expected 0 or 1", "grid")
    elif not np.isfinite(out).all():
        r, c = (int(v) for v in np.argwhere(~np.isfinite(out))[0])
        raise InputError(
            f"{path}: <{where}> value ({r}, {c}) is {float(out[r, c])!r}, expected a finite number", "grid"
        )
    return out


def _is_float(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def read_task(path: str) -> tuple[np.ndarray, tuple[int, int], tuple[int, int]]:
    """One task file: `(obstacles (H, W) bool, start (row, col), goal (row, col))` (module doc); InputError naming
    the file otherwise."""
    check_file(path, MAX_FILE_BYTES)
    data = Path(path).read_bytes()
    if _DECLARATION.search(data):
        raise InputError(f"{path}: holds a document type or entity declaration, which TransPath's tasks never do")
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        raise InputError(f"{path}: not well-formed XML ({one_line(str(exc))[:100]})") from None
    except (ValueError, UnicodeError) as exc:  # an encoding the parser refuses
        raise InputError(f"{path}: not readable XML ({one_line(str(exc))[:100]})") from None
    if root.tag != "root":
        raise InputError(f"{path}: the document element is <{one_line(root.tag[:30])}>, expected <root>", "root")
    maps = root.findall("map")
    if len(maps) != 1:
        raise InputError(f"{path}: {'no' if not maps else 'more than one'} <map> in <root>", "map")
    node = maps[0]
    start = (_int(node, "starty", path, "map"), _int(node, "startx", path, "map"))
    goal = (_int(node, "goaly", path, "map"), _int(node, "goalx", path, "map"))
    obstacles = _grid(node, path, "map", cells=True) == 1.0
    heat = root.findall("heatmap")
    if len(heat) > 1:
        raise InputError(f"{path}: more than one <heatmap> in <root>", "heatmap")
    if heat:
        values = _grid(heat[0], path, "heatmap", cells=False)
        if values.shape != obstacles.shape:
            raise InputError(
                f"{path}: <heatmap> is {values.shape[1]}x{values.shape[0]}, the map "
                f"{obstacles.shape[1]}x{obstacles.shape[0]}",
                "heatmap",
            )
    return obstacles, start, goal


def read(
    path: str | Sequence[str],
    split: str | None,
    starts: int | None,
    seed: int,
    moves: str | None = None,
    *,
    pad_to: int | None = None,
    corner_cutting: bool | None = None,
) -> tuple[MapSet, dict]:
    """The distinct tasks of the XML files at `path` (one path or several), one map each (module doc)."""
    paths = [str(path)] if isinstance(path, (str, os.PathLike)) else [str(p) for p in path]
    if starts is not None:
        raise InputError(f"{paths[0]}: a TransPath task brings its own start; starts cannot be set", "starts")
    if not paths:
        raise InputError("no TransPath task files given")
    cut = True if corner_cutting is None else bool(corner_cutting)
    seen: dict[tuple, int] = {}
    parts: list[MapSet] = []
    names: list[str] = []
    padded = 0
    for p in paths:
        obstacles, start, goal = read_task(p)
        key = (obstacles.shape, obstacles.tobytes(), start, goal)
        if key in seen:
            continue
        seen[key] = len(parts)
        parts.append(drawn_map_set(obstacles, goal, [start], pad_to=pad_to, corner_cutting=cut, where=p))
        names.append(p)
        padded += obstacles.shape != (parts[-1].size, parts[-1].size)
    maps = MapSet.concat(parts, names) if len(parts) > 1 else parts[0]
    return maps, {
        "maps": len(maps),
        "size": maps.size,
        "starts_per_map": 1,
        "maps_padded": 0,
        "files": len(paths),
        "tasks_counted_once": len(paths) - len(parts),
        "grids_padded_to_square": int(padded),
        "corner_cutting": maps.corner_cutting,
        "expert_paths": "vinadv's own (Dijkstra, octile moves)",
    }
