"""The gallery (examples/gallery/*.ipynb) runs from top to bottom, each notebook in a fresh kernel (nbclient), and
shows what it says it shows: its figures, and its tables and verdicts in its text. The site shows each notebook on a
page of docs/gallery/ (docs/notebooks.py), its links to the docs resolving both from the notebook and from the page."""

from __future__ import annotations

import importlib.util
import json
import os
import re
import time
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient
from traitlets.config import Config

from tests.needs import PUBLIC_DATA, public_data

ROOT = Path(__file__).resolve().parents[1]
GALLERY = ROOT / "examples" / "gallery"

#: per notebook: the public data files it reads, how many figures it draws, and texts its outputs must hold
SHOWS = {
    "neural_astar_mp_mazes": (["mpd/mazes_032_moore_c8.npz"], 1, ["8 maps of 32x32, movement model moore", "label "]),
    "compare_planners": ([], 1, ["4 entries", "wastar:w=2", "harmful_k_low", "vin vs wastar:w=2"]),
    "own_planner_leaderboard": ([], 0, ["gallery-tiny", "not a released suite", "my_search_planner.py:make"]),
    "attack_transfer": ([], 1, ["24 pairs found on VIN", "gppn", "harmful 95%", "harmful on both VIN and GPPN"]),
    "city_map": (["movingai/Berlin_1_256.map"], 2, ["12 windows of 32x32, moves octile, corner cutting False"]),
}
#: the text forms of a cell's results that the checks read
DATA_TEXT = ("text/plain", "text/markdown", "text/html")


def test_every_notebook_is_tested_and_has_a_page_in_the_nav():
    assert sorted(p.stem for p in GALLERY.glob("*.ipynb")) == sorted(SHOWS)
    nav = (ROOT / "mkdocs.yml").read_text()
    for name in SHOWS:
        assert (ROOT / "docs" / "gallery" / f"{name}.md").read_text() == f"<!-- vinadv:notebook {name} -->\n"
        assert f"gallery/{name}.md" in nav


def test_the_page_shows_the_notebooks_cells_with_links_that_resolve():
    spec = importlib.util.spec_from_file_location("docs_notebooks", ROOT / "docs" / "notebooks.py")
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    for name in SHOWS:
        cells = json.loads((GALLERY / f"{name}.ipynb").read_text())["cells"]
        page = hook.on_page_markdown(f"<!-- vinadv:notebook {name} -->\n")
        assert page.startswith("# ") and "<!-- vinadv:" not in page and f"examples/gallery/{name}.ipynb" in page
        for cell in cells:
            source = "".join(cell["source"]).strip("\n")
            if cell["cell_type"] == "code":
                assert f"```python\n{source}\n```" in page
            # a link to the docs resolves from the notebook's folder, and from docs/gallery/ once rewritten
            for link in re.findall(r"\]\(([^)#]+\.md)", source):
                assert (GALLERY / link).resolve().is_file(), (name, link)
                assert link.startswith("../../docs/"), (name, link)
                assert f"](../{link.removeprefix('../../docs/')}" in page


@pytest.mark.slow  # a kernel each (its imports: torch, numba, pandas: most of its time) and a few seconds of work
@pytest.mark.parametrize("name", sorted(SHOWS))
def test_gallery_notebook_runs_and_shows(name, tmp_path):
    files, figures, texts = SHOWS[name]
    for file in files:
        public_data(file)  # skipped without the public data; failed under CI=true
    notebook = nbformat.read(GALLERY / f"{name}.ipynb", as_version=4)
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    assert all(not cell.outputs and cell.execution_count is None for cell in code), "commit without outputs"
    start = time.perf_counter()
    # local sockets in tmp_path, not TCP ports of a shared machine; the notebook's temporary files in tmp_path
    sockets = Config({"KernelManager": {"transport": "ipc", "ip": str(tmp_path / "kernel")}})
    # run where Jupyter runs a notebook, its own folder (the paths in it are relative to it)
    client = NotebookClient(notebook, timeout=120, config=sockets, resources={"metadata": {"path": str(GALLERY)}})
    client.execute(env={**os.environ, "VINADV_DATA": str(PUBLIC_DATA), "TMPDIR": str(tmp_path)})
    seconds = time.perf_counter() - start
    outputs = [output for cell in code for output in cell.outputs]
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) == figures
    data = [o.get("data", {}) for o in outputs]
    text = "\n".join([o.get("text", "") for o in outputs] + [d.get(k, "") for d in data for k in DATA_TEXT])
    for expected in texts:
        assert expected in text
    print(f"{name}.ipynb: {seconds:.1f} s")
