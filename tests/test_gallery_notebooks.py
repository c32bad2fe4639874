"""The gallery (examples/gallery/*.ipynb) runs from top to bottom, each notebook in a fresh kernel (nbclient), and
shows what it says it shows: its figures and the figures' captions, tables and verdicts in its text."""

from __future__ import annotations

import os
import time
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient
from traitlets.config import Config

from tests.needs import PUBLIC_DATA, public_data

GALLERY = Path(__file__).resolve().parents[1] / "examples" / "gallery"

pytestmark = pytest.mark.slow  # a kernel each (its imports: torch, numba, pandas) and seconds of work: ~4-6 s each

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


def test_every_notebook_is_tested():
    assert sorted(p.stem for p in GALLERY.glob("*.ipynb")) == sorted(SHOWS)


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
