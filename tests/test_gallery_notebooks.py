"""The notebooks (examples/gallery/*.ipynb and examples/quickstart.ipynb) run from top to bottom (nbclient) and show
what they say they show: their figures, and their tables and verdicts in their text. They run one after the other in
one kernel, each from a clean slate (`kernel_slate`): a kernel's imports of torch, numba and pandas are most of a
notebook's time, and a fresh kernel each paid them six times. The site shows each gallery notebook on a page of
docs/gallery/ (docs/notebooks.py), its links to the docs resolving both from the notebook and from the page."""

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
QUICKSTART = ROOT / "examples" / "quickstart.ipynb"

#: the committed entries of the suite compare_planners reads (every one of them)
QUICK_V2_ENTRIES = len(list((ROOT / "docs" / "results" / "bench").glob("vin28-quick-v2.*.json")))
#: per notebook: the public data files it reads, how many figures it draws, and texts its outputs must hold
SHOWS = {
    "neural_astar_mp_mazes": (["mpd/mazes_032_moore_c8.npz"], 1, ["8 maps of 32x32, movement model moore", "label "]),
    "compare_planners": ([], 1, [f"{QUICK_V2_ENTRIES} entries", "wastar:w=2", "harmful_k_low", "vin vs wastar:w=2"]),
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


def kernel_slate(folder: Path, temp: Path) -> str:
    """The code that puts a used kernel where a fresh one starts a notebook of `folder`: in `folder` (where Jupyter
    runs a notebook; its paths are relative to it), with no figure open, temporary files in `temp`, and none of the
    names the earlier notebooks defined (`%reset -f`, which also empties the In/Out history). What stays is what
    a notebook cannot see but by speed: the imported modules, and the planners' and Numba's caches."""
    return (
        "import os, tempfile, matplotlib.pyplot\n"
        "matplotlib.pyplot.close('all')\n"
        f"os.chdir({str(folder)!r})\n"
        f"tempfile.tempdir = {str(temp)!r}\n"
        "%reset -f\n"
    )


@pytest.fixture(scope="module")
def ran(tmp_path_factory) -> dict[str, tuple[nbformat.NotebookNode | None, Exception | None, float]]:
    """Every notebook whose public data is here, run in one kernel, one after the other: name -> (the executed
    notebook, the exception that stopped it or None, seconds). A notebook that fails gets a fresh kernel for the
    next ones, so that each test reports its own notebook."""
    runs = {name: (GALLERY / f"{name}.ipynb", SHOWS[name][0]) for name in sorted(SHOWS)}
    runs["quickstart"] = (QUICKSTART, [])
    tmp = tmp_path_factory.mktemp("notebooks")
    # local sockets in tmp, not TCP ports of a shared machine; the notebooks' temporary files in tmp
    sockets = Config({"KernelManager": {"transport": "ipc", "ip": str(tmp / "kernel")}})
    env = {**os.environ, "VINADV_DATA": str(PUBLIC_DATA), "TMPDIR": str(tmp)}
    results: dict = {}
    client = None
    try:
        for name, (path, files) in runs.items():
            if not all((PUBLIC_DATA / file).is_file() for file in files):
                continue  # its test skips (or fails under CI=true) through `public_data`
            if client is None:
                client = NotebookClient(nbformat.v4.new_notebook(), timeout=120, config=sockets)
            (temp := tmp / name).mkdir()
            client.nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(kernel_slate(path.parent, temp))])
            client.execute(env=env, cleanup_kc=False)
            notebook = nbformat.read(path, as_version=4)
            start = time.perf_counter()
            try:
                client.nb = notebook
                client.execute(cleanup_kc=False)
                results[name] = (notebook, None, time.perf_counter() - start)
            except Exception as exc:  # noqa: BLE001 (its own test raises it)
                results[name] = (None, exc, time.perf_counter() - start)
                client._cleanup_kernel()
                client = None
    finally:
        if client is not None:
            client._cleanup_kernel()
    return results


def outputs_of(ran: dict, name: str, path: Path) -> list:
    """The outputs of notebook `name`'s code cells, once `ran` ran it (its error raised here)."""
    committed = nbformat.read(path, as_version=4)
    code = [cell for cell in committed.cells if cell.cell_type == "code"]
    assert all(not cell.outputs and cell.execution_count is None for cell in code), "commit without outputs"
    notebook, error, seconds = ran[name]
    if error is not None:
        raise error  # an error in a cell: CellExecutionError, naming the cell
    print(f"{path.name}: {seconds:.1f} s")
    return [output for cell in notebook.cells if cell.cell_type == "code" for output in cell.outputs]


@pytest.mark.slow  # a kernel (its imports: torch, numba, pandas: most of its time) and a few seconds each
@pytest.mark.parametrize("name", sorted(SHOWS))
def test_gallery_notebook_runs_and_shows(name, ran):
    files, figures, texts = SHOWS[name]
    for file in files:
        public_data(file)  # skipped without the public data; failed under CI=true
    outputs = outputs_of(ran, name, GALLERY / f"{name}.ipynb")
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) == figures
    data = [o.get("data", {}) for o in outputs]
    text = "\n".join([o.get("text", "") for o in outputs] + [d.get(k, "") for d in data for k in DATA_TEXT])
    for expected in texts:
        assert expected in text


@pytest.mark.slow  # the kernel, and a run of 300 maps
def test_quickstart_notebook_runs_and_draws(ran):
    outputs = outputs_of(ran, "quickstart", QUICKSTART)
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) == 2, "the harm-by-label chart and the drawn pair"
    text = "\n".join(o.get("text", "") + o.get("data", {}).get("text/plain", "") for o in outputs)
    assert "quickstart" in text and "harmless" in text and "UcP" in text
