"""Writing a figure: the image format by the file name, the one atomic save.

`vinadv.plot` leaves matplotlib's backend alone (a notebook keeps its inline one); what draws with no display (the
commands, the report) chooses Agg itself."""

from __future__ import annotations

import os

import matplotlib.pyplot as plt
from matplotlib.backend_bases import FigureCanvasBase

from vinadv.errors import InputError
from vinadv.outfile import atomic_output


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
