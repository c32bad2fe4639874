"""Reports that skip work on their figures, for the tests that do not check them: a figure is saved once per format
(`vinadv.report.figures.FORMATS`: PNG and SVG), each save laying the figure out and rendering it, so the saves are
most of a report's time. `figures_not_rendered`: the figures are drawn (every drawing function runs) and their files
written empty, for the tests of a report's page, tables and links; `png_figures_only`: PNGs only, for a test of the
PNGs. The figure files themselves (real PNG and SVG, written, linked, their text searchable) are checked on the
session reports of tests/report/conftest.py (`base_report`, `evaluated`), which render both formats."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import pytest
from matplotlib.figure import Figure

from vinadv.report import figures

PNG = ("png",)


@contextmanager
def png_figures_only() -> Iterator[None]:
    """Within the block, the report saves each figure as PNG only (the page links what was written)."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(figures, "FORMATS", PNG)
        yield


@contextmanager
def figures_not_rendered() -> Iterator[None]:
    """Within the block, the report draws its figures but renders none: every figure file it writes (in each of
    `FORMATS`, the page linking them as ever) is empty. For a test of the page and the tables only."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Figure, "savefig", lambda self, *args, **kwargs: None)
        yield
