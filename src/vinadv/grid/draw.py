"""Drawing maps and paths with matplotlib (Agg; no display needed). Downstream stages reuse these."""

from __future__ import annotations

import os
from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.backend_bases import FigureCanvasBase  # noqa: E402
from matplotlib.layout_engine import ConstrainedLayoutEngine  # noqa: E402

from vinadv.errors import InputError  # noqa: E402
from vinadv.outfile import atomic_output  # noqa: E402

PATH_STYLES = {"expert": ("#2ca02c", "-"), "original": ("#d62728", "-"), "adversarial": ("#1f77b4", "--")}


def draw_map(
    ax,
    obstacles: np.ndarray,
    goal: np.ndarray | None = None,
    start: np.ndarray | None = None,
    paths: Sequence[tuple[str, np.ndarray]] = (),
    added: np.ndarray | None = None,
    title: str | None = None,
    removed: bool = False,
) -> None:
    """Draw one N x N map on `ax`: obstacles black, start green circle, goal red star, paths as lines.

    `start` is one cell `(2,)` or several `(k, 2)` (each gets a marker). `paths` is a sequence of
    `(label, cells (L, 2))`; a label in PATH_STYLES gets its colour. `added`, one cell `(2,)` or several `(k, 2)`,
    marks the adversarial obstacles with orange squares; with `removed` (edit `remove`) they are freed cells, drawn as
    orange outlines. Every artist carries its label, for `map_legend`.
    """
    n = obstacles.shape[0]
    ax.imshow(~np.asarray(obstacles, dtype=bool), cmap="gray", vmin=0, vmax=1, interpolation="nearest")
    for label, cells in paths:
        colour, style = PATH_STYLES.get(label, (None, "-"))
        cells = np.asarray(cells)
        ax.plot(cells[:, 1], cells[:, 0], style, color=colour, lw=2, label=label, alpha=0.9)
    if added is not None:
        cells = np.asarray(added).reshape(-1, 2)
        what = "removed obstacle" if removed else "added obstacle"
        for k, (r, c) in enumerate(cells):
            label = (what if len(cells) == 1 else what + "s") if k == 0 else None
            if removed:
                square = plt.Rectangle((c - 0.45, r - 0.45), 0.9, 0.9, fill=False, ec="#ff7f0e", lw=2, label=label)
            else:
                square = plt.Rectangle((c - 0.5, r - 0.5), 1, 1, color="#ff7f0e", label=label)
            ax.add_patch(square)
    if start is not None:
        starts = np.asarray(start).reshape(-1, 2)
        ax.plot(
            starts[:, 1],
            starts[:, 0],
            "o",
            color="#2ca02c",
            ms=8,
            mec="k",
            ls="none",
            label="start" if len(starts) == 1 else "starts",
        )
    if goal is not None:
        ax.plot(goal[1], goal[0], "*", color="#d62728", ms=13, mec="k", label="goal")
    ax.set_xlim(-0.5, n - 0.5)
    ax.set_ylim(n - 0.5, -0.5)
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=9)


def map_legend(fig, axes, **kwargs) -> None:
    """One legend for the maps of `fig` (the start and goal markers, the added obstacle, the paths), below them:
    every labelled artist of `axes`, each label once."""
    handles: dict = {}
    for ax in np.asarray(axes).ravel():
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    if handles:
        # under constrained layout an "outside" legend gets its own room; else it hangs below the axes
        place = (
            {"loc": "outside lower center"}
            if isinstance(fig.get_layout_engine(), ConstrainedLayoutEngine)
            else {"loc": "lower center", "bbox_to_anchor": (0.5, -0.02)}
        )
        options = {**place, "ncol": min(len(handles), 5), "fontsize": 8, "frameon": False, **kwargs}
        fig.legend(list(handles.values()), list(handles), **options)


def figure_format(path: str | os.PathLike) -> str | None:
    """The image format of the file `path` by its extension (png, svg, pdf, ...; None without one: png); InputError
    naming the path when matplotlib writes no such format."""
    fmt = os.path.splitext(os.fspath(path))[1].lstrip(".").lower() or None
    supported = FigureCanvasBase.get_supported_filetypes()
    if fmt is not None and fmt not in supported:
        raise InputError(f"out: {os.fspath(path)!r} is no image file name (use .png, .svg or .pdf)", "out")
    return fmt


def save_figure(fig, path: str | os.PathLike) -> None:
    """Save and close `fig`; the format follows the file extension (png, svg, pdf; see `figure_format`)."""
    try:
        fmt = figure_format(path)
        with atomic_output(path, "wb") as fh:
            fig.savefig(fh, format=fmt, dpi=150, bbox_inches="tight")
    finally:
        plt.close(fig)
