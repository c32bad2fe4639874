"""Writing a figure: the image format by the file name, the one atomic save.

`vinadv.plot` leaves matplotlib's backend alone (a notebook keeps its inline one); what draws with no display (the
commands, the report) chooses Agg itself."""

from __future__ import annotations

import io
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


#: how an SVG is written: text kept as text, fixed ids (no random salt), so the same figure gives the same bytes
SVG_RC = {"svg.hashsalt": "vinadv", "svg.fonttype": "none"}


def save_figure(fig, path: str | os.PathLike) -> None:
    """Save and close `fig`; the format follows the file extension (png, svg, pdf; see `figure_format`). An SVG
    has no date and fixed ids (`SVG_RC`): the same figure, the same bytes."""
    try:
        fmt = figure_format(path)
        svg = fmt == "svg"
        with atomic_output(path, "wb") as fh, plt.rc_context(SVG_RC if svg else {}):
            fig.savefig(fh, format=fmt, dpi=150, bbox_inches="tight", metadata={"Date": None} if svg else None)
    finally:
        plt.close(fig)


def svg_text(fig) -> str:
    """`fig` as SVG text, then closed: text kept as text, no date and fixed ids, so the same figure gives the same
    bytes (a docs page that inlines it changes only when its data does)."""
    buffer = io.StringIO()
    try:
        with plt.rc_context(SVG_RC):
            fig.savefig(buffer, format="svg", metadata={"Date": None}, bbox_inches="tight")
    finally:
        plt.close(fig)
    return buffer.getvalue()
