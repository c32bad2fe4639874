"""Adversarial training: the maps it adds are the model's harmful adversarial maps, the training loop takes them in,
runs are deterministic for a seed and resume to the same weights, and the CLI records it all."""

import json
import math

import numpy as np
import pytest
import torch

from tests.cli_files import command_line
from tests.grid.oracle import brute_distances
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.hardening import AdversarialConfig, AdversarialMaps
from vinadv.planners.harness import split_indices
from vinadv.planners.imitation import TrainConfig
from vinadv.planners.vin.engine import plan_batch
from vinadv.planners.vin.training import train_vin
from vinadv.testing.planners import planning_vin

SIZE = 8
TINY = dict(epochs=2, lr=0.01, batch_size=8, val_fraction=0.25, seed=1, l_h=8, l_q=8)
#: the `train` options of the CLI tests: adversarial training by key-points from the first epoch, the record as JSON
ADVERSARIAL_JSON = ("--adversarial", "--adv-strategy", "key-points", "--adv-start", "1", "--json")


def _cost(path) -> float:
    return sum(math.sqrt(2) if (a[0] != b[0] and a[1] != b[1]) else 1.0 for a, b in zip(path, path[1:]))


def test_added_maps_are_the_models_harmful_adversarial_maps():
    maps = generate_maps(60, SIZE, seed=4, n_starts=1)
    model = planning_vin(SIZE, seed=3, noise=0.3)  # imperfect: some maps have a harmful cell
    train_idx, val_idx = split_indices(len(maps), 0.2, 0)
    hook = AdversarialMaps(maps, AdversarialConfig(maps_per_epoch=40, strategy="exhaustive"), seed=2)
    obstacles, goals, info = hook(model, 0, train_idx)
    assert info["attacked"] == 40 and info["harmful"] == len(obstacles) > 0
    originals = {i: maps.obstacles[i] for i in train_idx}
    for obs, goal in zip(obstacles, goals):
        # one cell more than a training map (never a validation map) with the same goal
        source = [
            i
            for i, o in originals.items()
            if (obs != o).sum() == 1 and (obs >= o).all() and tuple(maps.goals[i]) == tuple(goal)
        ]
        assert source, "not a training map plus one obstacle"
        i = source[0]
        start = maps.starts[i, 0]
        # harmful by an independent check: the model's path is unreached, or its regret grew
        path_o = plan_batch(maps.obstacles[i][None], start[None], goal[None], model).paths.unpack()[0].tolist()
        path_a = plan_batch(obs[None], start[None], goal[None], model).paths.unpack()[0].tolist()
        opt_o = brute_distances(maps.obstacles[i].tolist(), tuple(goal))[tuple(start)][0]
        opt_a = brute_distances(obs.tolist(), tuple(goal))[tuple(start)][0]
        reached_a = tuple(path_a[-1]) == tuple(goal)
        assert tuple(path_o[-1]) == tuple(goal)  # a valid pair: the original path reaches the goal
        assert not reached_a or _cost(path_a) - opt_a > _cost(path_o) - opt_o + 1e-6
    late = AdversarialMaps(maps, AdversarialConfig(maps_per_epoch=5, start_epoch=3), seed=2)
    assert late(model, 2, train_idx) is None


@pytest.mark.slow  # over a second: the quick tier keeps the module's other tests
def test_training_takes_the_added_maps_in_and_records_them(tmp_path):
    maps = generate_maps(16, SIZE, seed=8, n_starts=1)
    extra = generate_maps(6, SIZE, seed=9, n_starts=1)
    calls = []

    def augment(model, epoch, train_idx):
        calls.append((epoch, len(train_idx)))
        return extra.obstacles[epoch * 3 : epoch * 3 + 3], extra.goals[epoch * 3 : epoch * 3 + 3], {"note": epoch}

    ckpt = tmp_path / "w.ckpt"
    _, rec = train_vin(maps, TrainConfig(**TINY), checkpoint=ckpt, progress=False, augment=augment)
    assert calls == [(0, 12), (1, 12)]
    assert rec["added_maps"] == 6
    assert [(r["epoch"], r["added"], r["added_total"], r["note"]) for r in rec["augment_rounds"]] == [
        (1, 3, 3, 0),
        (2, 3, 6, 1),
    ]
    saved = torch.load(ckpt, weights_only=True)
    np.testing.assert_array_equal(saved["added_obstacles"].numpy(), extra.obstacles)
    # the added maps change what is learned: the same run without them ends elsewhere
    plain, _ = train_vin(maps, TrainConfig(**TINY), progress=False)
    hardened, _ = train_vin(maps, TrainConfig(**TINY), progress=False, augment=augment)
    assert any(not torch.equal(plain.state_dict()[k], v) for k, v in hardened.state_dict().items())


def test_adversarial_training_is_deterministic_and_resumes_to_the_same_weights(tmp_path):
    maps = generate_maps(24, SIZE, seed=5, n_starts=1)
    adv = AdversarialConfig(maps_per_epoch=10, strategy="key-points", budget=4)

    def run(**kw):
        config = TrainConfig(**{**TINY, **kw.pop("config", {})}, adversarial=adv.to_dict())
        return train_vin(maps, config, progress=False, augment=AdversarialMaps(maps, adv, seed=1), **kw)

    first, rec1 = run()
    second, rec2 = run()
    for key, value in first.state_dict().items():
        torch.testing.assert_close(second.state_dict()[key], value, rtol=0, atol=0)
    assert [{k: v for k, v in r.items() if k != "attack_s"} for r in rec1["augment_rounds"]] == [
        {k: v for k, v in r.items() if k != "attack_s"} for r in rec2["augment_rounds"]
    ]
    ckpt = tmp_path / "w.ckpt"
    run(config={"time_limit_min": 0.0}, checkpoint=ckpt)  # stops after epoch 1, as a kill would
    resumed, rec = run(checkpoint=ckpt, resume=True)
    assert len(rec["augment_rounds"]) == 2
    for key, value in first.state_dict().items():
        torch.testing.assert_close(resumed.state_dict()[key], value)
    with pytest.raises(InputError, match="adversarial"):  # a checkpoint of plain training is not resumed as this
        train_vin(maps, TrainConfig(**TINY), checkpoint=ckpt, resume=True, progress=False)


def test_adversarial_config_is_validated():
    for bad, param in (
        (dict(maps_per_epoch=0), "maps_per_epoch"),
        (dict(strategy="x"), "strategy"),
        (dict(objective="x"), "objective"),
        (dict(budget=0), "budget"),
    ):
        with pytest.raises(InputError) as err:
            AdversarialConfig(**bad).validate()
        assert err.value.parameters[0] == param


def test_cli_adversarial_training_records_everything(tmp_path, capsys):
    data = tmp_path / "maps.npz"
    generate_maps(30, SIZE, seed=2, n_starts=1).save(data)
    out = tmp_path / "r.pt"
    args = command_line("vin", "train", data=data, out=out, epochs=2, batch_size=8, adv_maps=10)
    assert main([*args, *ADVERSARIAL_JSON]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["train_config"]["adversarial"]["maps_per_epoch"] == 10
    assert [r["epoch"] for r in record["augment_rounds"]] == [1, 2]
    assert record["added_maps"] == sum(r["added"] for r in record["augment_rounds"])
    assert json.loads(out.with_suffix(".json").read_text())["augment_rounds"] == record["augment_rounds"]
    assert main(["vin", "train", "--data", str(data), "--out", str(out), "--adversarial", "--adv-maps", "0"]) == 2
    assert "--adv-maps" in capsys.readouterr().err


def test_cli_gppn_adversarial_training(tmp_path, capsys):
    data = tmp_path / "maps.npz"
    generate_maps(12, SIZE, seed=3, n_starts=1).save(data)
    out = tmp_path / "g.pt"
    args = command_line("gppn", "train", data=data, out=out, epochs=1, batch_size=4, l_h=4, k=4, kernel=3, adv_maps=6)
    assert main([*args, *ADVERSARIAL_JSON]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["planner"] == "gppn" and record["augment_rounds"][0]["attacked"] == 6
