"""PNG images of one stored pair, rendered on the server: the original map, the adversarial map and the path
image, with an LRU cache so that paging back and forth never renders a pair twice.

Maps are drawn with `vinadv.plot.draw_map` (in `vinadv.plot.palette`'s colours) on a bare
`matplotlib.figure.Figure` (no pyplot state, so rendering is safe from the server's threads; a lock still serialises
it, Agg is not fast enough in parallel on two cores to matter). The path image is the classifier's input
(`render_path_images`, DESIGN.md colours), scaled up by whole pixels so every cell stays a crisp square.
"""

from __future__ import annotations

import io
import threading
from collections import OrderedDict

import numpy as np

from vinadv.classify.images import render_path_images
from vinadv.plot.thumbnails import thumbnail_images
from vinadv.store.records import PairRecords

#: the images of a pair, in page order
KINDS = ("original", "adversarial", "pathimage")
#: pixels per cell of the path image
PATH_IMAGE_SCALE = 10
_MAP_INCHES = 3.2
_MAP_DPI = 100


class PngCache:
    """A thread-safe LRU cache of PNG bytes, keyed by any hashable key; `max_bytes` bounds its memory."""

    def __init__(self, max_bytes: int = 64 * 2**20) -> None:
        self.max_bytes = int(max_bytes)
        self._items: OrderedDict = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()
        self.hits = 0
        self.misses = 0

    def get(self, key):
        with self._lock:
            png = self._items.get(key)
            if png is None:
                self.misses += 1
                return None
            self._items.move_to_end(key)
            self.hits += 1
            return png

    def put(self, key, png: bytes) -> None:
        with self._lock:
            if key in self._items:
                self._bytes -= len(self._items.pop(key))
            self._items[key] = png
            self._bytes += len(png)
            while self._bytes > self.max_bytes and len(self._items) > 1:
                _, old = self._items.popitem(last=False)
                self._bytes -= len(old)

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key) -> bool:
        with self._lock:
            return key in self._items


_render_lock = threading.Lock()


def render_pair_png(records: PairRecords, i: int, kind: str, expanded: np.ndarray | None = None) -> bytes:
    """PNG bytes of image `kind` (one of KINDS) of pair `i` of `records`; `expanded`: the cells `(k, 2)` the planner's
    search expanded on that map (a search planner's pair), tinted under the paths, or None."""
    if kind == "pathimage":
        return _path_image_png(records, i)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from vinadv.plot.maps import as_pair, draw_map  # noqa: PLC0415 (Matplotlib: only the map images need it)

    pair = as_pair(records, i)
    paths = []
    if kind == "original":
        obstacles, added, title = pair.obstacles_o, None, "original map, original path"
        if len(pair.path_o):
            paths.append(("original", pair.path_o))
    elif kind == "adversarial":
        obstacles, added, title = pair.obstacles_a, pair.added, "adversarial map, both paths"
        if len(pair.path_o):
            paths.append(("original", pair.path_o))
        if len(pair.path_a):
            paths.append(("adversarial", pair.path_a))
    else:
        raise ValueError(f"unknown image kind {kind!r}")
    if expanded is not None:
        title += ", expanded cells"
    with _render_lock:
        fig = Figure(figsize=(_MAP_INCHES, _MAP_INCHES), dpi=_MAP_DPI)
        FigureCanvasAgg(fig)
        ax = fig.add_axes((0.02, 0.02, 0.96, 0.9))
        draw_map(
            ax,
            obstacles,
            goal=pair.goal,
            start=pair.start,
            paths=paths,
            added=added,
            title=title,
            removed=pair.removed,
            expanded=expanded,
        )
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=_MAP_DPI)
    return buf.getvalue()


def _path_image_png(records: PairRecords, i: int) -> bytes:
    from PIL import Image

    image = render_path_images(records.path_o.take([i]), records.path_a.take([i]), records.size)[0]
    big = np.repeat(np.repeat(image, PATH_IMAGE_SCALE, axis=0), PATH_IMAGE_SCALE, axis=1)
    buf = io.BytesIO()
    Image.fromarray(big, mode="RGB").save(buf, format="PNG", optimize=False)
    return buf.getvalue()


def render_thumbnails(records: PairRecords, expanded: tuple[np.ndarray, np.ndarray] | None = None) -> list[bytes]:
    """PNG bytes of the thumbnails of every pair of `records` (`vinadv.plot.thumbnails`, drawn in one pass);
    `expanded`: packed cells `(cells, offsets)` the search expanded on each adversarial map, or None."""
    from PIL import Image

    images = thumbnail_images(
        records.obstacles_a,
        records.starts,
        records.goals,
        records.added,
        records.removes,
        (records.path_o.cells, records.path_o.offsets),
        (records.path_a.cells, records.path_a.offsets),
        expanded=expanded,
    )
    out = []
    for image in images:
        buf = io.BytesIO()
        # the fastest compression: a thumbnail is a few KB whatever the level, and encoding is most of its cost
        Image.fromarray(image, mode="RGB").save(buf, format="PNG", compress_level=1)
        out.append(buf.getvalue())
    return out
