"""Thumbnails of pairs: the adversarial map with both paths, its edited cells and the search's expanded cells, drawn
straight into pixels in `PALETTE`'s colours, a batch of pairs in one NumPy pass (the viewer's pair list: no
matplotlib figure per pair).

Each cell is a square block of `scale` pixels. Free cells white, obstacles black, expanded cells the pale tint, an
added obstacle a filled orange block, a freed cell an orange ring; the original path fills its blocks red, the
adversarial path the blocks' insides blue (so a cell on both shows a red ring round a blue centre, as the dashed blue
line over the red one of the full drawing); the start a green and the goal a red block, each with a black edge.
"""

from __future__ import annotations

import numpy as np

from vinadv.plot.palette import PALETTE, Style

#: the largest side of a thumbnail, pixels (the scale is the whole number of pixels per cell that fits)
THUMBNAIL_PIXELS = 112


def thumbnail_scale(size: int, pixels: int = THUMBNAIL_PIXELS) -> int:
    """Pixels per cell of an `size x size` map's thumbnail: as many whole pixels as fit in `pixels`, at least 1."""
    return max(1, pixels // max(1, int(size)))


def _cell_mask(n: int, size: int, cells: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """`(n, size, size)` bool: True at each `cells[i]` `(k, 2)` of pair `owner[i]`."""
    mask = np.zeros((n, size, size), bool)
    if len(cells):
        mask[owner, cells[:, 0], cells[:, 1]] = True
    return mask


def _packed_mask(n: int, size: int, cells: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """The cells of n packed cell lists (`cells (total, 2)`, `offsets (n + 1,)`) as `(n, size, size)` bool."""
    owner = np.repeat(np.arange(n), np.diff(offsets))
    return _cell_mask(n, size, np.asarray(cells, dtype=np.int64).reshape(-1, 2), owner)


def _block(scale: int, part: str) -> np.ndarray:
    """The pixels of one cell's block that a `part` covers: `full`, `inner` (all but a 1-pixel edge, or the whole
    block below 3 pixels) or `edge` (that edge; none below 3 pixels)."""
    full = np.ones((scale, scale), bool)
    if scale < 3:
        return full if part != "edge" else ~full
    inner = np.zeros((scale, scale), bool)
    inner[1:-1, 1:-1] = True
    return {"full": full, "inner": inner, "edge": ~inner}[part]


def _paint(image: np.ndarray, cells: np.ndarray, style: Style, scale: int, part: str = "full") -> None:
    """Paint the `part` of the blocks of `cells` (`(n, N, N)` bool) in `style`'s colour, in place: only the pixels
    of those blocks are written."""
    n, size = cells.shape[0], cells.shape[1]
    blocks = image.reshape(n, size, scale, size, scale, 3)  # a view: [pair, row, y, col, x]
    pair, row, col = np.nonzero(cells)
    y, x = np.nonzero(_block(scale, part))
    blocks[pair[:, None], row[:, None], y[None], col[:, None], x[None]] = style.rgb


def thumbnail_images(
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    added: np.ndarray,
    removed: np.ndarray,
    path_o: tuple[np.ndarray, np.ndarray],
    path_a: tuple[np.ndarray, np.ndarray],
    expanded: tuple[np.ndarray, np.ndarray] | None = None,
    scale: int | None = None,
) -> np.ndarray:
    """Thumbnails of n pairs as `(n, N * scale, N * scale, 3)` uint8 RGB (module doc).

    `obstacles`: the adversarial maps `(n, N, N)` bool; `starts`, `goals` `(n, 2)`; `added` `(n, K, 2)` the edited
    cells, `removed` `(n,)` bool (the pair frees them); `path_o`, `path_a`: packed paths `(cells (total, 2),
    offsets (n + 1,))`; `expanded`: the cells the search expanded on each adversarial map, packed as the paths, or None;
    `scale`: pixels per cell (default `thumbnail_scale`)."""
    obstacles = np.asarray(obstacles, dtype=bool)
    n, size = obstacles.shape[0], obstacles.shape[1]
    scale = thumbnail_scale(size) if scale is None else int(scale)
    if n == 0:
        return np.zeros((0, size * scale, size * scale, 3), np.uint8)
    cells = np.where(obstacles[..., None], PALETTE.obstacle.rgb, PALETTE.free.rgb).astype(np.uint8)
    if expanded is not None:
        cells[_packed_mask(n, size, *expanded) & ~obstacles] = PALETTE.expanded.rgb
    image = np.repeat(np.repeat(cells, scale, axis=1), scale, axis=2)
    edited = np.asarray(added, dtype=np.int64).reshape(n, -1, 2)
    owner = np.repeat(np.arange(n), edited.shape[1])
    edited_mask = _cell_mask(n, size, edited.reshape(-1, 2), owner)
    freed = np.asarray(removed, dtype=bool).reshape(n)
    _paint(image, edited_mask & ~freed[:, None, None], PALETTE.added, scale)
    _paint(image, edited_mask & freed[:, None, None], PALETTE.removed, scale, "edge")
    _paint(image, _packed_mask(n, size, *path_o), PALETTE.original, scale)
    _paint(image, _packed_mask(n, size, *path_a), PALETTE.adversarial, scale, "inner")
    for style, where in ((PALETTE.start, starts), (PALETTE.goal, goals)):
        mask = _cell_mask(n, size, np.asarray(where, dtype=np.int64).reshape(n, 2), np.arange(n))
        _paint(image, mask, PALETTE.edge, scale)
        _paint(image, mask, style, scale, "inner")
    return image
