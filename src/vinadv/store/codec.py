"""Text formats of the `map_pairs` table (paper, Table 2: maps and paths as delimited strings), vectorised.

- map: its 0/1 rows joined by ';' — `"0110;1001"` (1 = obstacle); an N x N map is `N * (N + 1) - 1` characters.
- path: its `row,col` cells joined by ';' — `"3,4;3,5;4,6"`; an empty path is `""`.
- cell (start, goal, added obstacle): `"row,col"`.

Encoding and decoding work on whole batches with NumPy byte arrays, so there is no Python loop over cells.
Encoding writes a column, a cache-sized chunk at a time, as one ASCII text and cuts that into the strings (maps
by one slice each, paths by `str.split`); cells come from cached tables of ready-made strings and tokens.
Decoding reads fixed-width `S` arrays padded with NUL.

Rows: `encode_rows` turns `PairRecords` into `map_pairs` parameter tuples (`INSERT_COLUMNS`), `decode_rows` turns
rows read back (`PAIR_COLUMNS`) into `PairRecords`; `driver_insert_sql` is the plain INSERT statement they fit.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.paths import PackedPaths
from vinadv.store.records import PairRecords
from vinadv.store.schema import (
    EDIT_COLUMN,
    EFFORT_COLUMNS,
    HARM_COLUMNS,
    HARM_FLOAT_COLUMNS,
    MORE_ADDED_COLUMN,
    map_pairs,
)
from vinadv.vocabulary import ADD

if TYPE_CHECKING:
    import sqlalchemy as sa

_ZERO, _COMMA, _SEMI, _NEWLINE = ord("0"), ord(","), ord(";"), ord("\n")
_MAX_DIGITS = 5  # int16 cells: at most 32767
_POW10 = 10 ** np.arange(_MAX_DIGITS, dtype=np.int64)
_CHUNK_BYTES = 1 << 20  # maps and paths are encoded about this many bytes at a time (fits the L2 cache)


def _str_to_bytes_rows(texts: Sequence[str], what: str) -> tuple[np.ndarray, np.ndarray]:
    """list of n ASCII strings -> ((n, W) uint8 rows, NUL padded; (n,) lengths)."""
    try:
        arr = np.array(texts, dtype="S")  # ascii encode; raises on non-ascii
    except (UnicodeEncodeError, TypeError, ValueError) as exc:
        raise InputError(f"{what}: not an ASCII text column ({exc})") from None
    arr = arr.reshape(-1)
    width = arr.dtype.itemsize
    buf = arr.view(np.uint8).reshape(len(arr), width) if len(arr) else np.zeros((0, width), np.uint8)
    lengths = (buf != 0).sum(axis=1) if width else np.zeros(len(arr), np.int64)
    return buf, lengths.astype(np.int64)


# ----------------------------------------------------------------------------------------------- maps


def encode_maps(obstacles: np.ndarray) -> list[str]:
    """`obstacles` bool (n, N, N) -> n strings `"0110;1001;..."` (rows joined by ';', '1' = obstacle)."""
    obstacles = np.asarray(obstacles, dtype=bool)
    if obstacles.ndim != 3 or obstacles.shape[1] != obstacles.shape[2]:
        raise InputError(f"maps must have shape (n, N, N), got {obstacles.shape}")
    n, size, _ = obstacles.shape
    if size == 0:
        return [""] * n
    # every map as N lines of N digits + ';', back to back; a map's text is its first N * (N + 1) - 1 bytes.
    # A line is a record (N-byte row, ';'): the digits are made contiguously, then copied in as one N-byte item
    # per line (copying them into a strided (n, N, N + 1) byte array costs twice as much: one short inner loop
    # per row)
    row = np.dtype((np.void, size))
    line = np.dtype({"names": ["row", "semi"], "formats": [row, np.uint8], "offsets": [0, size], "itemsize": size + 1})
    stride = size * (size + 1)
    chunk = max(1, _CHUNK_BYTES // stride)
    digits = np.empty((min(n, chunk), size, size), dtype=np.uint8)
    lines = np.empty(len(digits) * size, dtype=line)
    lines["semi"] = _SEMI
    out: list[str] = []
    # chunk by chunk: cache-sized buffers, reused, instead of batch-sized ones freshly paged in
    for lo in range(0, n, chunk):
        m = min(chunk, n - lo)
        np.add(obstacles[lo : lo + m].view(np.uint8), _ZERO, out=digits[:m])
        lines["row"][: m * size] = digits[:m].view(row).reshape(-1)
        text = str(memoryview(lines[: m * size].view(np.uint8)), "ascii")
        # slicing is the cheapest way from one text to m fixed-width strings: ~0.2 us per 811-character map,
        # against ~0.4 us for str.split (which has to scan every character)
        out += [text[i : i + stride - 1] for i in range(0, m * stride, stride)]
    return out


def decode_maps(texts: Sequence[str], size: int | None = None) -> np.ndarray:
    """n map strings -> bool (n, N, N). All maps must have the same size (inferred unless given)."""
    n = len(texts)
    buf, lengths = _str_to_bytes_rows(list(texts), "map")
    if n == 0:
        return np.zeros((0, size or 0, size or 0), dtype=bool)
    length = int(lengths[0])
    if size is None:
        # N * (N + 1) - 1 = length  ->  N = (-1 + sqrt(5 + 4 * length)) / 2
        size = int(round((-1 + np.sqrt(5 + 4 * length)) / 2)) if length else 0
    if size == 0 and (lengths == 0).all():
        return np.zeros((n, 0, 0), dtype=bool)
    if (lengths != size * (size + 1) - 1).any():
        bad = int(np.flatnonzero(lengths != size * (size + 1) - 1)[0])
        raise InputError(
            f"map {bad}: {lengths[bad]} characters, expected {size * (size + 1) - 1} for a {size}x{size} map"
        )
    full = np.full((n, size * (size + 1)), _SEMI, dtype=np.uint8)
    full[:, :-1] = buf[:, : size * (size + 1) - 1]
    full = full.reshape(n, size, size + 1)
    cells = full[:, :, :size]
    if (full[:, :, size] != _SEMI).any() or ((cells != _ZERO) & (cells != _ZERO + 1)).any():
        wrong = (full[:, :, size] != _SEMI).any(1) | ((cells > _ZERO + 1) | (cells < _ZERO)).any((1, 2))
        bad = int(np.flatnonzero(wrong)[0])
        raise InputError(f"map {bad}: not 0/1 rows joined by ';': {texts[bad][:60]!r}")
    return cells == _ZERO + 1


# ---------------------------------------------------------------------------------------------- cells


def _n_digits(values: np.ndarray) -> np.ndarray:
    values = values.astype(np.int64)
    return 1 + (values >= 10) + (values >= 100) + (values >= 1000) + (values >= 10000)


def encode_cells(cells: np.ndarray) -> list[str]:
    """(n, 2) cells -> n strings `"row,col"`."""
    cells = np.asarray(cells, dtype=np.int64).reshape(-1, 2)
    side = _table_side(cells)
    if side:
        ids = cells[:, 0] * side + cells[:, 1]
        return _cell_strings(side)[ids].tolist()  # the cached str objects themselves: nothing is formatted
    return encode_paths(cells, np.arange(len(cells) + 1, dtype=np.int64))


def decode_cells(texts: Sequence[str]) -> np.ndarray:
    """n strings `"row,col"` -> int64 (n, 2)."""
    cells, offsets = decode_paths(texts)
    if (np.diff(offsets) != 1).any():
        bad = int(np.flatnonzero(np.diff(offsets) != 1)[0])
        raise InputError(f"cell {bad}: expected 'row,col', got {texts[bad]!r}")
    return cells.astype(np.int64)


# ---------------------------------------------------------------------------------------------- paths


def encode_paths(cells: np.ndarray, offsets: np.ndarray) -> list[str]:
    """Packed paths (cells (total, 2) non-negative ints, offsets (n + 1,)) -> n strings `"r,c;r,c;..."`."""
    cells = np.asarray(cells, dtype=np.int64).reshape(-1, 2)
    offsets = np.asarray(offsets, dtype=np.int64)
    n = len(offsets) - 1
    if n < 0 or offsets[0] != 0 or offsets[-1] != len(cells) or (np.diff(offsets) < 0).any():
        raise InputError(f"path offsets must run from 0 to {len(cells)} without decreasing")
    if len(cells) and (cells.min() < 0 or cells.max() >= 10**_MAX_DIGITS):
        raise InputError(f"path cells must be in [0, {10**_MAX_DIGITS}), got {cells.min()}..{cells.max()}")
    if len(cells) == 0:
        return [""] * n
    side = _table_side(cells)
    out: list[str] = []
    # chunk by chunk (whole paths, ~_CHUNK_BYTES of 8-byte padded tokens each), so the buffers stay in the cache
    lo = 0
    while lo < n:
        hi = max(lo + 1, int(np.searchsorted(offsets, offsets[lo] + _CHUNK_BYTES // 8, side="right")) - 1)
        out += _encode_path_chunk(cells[offsets[lo] : offsets[hi]], offsets[lo : hi + 1] - offsets[lo], side)
        lo = hi
    return out


def _encode_path_chunk(cells: np.ndarray, offsets: np.ndarray, side: int) -> list[str]:
    """`encode_paths` of checked packed paths (cells (T, 2) int64, offsets (m + 1,) from 0 to T); `side`: the
    token table to use (`_table_side`), 0 for none."""
    nonempty = offsets[1:] > offsets[:-1]
    last = offsets[1:][nonempty] - 1  # each non-empty path's last cell: its token ends in '\n', not ';'
    if side:
        ids = cells[:, 0] * side + cells[:, 1]
        ids[last] += side * side
        padded = _token_table(side)[ids]  # (T,) uint64: one 8-byte gather per cell
    else:
        padded, lengths = _token_chars(cells)
        padded[last, lengths[last] - 1] = _NEWLINE
    # every cell's "r,c;" back to back, in order: the non-empty paths as one text, each ending in '\n'
    # (tokens hold no NUL); str.split cuts it in C, faster than slicing per path
    texts = padded.tobytes().translate(None, b"\0").decode("ascii").split("\n")
    texts.pop()  # after the last '\n'
    if len(texts) == len(offsets) - 1:
        return texts
    out = np.full(len(offsets) - 1, "", dtype=object)
    out[nonempty] = texts
    return out.tolist()


_TABLE_SIDES = (32, 64, 128, 256)  # cached tables of cells with both values below one of these ("255,255;")


def _table_side(cells: np.ndarray) -> int:
    """The smallest `_TABLE_SIDES` above every value of `cells` (T, 2), 0 if none (or no cells, or a negative)."""
    if len(cells) == 0 or cells.min() < 0:
        return 0
    top = int(cells.max())
    return next((side for side in _TABLE_SIDES if top < side), 0)


@functools.cache
def _cell_strings(side: int) -> np.ndarray:
    """object (side**2,): the str "r,c" of cell (r, c) at r * side + c (built once per side)."""
    r, c = np.divmod(np.arange(side * side), side)
    return np.array([f"{a},{b}" for a, b in zip(r.tolist(), c.tolist())], dtype=object)


@functools.cache
def _token_table(side: int) -> np.ndarray:
    """uint64 (2 * side**2,): the token "r,c;" of cell (r, c) at r * side + c, and "r,c\\n" (a path's last cell)
    at side**2 + r * side + c, as ASCII bytes NUL padded to 8 (built once per side; 1 MB for side 256)."""
    r, c = np.divmod(np.arange(side * side), side)
    chars, lengths = _token_chars(np.stack([r, c], axis=1))
    assert lengths.max() <= 8
    last = chars.copy()
    last[np.arange(len(last)), lengths - 1] = _NEWLINE
    return np.concatenate([chars[:, :8], last[:, :8]]).view(np.uint64).reshape(-1)


def _token_chars(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T, 2) cells -> ("r,c;" as (T, 12) uint8 NUL padded, (T,) lengths), digit position by digit position."""
    rows, cols = cells[:, 0], cells[:, 1]
    nd_r, nd_c = _n_digits(rows), _n_digits(cols)
    chars = np.zeros((len(cells), 2 * _MAX_DIGITS + 2), dtype=np.uint8)
    t = np.arange(len(cells))
    for digit in range(_MAX_DIGITS):  # loop over digit positions (5), not over cells
        has = digit < nd_r
        chars[t[has], digit] = (rows[has] // _POW10[nd_r[has] - 1 - digit]) % 10 + _ZERO
        has = digit < nd_c
        chars[t[has], nd_r[has] + 1 + digit] = (cols[has] // _POW10[nd_c[has] - 1 - digit]) % 10 + _ZERO
    chars[t, nd_r] = _COMMA
    chars[t, nd_r + nd_c + 1] = _SEMI
    return chars, nd_r + nd_c + 2


def decode_paths(texts: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """n path strings -> packed paths (cells int16 (total, 2), offsets int64 (n + 1,))."""
    n = len(texts)
    buf, lengths = _str_to_bytes_rows(list(texts), "path")
    offsets = np.zeros(n + 1, dtype=np.int64)
    if n == 0 or not lengths.any():
        return np.zeros((0, 2), dtype=np.int16), offsets
    width = buf.shape[1]
    # append a ';' terminator to every non-empty path, then read all paths as one stream
    ext = np.zeros((n, width + 1), dtype=np.uint8)
    ext[:, :width] = buf
    nonempty = lengths > 0
    ext[np.flatnonzero(nonempty), lengths[nonempty]] = _SEMI
    n_cells = (ext == _SEMI).sum(axis=1)
    stream = ext[ext != 0]
    is_digit = (stream >= _ZERO) & (stream <= _ZERO + 9)
    is_sep = (stream == _COMMA) | (stream == _SEMI)
    sep_pos = np.flatnonzero(is_sep)
    seps = stream[sep_pos]
    n_tokens = len(sep_pos)
    expected = np.tile(np.array([_COMMA, _SEMI], dtype=np.uint8), n_tokens // 2 + 1)[:n_tokens]
    token_start = np.concatenate([[0], sep_pos[:-1] + 1])
    if (
        not (is_digit | is_sep).all()
        or n_tokens % 2
        or (seps != expected).any()
        or (sep_pos - token_start < 1).any()
        or (sep_pos - token_start > _MAX_DIGITS).any()
    ):
        # find the offending path for the message (error path only, so a loop is fine)
        for i, text in enumerate(texts):
            if text and not _is_path(text):
                raise InputError(f"path {i}: not 'row,col' cells joined by ';': {text[:60]!r}")
        raise InputError("paths: malformed path text")
    token_of_char = np.cumsum(is_sep) - is_sep  # token id of each char
    digit_idx = np.flatnonzero(is_digit)
    tok = token_of_char[digit_idx]
    power = sep_pos[tok] - digit_idx - 1
    values = np.bincount(tok, weights=(stream[digit_idx] - _ZERO) * _POW10[power], minlength=n_tokens)
    values = np.rint(values).astype(np.int64)
    if values.max(initial=0) > np.iinfo(np.int16).max:
        raise InputError(f"paths: cell value {values.max()} does not fit int16")
    np.cumsum(n_cells, out=offsets[1:])
    return values.reshape(-1, 2).astype(np.int16), offsets


def _is_path(text: str) -> bool:
    for cell in text.split(";"):
        parts = cell.split(",")
        if len(parts) != 2 or not all(p.isdigit() and p.isascii() and 0 < len(p) <= _MAX_DIGITS for p in parts):
            return False
    return True


# ------------------------------------------------------------------------------------ rows

#: columns read back, in order (`decode_rows` relies on it)
PAIR_COLUMNS = (
    "no",
    "pair_index",
    "map_o",
    "map_a",
    "path_o",
    "path_a",
    "label",
    "attack",
    "start",
    "goal",
    "added_obstacle",
    "label_source",
    "score",
    "term_o",
    "term_a",
    "dh",
    "dv",
    *HARM_COLUMNS,
    MORE_ADDED_COLUMN,
    EDIT_COLUMN,
    *EFFORT_COLUMNS,
)


#: columns written by `encode_rows`, in order: those read back, with the run instead of the row number
INSERT_COLUMNS = ("run_id", *PAIR_COLUMNS[1:])


def driver_insert_sql(dialect: sa.Dialect, rows: int = 1) -> str | None:
    """A plain `INSERT INTO map_pairs (...) VALUES (?, ...)` of `rows` rows (flat parameters, row after row) in the
    driver's positional paramstyle, or None.

    For SQLite it takes `encode_rows(..., sqlite=True)` rows (dh and dv as `NULLIF(?, -1)`, added_more as
    `NULLIF(?, '')`, as are the expanded cells; A*'s counts as `NULLIF(?, -1)`)."""
    marker = {"qmark": "?", "format": "%s", "pyformat": "%s"}.get(dialect.paramstyle)
    if marker is None:
        return None
    prep = dialect.identifier_preparer
    names = ", ".join(prep.quote(name) for name in INSERT_COLUMNS)
    sqlite_null = {"dh": "-1", "dv": "-1", MORE_ADDED_COLUMN: "''", "expanded_o": "''", "expanded_a": "''"}
    sqlite_null.update({"astar_expansions_o": "-1", "astar_expansions_a": "-1"})
    if dialect.name != "sqlite":
        sqlite_null = {}
    values = [
        f"NULLIF({marker}, {sqlite_null[name]})" if name in sqlite_null else marker  # see encode_rows
        for name in INSERT_COLUMNS
    ]
    group = f"({', '.join(values)})"
    return f"INSERT INTO {prep.format_table(map_pairs)} ({names}) VALUES {', '.join([group] * rows)}"


def encode_rows(
    run_id: int, records: PairRecords, lo: int = 0, hi: int | None = None, *, sqlite: bool = False
) -> list[tuple]:
    """Records `lo:hi` (default all) -> parameter tuples in `INSERT_COLUMNS` order, text columns encoded in bulk.

    NULLs are None and `attack` a bool, unless `sqlite`: then rows take SQLite's native form, holding only ints,
    floats and strs, which the sqlite3 module binds without looking for an adapter (it does for any other value,
    bool and None included: ~0.5 us each): `attack` 0/1, a NULL score a NaN (SQLite stores a NaN as NULL), a NULL
    dh/dv -1 (`driver_insert_sql` wraps them in `NULLIF(?, -1)`), a NULL harm cost a NaN, a NULL added_more ''
    (`NULLIF(?, '')`), NULL expanded cells '' and a NULL A* count -1 (the same).
    """
    return list(zip(*encode_columns(run_id, records, lo, hi, sqlite)))


def encode_columns(run_id: int, records: PairRecords, lo: int, hi: int | None, sqlite: bool) -> list:
    """The `INSERT_COLUMNS` of records `lo:hi`, one list of n values each.

    Reads the row range through views (no copy of the records, unlike `PairRecords.subset`).
    """
    hi = len(records) if hi is None else min(hi, len(records))
    lo = min(max(lo, 0), hi)
    n = hi - lo
    rows = slice(lo, hi)

    def path(name: str) -> list[str]:
        paths = getattr(records, name)
        offsets = paths.offsets[lo : hi + 1]
        cells = paths.cells[offsets[0] : offsets[-1]]
        return encode_paths(cells, offsets - offsets[0])

    def expanded(side: str) -> list:
        """The expanded cells as path text; NULL where none are reported (an empty list, or no column)."""
        if getattr(records, f"expanded_{side}") is None:
            return ["" if sqlite else None] * n
        texts = path(f"expanded_{side}")
        return texts if sqlite else [t or None for t in texts]

    def count(side: str) -> list:
        values = getattr(records, f"astar_expansions_{side}")
        if values is None:
            return [-1 if sqlite else None] * n
        return nullable(values[rows], values[rows] < 1)

    def nullable(values: np.ndarray, null: np.ndarray) -> list:
        if sqlite:
            return values.tolist()  # NaN and -1 stand for NULL (see `encode_rows`)
        out = values.astype(object)
        out[null] = None
        return out.tolist()

    score, dh, dv = records.score[rows], records.dh[rows], records.dv[rows]
    attack = records.attack[rows]
    columns = {
        "run_id": [int(run_id)] * n,
        "pair_index": records.pair_index[rows].tolist(),
        "map_o": encode_maps(records.obstacles_o[rows]),
        "map_a": encode_maps(records.obstacles_a[rows]),
        "path_o": path("path_o"),
        "path_a": path("path_a"),
        "label": records.label[rows].tolist(),
        "attack": (attack.astype(np.int64) if sqlite else attack).tolist(),
        "start": encode_cells(records.starts[rows]),
        "goal": encode_cells(records.goals[rows]),
        "added_obstacle": encode_cells(records.added[rows, 0]),
        "label_source": records.label_source[rows].tolist(),
        "score": nullable(score, np.isnan(score)),
        "term_o": records.term_o[rows].tolist(),
        "term_a": records.term_a[rows].tolist(),
        "dh": nullable(dh, dh < 0),
        "dv": nullable(dv, dv < 0),
        **{
            name: nullable(getattr(records, name)[rows], np.isnan(getattr(records, name)[rows]))
            for name in HARM_FLOAT_COLUMNS
        },
        "expert_label": records.expert_label[rows].tolist(),  # None = NULL
        "harm": records.harm[rows].tolist(),
        MORE_ADDED_COLUMN: _encode_more_added(records.added[rows], "" if sqlite else None),
        EDIT_COLUMN: records.edit[rows].tolist(),
        "expanded_o": expanded("o"),
        "expanded_a": expanded("a"),
        "astar_expansions_o": count("o"),
        "astar_expansions_a": count("a"),
    }
    assert tuple(columns) == INSERT_COLUMNS
    return list(columns.values())


def _encode_more_added(added: np.ndarray, null) -> list:
    """`added_more` of `added (n, K, 2)`: the cells after the first as path text, `null` for every row when K = 1."""
    n, k = added.shape[:2]
    if k == 1:
        return [null] * n
    return encode_paths(added[:, 1:].reshape(-1, 2), np.arange(n + 1, dtype=np.int64) * (k - 1))


def _decode_added(first: Sequence[str], more: Sequence[str | None]) -> np.ndarray:
    """`(n, K, 2)` added cells from `added_obstacle` and `added_more` texts (None: none after the first); every row
    must add as many cells (InputError otherwise: read one run's pairs at a time)."""
    first_cells = decode_cells(first).reshape(-1, 1, 2)
    if all(m is None for m in more):
        return first_cells
    cells, offsets = decode_paths(["" if m is None else m for m in more])
    counts = np.diff(offsets)
    if (counts != counts[0]).any():
        raise InputError(
            f"map_pairs: rows with different numbers of added obstacles ({sorted(set(counts + 1))}) "
            "in one read; read one run at a time"
        )
    rest = cells.astype(np.int64).reshape(len(first_cells), int(counts[0]), 2)
    return np.concatenate([first_cells, rest], axis=1)


def _decode_effort(col: dict) -> dict:
    """The search-effort fields of decoded rows: None for each where no row has it (NULL), else the cells
    (`PackedPaths`, an empty list for a NULL row) and the counts (-1 for NULL)."""
    out: dict = {}
    for side in ("o", "a"):
        texts = col[f"expanded_{side}"]
        if any(t is not None for t in texts):
            out[f"expanded_{side}"] = PackedPaths(*decode_paths(["" if t is None else t for t in texts]))
        counts = col[f"astar_expansions_{side}"]
        if any(c is not None for c in counts):
            out[f"astar_expansions_{side}"] = np.array([-1 if c is None else c for c in counts], dtype=np.int64)
    return out


def decode_rows(rows: Sequence) -> PairRecords:
    """Rows of `PAIR_COLUMNS` -> PairRecords (text columns decoded in bulk)."""
    cols = list(zip(*rows)) if rows else [()] * len(PAIR_COLUMNS)
    col = dict(zip(PAIR_COLUMNS, cols))
    path_o = decode_paths(col["path_o"])
    path_a = decode_paths(col["path_a"])
    map_o = decode_maps(col["map_o"])
    map_a = decode_maps(col["map_a"], size=map_o.shape[-1] if len(rows) else None)

    def nullable(values, fill, dtype):
        return np.array([fill if v is None else v for v in values], dtype=dtype).reshape(-1)

    return PairRecords(
        no=np.array(col["no"], dtype=np.int64).reshape(-1),
        pair_index=np.array(col["pair_index"], dtype=np.int64).reshape(-1),
        obstacles_o=map_o,
        obstacles_a=map_a,
        starts=decode_cells(col["start"]).reshape(-1, 2),
        goals=decode_cells(col["goal"]).reshape(-1, 2),
        added=_decode_added(col["added_obstacle"], col[MORE_ADDED_COLUMN]),
        path_o=PackedPaths(*path_o),
        path_a=PackedPaths(*path_a),
        label=np.array(col["label"], dtype=object),
        attack=np.array([bool(a) for a in col["attack"]], dtype=bool),
        term_o=np.array(col["term_o"], dtype=object),
        term_a=np.array(col["term_a"], dtype=object),
        label_source=np.array(col["label_source"], dtype=object),
        score=nullable(col["score"], np.nan, np.float64),
        dh=nullable(col["dh"], -1, np.int64),
        dv=nullable(col["dv"], -1, np.int64),
        **{name: nullable(col[name], np.nan, np.float64) for name in HARM_FLOAT_COLUMNS},
        expert_label=np.array(col["expert_label"], dtype=object),
        harm=np.array(col["harm"], dtype=object),
        edit=np.array([ADD if e is None else e for e in col[EDIT_COLUMN]], dtype=str).reshape(-1),  # NULL reads as add
        **_decode_effort(col),
    )
