"""`vinadv neural-astar import-weights` and `compare-modes` from the command line; the planner end to end through
plan, attack, run and robustness on an MP import and on our generator's moore maps."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from tests.needs import public_data
from tests.planners.neural_astar.literal import CHECKPOINT, checkpoint_state
from vinadv.attacks.pairs import PairSet
from vinadv.cli import main
from vinadv.grid import generate_maps
from vinadv.grid.mapset import MapSet
from vinadv.planners.neural_astar.model import load_neural_astar
from vinadv.planners.pathset import PathSet
from vinadv.planners.registry import load_planner
from vinadv.planners.weights import weights_checksum
from vinadv.store import Store


def test_import_weights_converts_the_authors_checkpoint_with_its_record(tmp_path, capsys):
    out = tmp_path / "na.pt"
    ckpt = public_data(CHECKPOINT)
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
    args = ["neural-astar", "import-weights", str(public_data(CHECKPOINT)), "--train-config", str(config)]
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


def _mp_import(tmp_path) -> str:
    """The first three maps of the mazes family's test split, imported by the CLI (the Neural A* start rule)."""
    full, small = tmp_path / "mazes_full.npz", tmp_path / "mazes.npz"
    source = public_data("mpd/mazes_032_moore_c8.npz")
    line = ["maps", "import", "--format", "mpd", str(source), "--split", "test", "--seed", "0", "--out", str(full)]
    assert main([*line, "--quiet"]) == 0
    MapSet.load(full).take(np.arange(3)).save(small)
    return str(small)


def _generated(tmp_path) -> str:
    """Three maps of our generator at 32x32 with moore moves, by the CLI."""
    out = tmp_path / "gen.npz"
    line = ["maps", "generate", "--n", "3", "--size", "32", "--moves", "moore", "--starts", "1", "--seed", "4"]
    assert main([*line, "--out", str(out), "--quiet"]) == 0
    return str(out)


def _json(capsys, argv) -> dict:
    capsys.readouterr()
    assert main([*argv, "--json", "--quiet"]) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


@pytest.mark.slow
@pytest.mark.parametrize("source", ["mp", "generated"])
def test_neural_astar_end_to_end_on_mp_and_generated_maps(source, tmp_path, capsys):
    maps_file = _mp_import(tmp_path) if source == "mp" else _generated(tmp_path)
    maps = MapSet.load(maps_file)
    assert maps.moves == "moore" and maps.obstacles.shape[1:] == (32, 32)
    # plan: a path per map from its start to its goal through free cells, one Moore step at a time (checked by hand)
    paths_file = tmp_path / "p.npz"
    summary = _json(capsys, ["plan", "--maps", maps_file, "--planner", "neural-astar", "--out", str(paths_file)])
    assert summary["paths"] == 3
    paths = PathSet.load(paths_file)
    for m in range(3):
        path = [tuple(int(v) for v in cell) for cell in paths.paths[m]]
        assert path[0] == tuple(maps.starts[m, 0]) and path[-1] == tuple(maps.goals[m])
        assert all(not maps.obstacles[m][cell] for cell in path)
        assert all(max(abs(a[0] - b[0]), abs(a[1] - b[1])) == 1 for a, b in zip(path, path[1:]))
    # attack by saliency: the differentiable search's gradient, so no key-points fallback is recorded
    pairs_file = tmp_path / "a.npz"
    line = ["attack", "--maps", maps_file, "--planner", "neural-astar", "--strategy", "saliency", "--budget", "4"]
    summary = _json(capsys, [*line, "--out", str(pairs_file)])
    assert "ranked_as" not in summary
    pairs = PairSet.load(pairs_file)
    assert pairs.params["planner"]["name"] == "neural-astar" and "ranked_as" not in pairs.params
    # run, stored
    db = str(tmp_path / "r.db")
    line = ["run", "--maps", maps_file, "--n", "3", "--db", db, "--planner", "neural-astar", "--attack", "saliency"]
    summary = _json(capsys, line)
    with Store.open(db) as store:
        info = store.run_info(summary["run_id"])
    assert summary["maps"] == 3 and info["config"]["planner"] == "neural-astar"
    # robustness: harm on unit costs; saliency by gradient here too
    out = _json(
        capsys,
        ["robustness", "--maps", maps_file, "--planner", "neural-astar", "--max-obstacles", "1"]
        + ["--strategies", "saliency,random", "--budget", "4"],
    )
    assert out["clean"]["maps"] == 3 and out["settings"]["n"] == 3
    assert out["strategies"]["saliency"]["ranked_as"] is None and out["strategies"]["random"]["ranked_as"] is None


@pytest.mark.slow
def test_train_writes_weights_and_record_loadable_by_the_planner(tmp_path, capsys):
    train, val = tmp_path / "train.npz", tmp_path / "val.npz"
    generate_maps(4, 10, seed=2, n_starts=1, moves="moore").save(train)
    generate_maps(3, 10, seed=3, n_starts=1, moves="moore").save(val)
    out = tmp_path / "na.pt"
    args = ["neural-astar", "train", "--data", str(train), "--data", str(train), "--val-data", str(val)]
    assert main([*args, "--out", str(out), "--epochs", "2", "--depth", "1", "--batch-size", "4", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    record = json.loads(out.with_suffix(".json").read_text())
    assert printed == record and not out.with_name("na.pt.ckpt").exists()
    assert record["format"] == "vinadv.neural-astar-training-record/1" and record["n_train"] == 8
    assert record["train_config"]["tmax"] == 0.25 and record["train_config"]["lr"] == 0.001
    assert [d["sha256"] for d in record["data"]] == [weights_checksum(train)] * 2
    assert record["val_data"][0]["sha256"] == weights_checksum(val) and record["epochs_done"] == 2
    assert record["best_epoch"] == max(record["epochs"], key=lambda e: e["val_h_mean"])["epoch"]
    assert load_neural_astar(out).record == record
    assert main(["eval", "--data", str(val), "--planner", "neural-astar", "--weights", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["search"]["rows"] == 3


def test_train_refuses_in_one_line(tmp_path, capsys):
    moore, octile = tmp_path / "moore.npz", tmp_path / "octile.npz"
    generate_maps(3, 10, seed=2, n_starts=1, moves="moore").save(moore)
    generate_maps(3, 10, seed=2, n_starts=1).save(octile)
    out = tmp_path / "na.pt"
    base = ["neural-astar", "train", "--out", str(out), "--depth", "1", "--quiet"]
    cases = [
        ([*base, "--data", str(octile)], "'octile'"),
        ([*base, "--data", str(moore), "--tmax", "0"], "--tmax"),
        ([*base, "--data", str(moore), "--data", str(octile)], "moves"),
        ([*base, "--data", str(moore), "--val-fraction", "1.5"], "--val-fraction"),
        ([*base, "--data", str(tmp_path / "none.npz")], "none.npz"),
    ]
    for argv, word in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and word in err, err
    out.with_name("na.pt.ckpt").write_bytes(b"")
    assert main([*base, "--data", str(moore)]) == 2
    assert "--resume" in capsys.readouterr().err
    assert not out.exists()
