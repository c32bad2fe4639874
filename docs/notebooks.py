"""MkDocs hook: the gallery's pages show their notebooks, read at build time from `examples/gallery/*.ipynb`.

A page holding `<!-- vinadv:notebook NAME -->` gets the notebook `examples/gallery/NAME.ipynb` in its place: its
Markdown cells as they are (their links to `../../docs/PAGE.md`, which resolve from the notebook's folder on GitHub
and in Jupyter, made relative to the gallery's pages), its code cells as Python blocks. Nothing is executed at the
build: the notebooks are committed without outputs, and the test suite runs them (`tests/test_gallery_notebooks.py`),
so the page shows the code that was tested, and the reader runs it to see the figures.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
GALLERY = ROOT / "examples" / "gallery"
MARKER = re.compile(r"<!-- vinadv:notebook (\w+) -->")
#: a link from a notebook's folder to a docs page, as the gallery's pages (docs/gallery/) reach it
DOCS_LINK = re.compile(r"\]\(\.\./\.\./docs/")


def notebook_markdown(name: str, folder: Path = GALLERY) -> str:
    """The notebook `folder/NAME.ipynb` as Markdown: its first cell (the title), a note naming the file and how to
    run it, then its cells in order (Markdown as is, code as Python blocks)."""
    path = folder / f"{name}.ipynb"
    cells = json.loads(path.read_text())["cells"]
    parts = []
    for cell in cells:
        source = "".join(cell["source"]).strip("\n")
        if cell["cell_type"] == "markdown":
            parts.append(DOCS_LINK.sub("](../", source))
        elif cell["cell_type"] == "code":
            parts.append(f"```python\n{source}\n```")
    note = (
        f'!!! note "Run it"\n    This page is the notebook `examples/gallery/{name}.ipynb`, its code and prose; '
        "its tables and figures appear when you run it (open it in Jupyter from a checkout, with "
        "vinadv installed). The test suite runs it in a fresh kernel and checks what it shows."
    )
    return "\n\n".join([parts[0], note, *parts[1:]]) + "\n"


def on_page_markdown(markdown: str, **kwargs) -> str:
    """MkDocs event: put each notebook in place of its marker."""
    return MARKER.sub(lambda m: notebook_markdown(m.group(1)), markdown)


if __name__ == "__main__":
    import sys

    print(notebook_markdown(sys.argv[1]))
