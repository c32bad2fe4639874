"""`vinadv neural-astar import-weights` and `compare-modes` from the command line."""

from __future__ import annotations

import json

import pytest
import torch

from tests.planners.neural_astar.literal import CHECKPOINT, checkpoint_state, shared_file
from vinadv.cli import main
from vinadv.grid import generate_maps
from vinadv.planners.neural_astar.model import load_neural_astar
from vinadv.planners.registry import load_planner
from vinadv.planners.weights import weights_checksum


def test_import_weights_converts_the_authors_checkpoint_with_its_record(tmp_path, capsys):
    out = tmp_path / "na.pt"
    ckpt = shared_file(CHECKPOINT)
    assert main(["neural-astar", "import-weights", str(ckpt), "--source", "the repo", "--out", str(out), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    record = json.loads(out.with_suffix(".json").read_text())
    assert printed == record
    assert (
        record["imported_from"]["sha256"] == weights_checksum(ckpt) and record["imported_from"]["source"] == "the repo"
    )
    assert record["imported_from"]["epoch"] == 33 and record["train_config"]["Tmax"] == 0.25
    assert record["license"].startswith("MIT License") and record["moves"] == "moore"
    model = load_neural_astar(out)
    assert model.record == record
    state = checkpoint_state()
    for key, value in model.encoder.state_dict().items():
        assert torch.equal(value, state[f"planner.encoder.{key}"]), key
    planner = load_planner("neural-astar", 32, weights=str(out), moves="moore")
    assert planner.checksum == weights_checksum(out)


def test_import_weights_refuses_a_foreign_checkpoint_in_one_line(tmp_path, capsys):
    ckpt = tmp_path / "unet.ckpt"
    torch.save({"state_dict": {"planner.encoder.model.encoder.features.0.weight": torch.zeros(64, 2, 3, 3)}}, ckpt)
    out = tmp_path / "na.pt"
    assert main(["neural-astar", "import-weights", str(ckpt), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "planner.encoder.model.encoder.features.0.weight" in err, err
    assert not out.exists() and not out.with_suffix(".json").exists()
    assert main(["neural-astar", "import-weights", str(tmp_path / "none.ckpt"), "--out", str(out)]) == 2
    assert "no such checkpoint file" in capsys.readouterr().err


def test_import_weights_refuses_a_training_configuration_of_another_model(tmp_path, capsys):
    config = tmp_path / "train.yaml"
    config.write_text("encoder:\n  input: m+\n  arch: Unet\n  depth: 4\n")
    out = tmp_path / "na.pt"
    args = ["neural-astar", "import-weights", str(shared_file(CHECKPOINT)), "--train-config", str(config)]
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "encoder.arch is 'Unet'" in err
    assert not out.exists()


@pytest.mark.slow
def test_compare_modes_counts_identical_searches(tmp_path, capsys):
    maps = tmp_path / "m.npz"
    generate_maps(4, 12, seed=2, n_starts=2, moves="moore").save(maps)
    assert main(["neural-astar", "compare-modes", "--data", str(maps), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["searches"] == 8 and result["identical_paths"] == 8 and result["identical_expansions"] == 8
    assert result["share_identical_paths"] == 1.0 and result["differing"] == []


def test_compare_modes_refuses_octile_maps(tmp_path, capsys):
    maps = tmp_path / "m.npz"
    generate_maps(2, 8, seed=2, n_starts=1).save(maps)
    assert main(["neural-astar", "compare-modes", "--data", str(maps)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "plans moore moves" in err and "'octile' moves" in err
