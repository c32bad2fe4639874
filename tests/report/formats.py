"""Reports with their figures saved as PNG only, for the tests that check a report's data, sections and links but not
its figure files: a figure is saved once per format (`vinadv.report.figures.FORMATS`), each save laying the figure
out and drawing it, so the SVGs are about half of a report's time. The SVGs themselves (written, linked, their text
searchable) are checked on the session reports of tests/report/conftest.py (`base_report`, `evaluated`) and by the
frozen baseline, which keep both formats."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from vinadv.report import figures

PNG = ("png",)


@contextmanager
def png_figures_only() -> Iterator[None]:
    """Within the block, the report saves each figure as PNG only (the page links what was written)."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(figures, "FORMATS", PNG)
        yield
