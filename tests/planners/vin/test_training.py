"""The VIN's training entry (`vinadv.planners.vin.training.train_vin`): a tiny run, resume, `--init`, the
shift-initialised kernels, the CLI."""

import json

import numpy as np
import pytest
import torch

from tests.grid.oracle import DELTAS
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.planners.imitation import TrainConfig, evaluate_loss, optimal_action_bits
from vinadv.planners.vin import VIN, VINConfig, init_shift_kernels
from vinadv.planners.vin.training import train_vin
from vinadv.planners.vin.weights import load_vin, save_vin
from vinadv.planners.weights import weights_checksum

pytestmark = pytest.mark.slow

TINY = dict(epochs=2, lr=0.01, batch_size=8, val_fraction=0.25, seed=1, l_h=8, l_q=8)


def test_tiny_training_lowers_the_loss():
    maps = generate_maps(32, 8, seed=7, n_starts=1)
    bits = optimal_action_bits(maps)
    idx = np.arange(len(maps))
    torch.manual_seed(1)  # train_vin seeds the same way before building its model
    before = evaluate_loss(VIN(VINConfig(k=10, l_h=8, l_q=8)), maps, bits, idx, 16, torch.device("cpu"))
    model, record = train_vin(maps, TrainConfig(**TINY), progress=False)
    after = evaluate_loss(model, maps, bits, idx, 16, torch.device("cpu"))
    assert after["loss"] < before["loss"] - 0.05
    assert record["epochs_done"] == 2 and len(record["epochs"]) == 2
    assert record["n_train"] == 24 and record["n_val"] == 8
    assert record["epochs"][1]["val_loss"] is not None


def test_killed_training_resumes_to_the_same_weights(tmp_path):
    maps = generate_maps(16, 8, seed=8, n_starts=1)
    full, _ = train_vin(maps, TrainConfig(**TINY), progress=False)
    ckpt = tmp_path / "w.ckpt"
    # time_limit 0 stops after the first epoch, as a kill after its checkpoint would
    _, rec = train_vin(maps, TrainConfig(**TINY, time_limit_min=0.0), checkpoint=ckpt, progress=False)
    assert rec["epochs_done"] == 1 and rec["stopped_early"]
    resumed, rec = train_vin(maps, TrainConfig(**TINY), checkpoint=ckpt, resume=True, progress=False)
    assert rec["epochs_done"] == 2 and [e["epoch"] for e in rec["epochs"]] == [1, 2]
    for key, value in full.state_dict().items():
        torch.testing.assert_close(resumed.state_dict()[key], value)
    with pytest.raises(InputError, match="lr"):
        train_vin(maps, TrainConfig(**{**TINY, "lr": 0.5}), checkpoint=ckpt, resume=True, progress=False)


def test_init_continues_from_given_weights(tmp_path):
    maps = generate_maps(16, 8, seed=9, n_starts=1)
    first, _ = train_vin(maps, TrainConfig(**TINY), progress=False)
    save_vin(first, tmp_path / "first.pt")
    # with a vanishing learning rate, continued training stays at the starting weights, whatever the seed
    same, rec = train_vin(
        maps, TrainConfig(**{**TINY, "lr": 1e-12, "seed": 5}, init=str(tmp_path / "first.pt")), progress=False
    )
    assert rec["init_sha256"] == weights_checksum(tmp_path / "first.pt") and "init_k" not in rec
    for key, value in first.state_dict().items():
        torch.testing.assert_close(same.state_dict()[key], value)
    # k is iterations, not weights: another k starts from the same weights, and the record keeps the file's k
    more_k, rec = train_vin(
        maps,
        TrainConfig(**{**TINY, "lr": 1e-12, "k": first.config.k + 3}, init=str(tmp_path / "first.pt")),
        progress=False,
    )
    assert more_k.config.k == first.config.k + 3 and rec["init_k"] == first.config.k
    for key, value in first.state_dict().items():
        torch.testing.assert_close(more_k.state_dict()[key], value)
    save_vin(VIN(VINConfig(k=10, l_h=12, l_q=8)), tmp_path / "other.pt")
    with pytest.raises(InputError, match="^init "):
        train_vin(maps, TrainConfig(**TINY, init=str(tmp_path / "other.pt")), progress=False)


def test_cli_train_writes_weights_and_record(tmp_path, capsys):
    maps = generate_maps(12, 8, seed=9, n_starts=2)
    maps.save(tmp_path / "maps.npz")
    out = tmp_path / "w.pt"
    args = [
        "vin",
        "train",
        "--data",
        str(tmp_path / "maps.npz"),
        "--out",
        str(out),
        "--epochs",
        "1",
        "--batch-size",
        "4",
        "--val-fraction",
        "0.25",
        "--seed",
        "2",
        "--quiet",
    ]
    assert main(args) == 0
    record = json.loads(out.with_suffix(".json").read_text())
    for key in ("command", "seed", "data", "epochs", "wall_time_s", "hardware", "train_config"):
        assert key in record
    assert record["command"].startswith("vinadv ") and len(record["data"]["sha256"]) == 64
    assert record["data"]["moves"] == "octile"  # the maps' movement model, recorded
    model = load_vin(out, size=8)
    assert model.record["epochs_done"] == 1 and model.config.k == 10
    assert not out.with_name("w.pt.ckpt").exists()
    # a leftover checkpoint without --resume is refused, with exit 2
    out.with_name("w.pt.ckpt").write_bytes(b"x")
    capsys.readouterr()
    assert main(args) == 2
    assert "--resume" in capsys.readouterr().err
    assert main(["vin", "train", "--data", str(tmp_path / "nothing.npz"), "--out", str(out), "--quiet"]) == 2
    assert main([*args[:-1], "--epochs", "0"]) == 2
    # --vi-init: recorded; refused beside --init, in flags
    shifted = tmp_path / "s.pt"
    assert main([*args[:5], str(shifted), *args[6:], "--vi-init", "shift"]) == 0
    assert json.loads(shifted.with_suffix(".json").read_text())["train_config"]["vi_init"] == "shift"
    capsys.readouterr()
    assert main([*args[:5], str(tmp_path / "t.pt"), *args[6:], "--vi-init", "shift", "--init", str(shifted)]) == 2
    assert "--vi-init 'shift' starts a fresh VIN and --init continues" in capsys.readouterr().err


def test_shift_kernels_read_each_actions_neighbour():
    model = init_shift_kernels(VIN(VINConfig(k=10, l_h=8, l_q=10)))
    v = torch.randn(1, 1, 9, 9)
    moved = torch.nn.functional.conv2d(v, model.w, padding=1)[0]
    for a, (dr, dc) in enumerate(DELTAS):
        for r, c in [(4, 4), (1, 7), (7, 1)]:
            assert moved[a, r, c].item() == v[0, 0, r + dr, c + dc].item()
    assert torch.equal(moved[8:], v[0].expand(2, 9, 9))
    q = torch.randn(5, 10)
    torch.testing.assert_close(model.fc(q), q[:, :8])
    with pytest.raises(InputError, match="l_q >= 8"):
        init_shift_kernels(VIN(VINConfig(k=10, l_h=8, l_q=6)))


def test_shift_initialised_training_learns_the_recursion():
    # the point of vi_init 'shift': on the same maps, steps and seed, it learns what the default start does not
    # (at 28x28 on 20,000 maps: 99.9% after 10 epochs, against 96.8% for vin28.pt after nine rounds;
    # docs/results/history.md)
    maps = generate_maps(1000, 16, seed=11, n_starts=1)
    settings = dict(epochs=3, lr=0.002, batch_size=16, val_fraction=0.2, seed=3)
    accuracy = {}
    for vi_init in ("default", "shift"):
        _, record = train_vin(maps, TrainConfig(**settings, vi_init=vi_init), progress=False)
        assert record["train_config"]["vi_init"] == vi_init
        accuracy[vi_init] = record["epochs"][-1]["val_action_accuracy"]
    assert accuracy["shift"] > 0.92 and accuracy["shift"] > accuracy["default"] + 0.05, accuracy
