"""Text formats of the `map_pairs` table (paper, Table 2: maps and paths as delimited strings), vectorised.

- map: its 0/1 rows joined by ';' — `"0110;1001"` (1 = obstacle); an N x N map is `N * (N + 1) - 1` characters.
- path: its `row,col` cells joined by ';' — `"3,4;3,5;4,6"`; an empty path is `""`.
- cell (start, goal, added obstacle): `"row,col"`.

Encoding and decoding work on whole batches with NumPy byte arrays (fixed-width `S` arrays padded with NUL,
which NumPy strips when it turns them into Python strings), so there is no Python loop over cells.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vinadv.errors import InputError

_ZERO, _COMMA, _SEMI = ord("0"), ord(","), ord(";")
_MAX_DIGITS = 5  # int16 cells: at most 32767
_POW10 = 10 ** np.arange(_MAX_DIGITS, dtype=np.int64)


def _bytes_rows_to_str(buf: np.ndarray, lengths: np.ndarray | None = None) -> list[str]:
    """(n, W) uint8 ASCII rows -> n Python strings, row i cut to `lengths[i]` (default W).

    One ASCII decode of the whole buffer, then slicing (each row string has to be built anyway); about
    twice as fast as going through a NumPy unicode array.
    """
    n, width = buf.shape
    if width == 0:
        return [""] * n
    text = np.ascontiguousarray(buf).tobytes().decode("ascii")
    starts = np.arange(n, dtype=np.int64) * width
    ends = starts + (width if lengths is None else np.asarray(lengths, dtype=np.int64))
    return [text[a:b] for a, b in zip(starts.tolist(), ends.tolist())]


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
    buf = np.full((n, size, size + 1), _SEMI, dtype=np.uint8)
    buf[:, :, :size] = obstacles.view(np.uint8) + _ZERO
    width = size * (size + 1)
    return _bytes_rows_to_str(buf.reshape(n, width), np.full(n, width - 1))  # no ';' after the last row


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
        raise InputError(f"map {bad}: {lengths[bad]} characters, expected {size * (size + 1) - 1} for a {size}x{size} map")
    full = np.full((n, size * (size + 1)), _SEMI, dtype=np.uint8)
    full[:, :-1] = buf[:, : size * (size + 1) - 1]
    full = full.reshape(n, size, size + 1)
    cells = full[:, :, :size]
    if (full[:, :, size] != _SEMI).any() or ((cells != _ZERO) & (cells != _ZERO + 1)).any():
        bad = int(np.flatnonzero(((full[:, :, size] != _SEMI).any(1)) | ((cells > _ZERO + 1) | (cells < _ZERO)).any((1, 2)))[0])
        raise InputError(f"map {bad}: not 0/1 rows joined by ';': {texts[bad][:60]!r}")
    return cells == _ZERO + 1


# ---------------------------------------------------------------------------------------------- cells


def _n_digits(values: np.ndarray) -> np.ndarray:
    values = values.astype(np.int64)
    return 1 + (values >= 10) + (values >= 100) + (values >= 1000) + (values >= 10000)


def encode_cells(cells: np.ndarray) -> list[str]:
    """(n, 2) cells -> n strings `"row,col"`."""
    cells = np.asarray(cells).reshape(-1, 2)
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
    value_range = int(cells.max()) + 1
    if value_range <= _TABLE_MAX:
        # tokens "r,c;" from a table of every (r, c) below value_range (cached), column-major
        table_t, table_len = _token_table(value_range)
        token_id = cells[:, 0] * value_range + cells[:, 1]
        token = table_len[token_id]
        columns = [table_t[j][token_id] for j in range(table_t.shape[0])]
    else:
        chars, token = _token_chars(cells)
        columns = list(chars.T)
    path_of_cell = np.repeat(np.arange(n), np.diff(offsets))
    ends = np.cumsum(token)
    before = np.concatenate([[0], ends])[offsets[:-1]]  # characters before each path's first cell
    lengths = np.concatenate([[0], ends])[offsets[1:]] - before  # includes the last cell's ';'
    width = int(lengths.max())
    pos = path_of_cell * width + (ends - token - before[path_of_cell])  # flat index of each cell's first char
    out = np.zeros(n * width + len(columns), dtype=np.uint8)
    # Write token columns last to first: a token's NUL padding lands on the next token's start, whose own
    # (earlier) columns are written after and win, so no mask is needed.
    for j in range(len(columns) - 1, -1, -1):
        out[pos + j] = columns[j]
    out = out[: n * width].reshape(n, width)
    return _bytes_rows_to_str(out, np.maximum(lengths - 1, 0))  # drop the last cell's ';'


_TABLE_MAX = 256  # token table for cells below this: 65,536 tokens x 8 bytes
_TOKEN_TABLES: dict[int, tuple[np.ndarray, np.ndarray]] = {}


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


def _token_table(value_range: int) -> tuple[np.ndarray, np.ndarray]:
    """Tokens "r,c;" for all r, c < value_range: (chars (width, V*V) uint8 column-major, lengths (V*V,)),
    token r * value_range + c (cached)."""
    if value_range not in _TOKEN_TABLES:
        r, c = np.divmod(np.arange(value_range * value_range), value_range)
        chars, lengths = _token_chars(np.stack([r, c], axis=1))
        width = int(lengths.max())
        _TOKEN_TABLES[value_range] = (np.ascontiguousarray(chars[:, :width].T), lengths)
    return _TOKEN_TABLES[value_range]


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
