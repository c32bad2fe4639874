"""The Moving AI Lab benchmark layout (Sturtevant 2012, movingai.com/benchmarks; the multi-agent set: Stern et al.
2019): a grid `.map` file and a `.scen` file of start/goal problems with their optimal lengths.

`.map` (ASCII): four header lines `type octile`, `height H`, `width W`, `map`, then H rows of W characters; (0, 0)
is the top-left cell, x the column, y the row. Passable: `.`, `G` (ground) and `S` (swamp); obstacles: `@`, `O`
(out of bounds), `T` (trees) and `W` (water, passable only from water in the original game rules: an obstacle here).
Any other character is refused, naming the line and column. `.scen`: a first line `version 1`, then one problem a
line, tab-separated: bucket, map file, map width, map height, start x, start y, goal x, goal y, optimal length.
Moves are the format's: `octile` (8 moves, diagonal sqrt 2) without corner cutting (a diagonal move needs both
orthogonal neighbours free).

A maps file holds one goal per map, so each problem becomes a map of its own (the same grid, one start), in the
`.scen` file's order; `bucket` keeps the problems of some buckets only, and the rows whose map name is not the
`.map` file's are counted and left out. Every optimal length is checked against vinadv's shortest path on the whole
map (a difference above `LENGTH_TOL` is one line naming the file, the line and both lengths). A problem whose
start is its goal (length 0) is left out and counted: a maps file's start is never its goal.

A map that is not square (den312d: 81 rows of 65 columns) is padded with obstacles below and to the right into a
square of its larger side; `padding` (in the info) says how many rows and columns, and the padded cells are the
map set's `frozen` cells (`MapSet.frozen`: no attack adds to or frees them). Every map records its provenance in
the maps file (`MapSet.source`, `source_sha256`, `origin`): the `.map` file's name, its sha256 and the source cell of
the map's (0, 0) (a crop's window origin; (0, 0) for the whole map).

Crops (`crop` N, `crops` K, `seed`): maps larger than a planner's size are cut into K windows of N x N, each origin
drawn uniformly (seeded) among the windows with at least `min_free` (default `MIN_FREE`, a half) of their cells
free; a drawn window with fewer is drawn again, up to `CROP_TRIES` times K in all. A crop's goal is drawn uniformly
among the free cells of its largest connected region (moves without corner cutting join exactly the 4-connected
free cells; ties to the region met first in row-major order), and its starts (`starts`, default 1) by the Neural A*
loader's rule (`vinadv.interop.formats.mpd`: a band of 55-70, 70-85 or 85-100 percent of the distance to the goal
at random, then a cell of it), the distances vinadv's inside the window (a `.scen` length does not hold there). A
crop whose region has no cell in a band is drawn again. Each crop's source file, its sha256 and the window's origin
(row, col) are in the info (`crops`). Without `scen` and `crop`, the whole map is one map whose goal and starts are
drawn by the same rule.

Export writes the maps of a set back: one `.map` per distinct grid, the frozen rows below and columns to the right
cut off (the padding of import: a non-square map goes back as it was), and one `.scen` of every real start (bucket
`floor(length / 4)`, the benchmarks' rule; lengths with 8 decimals). Only `octile` maps without corner cutting are
written: the format cannot say another rule.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from vinadv.checksums import file_sha256
from vinadv.errors import InputError, one_line
from vinadv.grid.mapset import MapSet
from vinadv.grid.shortest_paths import expert_paths_from, shortest_distances
from vinadv.interop.formats.files import ascii_text
from vinadv.interop.formats.mpd import draw_starts, start_bands
from vinadv.seeds import check_seed

MOVES = "octile"
#: the characters of a `.map` grid: passable ones, obstacles
PASSABLE = ".GS"
OBSTACLE = "@OTW"
#: the largest side read and the largest file (bytes): a bound on what a damaged or hostile header can ask for
MAX_SIDE = 4096
MAX_FILE_BYTES = 64 * 2**20
#: the most cells (maps x N x N) one import may hold in memory: a bucket filter or crops for more
MAX_CELLS = 2**28
#: a `.scen` length and vinadv's agree within this (the file prints 8 decimals)
LENGTH_TOL = 1e-6
#: the least share of free cells of a crop window (by default)
MIN_FREE = 0.5
#: how many windows are drawn at most, per crop asked for
CROP_TRIES = 100
#: `.scen` fields, in order
SCEN_FIELDS = ("bucket", "map", "width", "height", "start x", "start y", "goal x", "goal y", "optimal length")

_CODES = np.full(256, 2, dtype=np.uint8)  # 0 free, 1 obstacle, 2 not a grid character
_CODES[np.frombuffer(PASSABLE.encode(), np.uint8)] = 0
_CODES[np.frombuffer(OBSTACLE.encode(), np.uint8)] = 1


def _lines(path: str) -> list[str]:
    """The lines of the ASCII text file at `path` (line ends `\\n` or `\\r\\n`)."""
    if not os.path.exists(path):
        raise InputError(f"{path}: no such file")
    if os.path.isdir(path):
        raise InputError(f"{path}: is a directory, expected a file")
    size = os.path.getsize(path)
    if size > MAX_FILE_BYTES:
        raise InputError(f"{path}: {size} bytes, more than the {MAX_FILE_BYTES} read")
    with open(path, "rb") as fh:
        text = ascii_text(path, fh.read())
    lines = text.replace("\r\n", "\n").split("\n")
    return lines[:-1] if len(lines) > 1 and lines[-1] == "" else lines  # the last line's end ends no line


def _header(path: str, lines: list[str], i: int, key: str) -> int:
    words = lines[i].split() if i < len(lines) else []
    if len(words) != 2 or words[0] != key or not re.fullmatch(r"[0-9]{1,9}", words[1]):
        got = one_line(lines[i][:40]) if i < len(lines) else "the end of the file"
        raise InputError(f"{path}: line {i + 1} is {got!r}, expected '{key} N'")
    value = int(words[1])
    if not 1 <= value <= MAX_SIDE:
        raise InputError(f"{path}: line {i + 1}: {key} {value} is outside 1..{MAX_SIDE}")
    return value


def read_grid(path: str | os.PathLike) -> np.ndarray:
    """The obstacles of the `.map` file at `path`: `(H, W)` bool, True = obstacle. Any problem raises InputError
    naming the file and the line."""
    path = str(path)
    lines = _lines(path)
    if not lines or lines[0].split() != ["type", "octile"]:
        got = one_line(lines[0][:40]) if lines else ""
        raise InputError(f"{path}: line 1 is {got!r}, expected 'type octile' (a Moving AI .map file)")
    height, width = _header(path, lines, 1, "height"), _header(path, lines, 2, "width")
    if len(lines) < 4 or lines[3].strip() != "map":
        raise InputError(f"{path}: line 4 is not 'map'")
    rows = lines[4 : 4 + height]
    if len(rows) < height:
        raise InputError(f"{path}: has {len(rows)} grid rows, its header says height {height}")
    for i, row in enumerate(rows):
        if len(row) != width:
            raise InputError(f"{path}: line {i + 5} has {len(row)} characters, the header says width {width}")
    extra = [i for i, line in enumerate(lines[4 + height :]) if line.strip()]
    if extra:
        raise InputError(f"{path}: line {4 + height + extra[0] + 1} follows the {height} grid rows the header says")
    codes = _CODES[np.frombuffer("".join(rows).encode(), np.uint8)].reshape(height, width)
    if (codes == 2).any():
        r, c = (int(v) for v in np.argwhere(codes == 2)[0])
        raise InputError(
            f"{path}: line {r + 5} column {c + 1} is {rows[r][c]!r}, not a map character "
            f"(passable {PASSABLE}, obstacles {OBSTACLE})"
        )
    return codes == 1


def read_problems(path: str | os.PathLike) -> list[tuple[int, tuple]]:
    """The problems of the `.scen` file at `path`: `(line number, (bucket, map, width, height, sx, sy, gx, gy,
    length))` for each, in order. A malformed line raises InputError naming the file, line and field."""
    path = str(path)
    lines = _lines(path)
    if not lines or not re.fullmatch(r"version\s+1(\.0)?\s*", lines[0]):
        got = one_line(lines[0][:40]) if lines else ""
        raise InputError(f"{path}: line 1 is {got!r}, expected 'version 1' (a Moving AI .scen file)")
    out = []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        fields = line.split("\t") if "\t" in line else line.split()
        fields = [f.strip() for f in fields]
        if len(fields) != len(SCEN_FIELDS):
            raise InputError(f"{path}: line {number} has {len(fields)} fields, expected {len(SCEN_FIELDS)}")
        values: list = []
        for name, text in zip(SCEN_FIELDS, fields, strict=True):
            if name == "map":
                values.append(text)
            elif name == "optimal length":
                try:
                    length = float(text)
                except ValueError:
                    length = float("nan")
                if not np.isfinite(length) or length < 0:
                    raise InputError(f"{path}: line {number}: {name} {one_line(text[:30])!r} is not a length")
                values.append(length)
            else:
                if not re.fullmatch(r"[0-9]{1,9}", text):
                    raise InputError(f"{path}: line {number}: {name} {one_line(text[:30])!r} is not an integer >= 0")
                values.append(int(text))
        out.append((number, tuple(values)))
    return out


def parse_buckets(bucket: int | str | Iterable[int] | None) -> set[int] | None:
    """The buckets kept: None (all), an int, an iterable of ints, or text like `0-4,7`."""
    if bucket is None:
        return None
    if isinstance(bucket, int | np.integer):
        return {int(bucket)}
    if isinstance(bucket, str):
        out: set[int] = set()
        for part in bucket.split(","):
            found = re.fullmatch(r"\s*([0-9]{1,6})\s*(?:-\s*([0-9]{1,6})\s*)?", part)
            if not found or (found.group(2) and int(found.group(2)) < int(found.group(1))):
                raise InputError(f"bucket {bucket!r}: expected numbers and ranges like 0-4,7", "bucket")
            out.update(range(int(found.group(1)), int(found.group(2) or found.group(1)) + 1))
        return out
    return {int(b) for b in bucket}


def pad_square(grid: np.ndarray, side: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """`(padded (S, S), padding (S, S))`: `grid (H, W)` padded with obstacles below and to the right into a square of
    side `side` (default the larger of H and W), and the mask of the padded cells."""
    h, w = grid.shape
    side = max(h, w) if side is None else side
    padded = np.ones((side, side), dtype=bool)
    padded[:h, :w] = grid
    padding = np.ones((side, side), dtype=bool)
    padding[:h, :w] = False
    return padded, padding


def _bound(path: str, n: int, side: int) -> None:
    if n * side * side > MAX_CELLS:
        raise InputError(
            f"{path}: {n} maps of {side}x{side} are more than the {MAX_CELLS} cells one import holds; keep fewer "
            "problems (bucket) or fewer crops"
        )


def _map_set(obstacles, goals, starts, dist, seed: int, info: dict, origins=None, padding=None) -> MapSet:
    """The maps, with their provenance (the `.map` file's name and sha256 in `info`, `origins (n, 2)`, default (0, 0))
    and `padding (N, N)`, the padded cells, as every map's frozen cells (None: none)."""
    n = len(goals)
    starts = starts.reshape(n, -1, 2)
    costs, expert = expert_paths_from(dist, obstacles, goals, starts, False, MOVES)
    frozen = None if padding is None or not padding.any() else np.broadcast_to(padding, obstacles.shape).copy()
    return MapSet(
        obstacles=obstacles,
        goals=goals,
        starts=starts,
        expert_costs=costs,
        expert=expert,
        corner_cutting=False,
        seed=seed,
        moves=MOVES,
        frozen=frozen,
        source=np.full(n, os.path.basename(info["source"])),
        source_sha256=np.full(n, info["sha256"]),
        origin=np.zeros((n, 2), np.int64) if origins is None else np.asarray(origins, np.int64).reshape(n, 2),
    )


def read(
    path: str,
    split: str | None,
    starts: int | None,
    seed: int,
    moves: str | None = None,
    *,
    scen: str | os.PathLike | None = None,
    bucket: int | str | Iterable[int] | None = None,
    crop: int | None = None,
    crops: int | None = None,
    min_free: float | None = None,
    corner_cutting: bool | None = None,
) -> tuple[MapSet, dict]:
    """The maps of the `.map` file at `path`: the problems of `scen` (in `bucket`), or `crops` crops of `crop` x
    `crop`, or the whole map with drawn starts (module docstring). `split` is not used (one grid, no splits)."""
    check_seed(seed)
    if corner_cutting:
        raise InputError(f"{path}: the Moving AI maps' moves never cut corners; corner cutting cannot be asked for")
    grid = read_grid(path)
    info: dict = {"source": path, "sha256": file_sha256(path), "height": grid.shape[0], "width": grid.shape[1]}
    if (crops is not None or min_free is not None) and crop is None:
        raise InputError("crops and min_free go with crop (the window side)", "crops", "min_free", "crop")
    if crop is not None:
        if scen is not None or bucket is not None:
            raise InputError(
                "scen and bucket go without crop: a window draws its own goal and starts (a .scen length does not "
                "hold in a window)",
                "scen",
                "bucket",
                "crop",
            )
        return _read_crops(path, grid, crop, 1 if crops is None else crops, starts, seed, min_free, info)
    if scen is not None:
        if starts is not None:
            raise InputError("the .scen problems bring their own starts (one per problem): starts cannot be set")
        return _read_scen(path, grid, str(scen), parse_buckets(bucket), seed, info)
    if bucket is not None:
        raise InputError("bucket filters the problems of a .scen file: give scen too", "bucket", "scen")
    return _read_whole(path, grid, 1 if starts is None else starts, seed, info)


def _square(path: str, grid: np.ndarray, info: dict) -> tuple[np.ndarray, np.ndarray]:
    square, padding = pad_square(grid)
    info["size"] = square.shape[0]
    info["padding"] = {"rows": square.shape[0] - grid.shape[0], "cols": square.shape[1] - grid.shape[1]}
    return square, padding


def _read_scen(path: str, grid: np.ndarray, scen: str, buckets: set[int] | None, seed: int, info: dict):
    h, w = grid.shape
    problems = read_problems(scen)
    name = os.path.basename(path)
    other = [p for _, p in problems if p[1] != name and os.path.basename(p[1]) != name]
    rows = [(number, p) for number, p in problems if p[1] == name or os.path.basename(p[1]) == name]
    if problems and not rows:
        raise InputError(f"{scen}: no problem names the map {name} (its rows name {problems[0][1][1]!r})")
    for number, p in rows:
        if (p[2], p[3]) != (w, h):
            raise InputError(f"{scen}: line {number}: map size {p[2]}x{p[3]} (width x height), {path} is {w}x{h}")
        for what, x, y in (("start", p[4], p[5]), ("goal", p[6], p[7])):
            if x >= w or y >= h:
                raise InputError(f"{scen}: line {number}: {what} ({x}, {y}) is outside the {w}x{h} map")
            if grid[y, x]:
                raise InputError(f"{scen}: line {number}: {what} ({x}, {y}) is on an obstacle of {path}")
    kept = [(number, p) for number, p in rows if buckets is None or p[0] in buckets]
    same = [(number, p) for number, p in kept if (p[4], p[5]) == (p[6], p[7])]
    kept = [(number, p) for number, p in kept if (p[4], p[5]) != (p[6], p[7])]
    if not kept:
        raise InputError(f"{scen}: no problem with its start apart from its goal in the buckets asked for", "bucket")
    square, padding = _square(path, grid, info)
    n, side = len(kept), square.shape[0]
    _bound(path, n, side)
    p = np.array([q[4:8] for _, q in kept], dtype=np.int64)
    goals, starts = p[:, [3, 2]], p[:, [1, 0]]
    lengths = np.array([q[8] for _, q in kept])
    # one Dijkstra per distinct goal, on the whole map
    unique, which = np.unique(goals, axis=0, return_inverse=True)
    which = which.reshape(-1)
    dist_u, _ = shortest_distances(np.broadcast_to(square, (len(unique), side, side)), unique, False, MOVES)
    ours = dist_u[which, starts[:, 0], starts[:, 1]]
    bad = ~(np.abs(ours - lengths) <= LENGTH_TOL)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InputError(
            f"{scen}: line {kept[i][0]}: optimal length {lengths[i]:.8f} in the file, vinadv's shortest path is "
            f"{ours[i]:.8f} (octile, no corner cutting; {int(bad.sum())} of {n} problems differ)"
        )
    obstacles = np.broadcast_to(square, (n, side, side)).copy()
    maps = _map_set(obstacles, goals, starts, dist_u[which], -1, info, padding=padding)
    info.update(
        scen=scen,
        scen_sha256=file_sha256(scen),
        maps=n,
        starts_per_map=1,
        maps_padded=0,
        problems=len(problems),
        problems_other_maps=len(other),
        problems_start_on_goal=len(same),
        problems_other_buckets=len(rows) - len(kept) - len(same),
        lengths_checked=n,
        expert_paths="vinadv's own (Dijkstra, octile moves without corner cutting); every .scen optimal length "
        "checked equal",
    )
    return maps, info


def _draw(windows: np.ndarray, k: int, rng: np.random.Generator):
    """Goals in each window's largest connected region and up to `k` starts by the Neural A* loader's bands:
    `(ok (B,), goals (B, 2), starts (B, k, 2), counts (B,), dist (B, N, N))`; ok False where no band has a cell."""
    import scipy.ndimage

    b, n = windows.shape[0], windows.shape[1]
    goals = np.zeros((b, 2), dtype=np.int64)
    for i in range(b):
        labels, count = scipy.ndimage.label(~windows[i])  # 4-connected: moves without corner cutting
        sizes = np.bincount(labels.reshape(-1), minlength=count + 1)
        sizes[0] = 0
        cells = np.flatnonzero(labels.reshape(-1) == int(np.argmax(sizes)))
        goals[i] = divmod(int(cells[rng.integers(len(cells))]), n)
    dist, _ = shortest_distances(windows, goals, False, MOVES)
    stored = np.where(np.isfinite(dist), -dist, -float(n * n))
    drawn, counts = draw_starts(start_bands(stored), k, rng)
    starts = np.stack(np.divmod(drawn, n), axis=-1).astype(np.int64)
    pad = np.arange(k)[None, :] >= counts[:, None]
    starts[pad] = np.repeat(goals[:, None, :], k, axis=1)[pad]
    return counts > 0, goals, starts, counts, dist


def _read_crops(path, grid, crop, crops, starts, seed, min_free, info):
    h, w = grid.shape
    k = 1 if starts is None else starts
    min_free = MIN_FREE if min_free is None else float(min_free)
    if not 0 <= min_free <= 1:
        raise InputError(f"min_free must be in 0..1, got {min_free}", "min_free")
    if isinstance(crop, bool) or not 3 <= crop <= min(h, w):
        raise InputError(f"crop {crop}: a window side must be in 3..{min(h, w)} for {path} ({w}x{h})", "crop")
    if crops < 1:
        raise InputError(f"crops must be >= 1, got {crops}", "crops")
    if k < 1:
        raise InputError(f"starts must be >= 1, got {k}", "starts")
    _bound(path, crops, crop)
    rng = np.random.default_rng(seed)
    origins: list[tuple[int, int]] = []
    parts = []
    tries = 0
    while len(origins) < crops and tries < CROP_TRIES * crops:
        want = min(crops - len(origins), CROP_TRIES * crops - tries)
        rows, cols = rng.integers(0, h - crop + 1, want), rng.integers(0, w - crop + 1, want)
        tries += want
        windows = np.stack([grid[r : r + crop, c : c + crop] for r, c in zip(rows, cols, strict=True)])
        free = (~windows).mean(axis=(1, 2)) >= min_free
        if not free.any():
            continue
        ok, goals, drawn, counts, dist = _draw(windows[free], k, rng)
        for j in np.flatnonzero(ok):
            i = int(np.flatnonzero(free)[j])
            origins.append((int(rows[i]), int(cols[i])))
            parts.append((windows[i], goals[j], drawn[j], counts[j], dist[j]))
    if len(origins) < crops:
        raise InputError(
            f"{path}: {len(origins)} of {crops} windows of {crop}x{crop} found in {tries} draws with at least "
            f"{min_free:.0%} free cells and a start far enough from the goal; lower min_free or crop",
            "min_free",
        )
    obstacles = np.stack([p[0] for p in parts])
    goals = np.stack([p[1] for p in parts])
    drawn = np.stack([p[2] for p in parts])
    counts = np.array([p[3] for p in parts], dtype=np.int64)
    dist = np.stack([p[4] for p in parts])
    maps = _map_set(obstacles, goals, drawn, dist, int(seed), info, origins=origins)
    if counts.min() < k:
        maps.start_counts = counts
    info.update(
        size=crop,
        maps=crops,
        starts_per_map=k,
        starts_seed=int(seed),
        maps_padded=int((counts < k).sum()),
        min_free=min_free,
        crops=[{"source": path, "sha256": info["sha256"], "origin": list(o)} for o in origins],
        starts_rule="goal: uniform in the window's largest connected region; starts: Neural A*'s percentile bands "
        "of the distance (55-70, 70-85, 85-100) at random, then a cell",
        expert_paths="vinadv's own (Dijkstra, octile moves without corner cutting) inside each window",
    )
    return maps, info


def _read_whole(path: str, grid: np.ndarray, k: int, seed: int, info: dict):
    if k < 1:
        raise InputError(f"starts must be >= 1, got {k}", "starts")
    square, padding = _square(path, grid, info)
    _bound(path, 1, square.shape[0])
    ok, goals, drawn, counts, dist = _draw(square[None], k, np.random.default_rng(seed))
    if not ok[0]:
        raise InputError(f"{path}: no cell is far enough from a goal in the largest free region to be a start")
    maps = _map_set(square[None].copy(), goals, drawn, dist, int(seed), info, padding=padding)
    if counts[0] < k:
        maps.start_counts = counts.astype(np.int64)
    info.update(
        maps=1,
        starts_per_map=k,
        starts_seed=int(seed),
        maps_padded=int(counts[0] < k),
        starts_rule="goal: uniform in the map's largest connected region; starts: Neural A*'s percentile bands "
        "of the distance (55-70, 70-85, 85-100) at random, then a cell",
        expert_paths="vinadv's own (Dijkstra, octile moves without corner cutting)",
    )
    return maps, info


# ------------------------------------------------------------------------------------------------------ export


def write_map(grid: np.ndarray, path: str | os.PathLike) -> None:
    """Write `grid (H, W)` bool (True = obstacle) as a `.map` file: `@` obstacles, `.` free."""
    h, w = grid.shape
    rows = np.where(grid, "@", ".")
    text = f"type octile\nheight {h}\nwidth {w}\nmap\n" + "".join("".join(r) + "\n" for r in rows)
    Path(path).write_text(text, encoding="ascii")


def unpadded(maps: MapSet, i: int) -> np.ndarray:
    """Map `i`'s obstacles without its padding: the trailing rows and columns of frozen cells cut off (all of them
    frozen in the row or column; the padding that import adds below and to the right)."""
    grid = maps.obstacles[i]
    if maps.frozen is None:
        return grid
    frozen = maps.frozen[i]
    rows = np.flatnonzero(~frozen.all(axis=1))
    cols = np.flatnonzero(~frozen.all(axis=0))
    h = int(rows[-1]) + 1 if len(rows) else 0
    w = int(cols[-1]) + 1 if len(cols) else 0
    return grid[: max(h, 1), : max(w, 1)]


def write(maps: MapSet, path: Path, split: str) -> dict:
    """Write `maps` (octile, no corner cutting) as `.map` files and one `.scen` file: `path` names the `.scen`
    (its `.map` beside it, `STEM.map` for one grid, `STEM-0000.map`... for several), each grid without its padding
    (`unpadded`). Returns the counts."""
    if maps.corner_cutting or maps.moves != MOVES:
        raise InputError(
            f"maps: the Moving AI format holds octile moves without corner cutting; these maps have {maps.moves} "
            f"moves{' with corner cutting' if maps.corner_cutting else ''}"
        )
    path = Path(path)
    stem = path.with_suffix("")
    grids: list[np.ndarray] = []
    names: list[str] = []
    of_map: list[int] = []
    for i in range(len(maps)):
        grid = unpadded(maps, i)
        for j, seen in enumerate(grids):
            if seen.shape == grid.shape and np.array_equal(seen, grid):
                of_map.append(j)
                break
        else:
            grids.append(grid)
            of_map.append(len(grids) - 1)
    files = [stem.with_name(stem.name + ".map")] if len(grids) == 1 else []
    files = files or [stem.with_name(f"{stem.name}-{j:04d}.map") for j in range(len(grids))]
    for grid, file in zip(grids, files, strict=True):
        write_map(grid, file)
        names.append(file.name)
    lines = ["version 1"]
    mask = maps.start_mask
    for i in range(len(maps)):
        h, w = grids[of_map[i]].shape
        gr, gc = (int(v) for v in maps.goals[i])
        for s in np.flatnonzero(mask[i]):
            sr, sc = (int(v) for v in maps.starts[i, s])
            if max(sr, gr) >= h or max(sc, gc) >= w:
                raise InputError(f"maps: map {i}'s start or goal is on its frozen padding, outside the {w}x{h} map")
            length = float(maps.expert_costs[i, s])
            lines.append(f"{int(length // 4)}\t{names[of_map[i]]}\t{w}\t{h}\t{sc}\t{sr}\t{gc}\t{gr}\t{length:.8f}")
    scen = path if path.suffix == ".scen" else path.with_suffix(".scen")
    scen.write_text("\n".join(lines) + "\n", encoding="ascii")
    return {"maps": len(maps), "map_files": [str(f) for f in files], "scen": str(scen), "problems": len(lines) - 1}


__all__ = ["MIN_FREE", "PASSABLE", "OBSTACLE", "read", "read_grid", "read_problems", "write", "write_map"]
