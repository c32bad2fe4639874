"""vinadv.outfile's writers on a full disk: one OutputError naming the file, no temporary file left (issue 45)."""

from __future__ import annotations

import contextlib
import errno

import pytest
import torch

from tests.fault_files import tmpfs
from vinadv.errors import OutputError
from vinadv.interop.checkpoints import export_state_dict
from vinadv.outfile import atomic_output, save_torch
from vinadv.planners.gppn import GPPN, GPPNConfig, save_gppn
from vinadv.planners.neural_astar.model import NeuralAstar, save_neural_astar
from vinadv.planners.vin.weights import save_vin
from vinadv.testing.planners import planning_vin


def _full_disk(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


def test_save_torch_on_a_full_disk_is_one_output_error_and_leaves_no_temporary(tmp_path, monkeypatch):
    class Full:
        """A file whose writes fail as a full disk's do: torch wraps the error in a RuntimeError."""

        def __init__(self, fh):
            self.fh = fh

        def write(self, data):
            _full_disk()

        def __getattr__(self, name):
            return getattr(self.fh, name)

    real = atomic_output

    @contextlib.contextmanager
    def full_output(path, mode="wb", **kwargs):
        with real(path, mode, **kwargs) as fh:
            yield Full(fh)

    monkeypatch.setattr("vinadv.outfile.atomic_output", full_output)
    with pytest.raises(OutputError, match=r"cannot write .*w\.pt: no space left on the device"):
        save_torch({"a": torch.zeros(1000)}, tmp_path / "w.pt")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("saver", ["gppn", "neural-astar", "vin", "vin-export"])
def test_weights_writers_on_a_full_disk_are_one_line_and_leave_no_temporary(saver, tmp_path):
    """The weights writers of `gppn import-weights`/`gppn train`, `neural-astar import-weights`, `vin train` and
    `vin export-weights` on a full file system (a 64 KiB tmpfs, almost filled)."""
    with tmpfs(tmp_path / "full", "64k") as folder:
        (folder / "filler").write_bytes(bytes(60 * 1024))
        out = folder / "w.pt"
        with pytest.raises(OutputError, match=r"w\.pt: no space left on the device"):
            if saver == "gppn":
                save_gppn(GPPN(GPPNConfig()), out)
            elif saver == "neural-astar":
                save_neural_astar(NeuralAstar(), out)
            elif saver == "vin":
                save_vin(planning_vin(8), out)
            else:
                export_state_dict(planning_vin(8), out)
        assert [p.name for p in folder.iterdir()] == ["filler"]
