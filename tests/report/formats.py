"""Reports with their figures saved as PNG only, or drawn and not rendered, for the tests that check a report's data,
sections and links but not its figure files: a figure is saved once per format (`vinadv.report.figures.FORMATS`),
each save laying the figure out and rendering it, so the saves are most of a report's time and the SVGs about half
of it. The figure files themselves (PNG and SVG written, linked, their text searchable) are checked on the session
reports of tests/report/conftest.py (`base_report`, `evaluated`), which keep both formats."""

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
