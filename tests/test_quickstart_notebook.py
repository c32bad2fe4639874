"""examples/quickstart.ipynb runs from top to bottom in a fresh kernel (nbclient) and shows what it says it shows: the
run's DataFrame, the harm-by-label table and chart, and one pair drawn."""

from __future__ import annotations

import time
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient
from traitlets.config import Config

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "quickstart.ipynb"

pytestmark = pytest.mark.slow  # a kernel and a run of 300 maps: about 12 s on the 2-core machine


def test_quickstart_notebook_runs_and_draws(tmp_path):
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    assert all(not cell.outputs for cell in code), "commit the notebook without outputs"
    start = time.perf_counter()
    # an error in a cell raises CellExecutionError, naming the cell
    # the kernel talks over local sockets in tmp_path, not TCP ports of a shared machine
    # (the client starts the kernel and shuts it down)
    sockets = Config({"KernelManager": {"transport": "ipc", "ip": str(tmp_path / "kernel")}})
    client = NotebookClient(notebook, timeout=120, config=sockets, resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    seconds = time.perf_counter() - start
    outputs = [output for cell in code for output in cell.outputs]
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) == 2, "the harm-by-label chart and the drawn pair"
    text = "\n".join(o.get("text", "") + o.get("data", {}).get("text/plain", "") for o in outputs)
    assert "quickstart" in text and "harmless" in text and "UcP" in text
    print(f"quickstart.ipynb: {seconds:.1f} s")
