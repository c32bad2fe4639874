"""Weights that lie (issue 45): a file vinadv's own reader finds damaged is never read by PyTorch (which does not
check the zip CRC); non-finite tensors are refused at import and load; `k` is bounded before any loop; special files
are refused by type; the compiled value iteration runs in rounds, so signals are seen between them."""

from __future__ import annotations

import os
import zipfile

import numpy as np
import pytest
import torch

from tests.planners.neural_astar.test_checkpoint import cnn_state, lightning
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.planners import batching
from vinadv.planners.vin.weights import load_vin_weights, save_vin
from vinadv.planners.weights import MAX_ITERATIONS, torch_load
from vinadv.testing.planners import planning_vin

SIZE = 8


@pytest.fixture
def vin_file(tmp_path):
    path = tmp_path / "vin.pt"
    save_vin(planning_vin(SIZE, seed=3), path, {"size": SIZE})
    return path


def _flip_tensor_byte(path) -> None:
    """Flip one byte inside the data of the file's largest tensor storage (its zip CRC then fails)."""
    with zipfile.ZipFile(path) as archive:
        info = max((i for i in archive.infolist() if "/data/" in i.filename), key=lambda i: i.file_size)
    raw = bytearray(path.read_bytes())
    # local header: 30 bytes, the name, the extra field; then the stored (uncompressed) data
    name_len = int.from_bytes(raw[info.header_offset + 26 : info.header_offset + 28], "little")
    extra_len = int.from_bytes(raw[info.header_offset + 28 : info.header_offset + 30], "little")
    start = info.header_offset + 30 + name_len + extra_len
    raw[start + info.file_size // 2] ^= 0x01
    path.write_bytes(bytes(raw))


def test_a_flipped_byte_in_tensor_data_is_refused_never_read_by_torch(vin_file, capsys):
    _flip_tensor_byte(vin_file)
    with pytest.raises(InputError, match="vin.pt: a damaged weights file"):
        load_vin_weights(vin_file, size=SIZE)
    with pytest.raises(InputError, match="vin.pt: a damaged weights file"):
        torch_load(vin_file, "weights file")  # every reader that goes through torch checks the CRC first
    assert main(["vin", "eval", "--weights", str(vin_file), "--n", "4", "--size", str(SIZE)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "damaged" in err and "vin.pt" in err


def test_non_finite_vin_weights_are_refused_at_load(tmp_path):
    model = planning_vin(SIZE, seed=3)
    with torch.no_grad():
        model.w[0, 0, 1, 1] = float("nan")
    save_vin(model, tmp_path / "nan.pt", {"size": SIZE})
    with pytest.raises(InputError, match="nan.pt: tensor 'state_dict.w' holds NaN or infinite values"):
        load_vin_weights(tmp_path / "nan.pt", size=SIZE)


def test_neural_astar_import_weights_refuses_nan_encoder_weights(tmp_path, capsys):
    state = cnn_state()
    state["planner.encoder.model.0.weight"][0, 0, 0, 0] = float("nan")
    ckpt = lightning(tmp_path, state)
    out = tmp_path / "na.pt"
    assert main(["neural-astar", "import-weights", str(ckpt), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "fake.ckpt" in err and "NaN" in err and "model.0.weight" in err
    assert not out.exists()


@pytest.mark.timeout(60)
def test_a_config_k_of_ten_to_the_eighteen_is_refused_before_any_loop(vin_file, tmp_path):
    data = torch.load(vin_file, weights_only=True)
    data["config"]["k"] = 10**18
    torch.save(data, tmp_path / "huge.pt")
    with pytest.raises(
        InputError, match=f"huge.pt: config entry 'k' is 1000000000000000000, expected .*{MAX_ITERATIONS}"
    ):
        load_vin_weights(tmp_path / "huge.pt", size=SIZE)
    with pytest.raises(InputError, match="k is"):
        load_vin_weights(vin_file, size=SIZE, k=MAX_ITERATIONS + 1)
    data["config"]["k"], data["config"]["l_h"] = 36, 10**12
    torch.save(data, tmp_path / "wide.pt")
    with pytest.raises(InputError, match="wide.pt: config entry 'l_h'"):
        load_vin_weights(tmp_path / "wide.pt", size=SIZE)


@pytest.mark.timeout(60)
@pytest.mark.parametrize("kind", ["fifo", "dev-zero"])
def test_special_files_are_refused_by_type(tmp_path, kind):
    path = tmp_path / "w.pt"
    if kind == "fifo":
        os.mkfifo(path)
    else:
        path.symlink_to("/dev/zero")
    with pytest.raises(InputError, match="w.pt: a (FIFO|device or special file), not a weights file"):
        load_vin_weights(path, size=SIZE)
    with pytest.raises(InputError, match="not a weights file"):
        torch_load(path, "weights file")


def test_over_maps_runs_costly_maps_in_rounds(monkeypatch):
    monkeypatch.setattr(batching, "ROUND_COST", 100)
    calls = []
    batching.over_maps(10, lambda lo, hi: calls.append((lo, hi)), threads=1, cost=30)
    assert calls == [(0, 3), (3, 6), (6, 9), (9, 10)]  # three maps a round: a signal is seen between rounds
    calls.clear()
    batching.over_maps(10, lambda lo, hi: calls.append((lo, hi)), threads=1)
    assert calls == [(0, 10)]


def test_engine_results_are_the_same_in_rounds(monkeypatch):
    from vinadv.planners.vin.engine import action_maps  # noqa: PLC0415
    from vinadv.robustness import heldout_maps  # noqa: PLC0415

    maps = heldout_maps(20, SIZE, seed=0)
    model = planning_vin(SIZE, seed=3)
    whole = action_maps(model, maps.obstacles, maps.goals)
    monkeypatch.setattr(batching, "ROUND_COST", 1)  # one map a round
    assert np.array_equal(action_maps(model, maps.obstacles, maps.goals), whole)
