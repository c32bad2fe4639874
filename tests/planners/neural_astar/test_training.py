"""Neural A* training (`vinadv.planners.neural_astar.training`): the optimal path map and the loss against plain
hand computations (the literal search of the published equations, a loop over cells), resuming against an
uninterrupted run, model selection, refusals. Tiny maps (10x10, depth-1 encoder) keep it cheap."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from tests.planners.neural_astar.literal import literal_search
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.planners.interface import PlannerError
from vinadv.planners.neural_astar.model import NeuralAstar, NeuralAstarConfig
from vinadv.planners.neural_astar.training import (
    RECORD_FORMAT,
    NeuralAstarTrainConfig,
    history_loss,
    optimal_path_maps,
    train_neural_astar,
)
from vinadv.planners.registry import load_planner
from vinadv.planners.weights import WEIGHTS_DIR, weights_checksum

SIZE = 10


@pytest.fixture(scope="module")
def maps():
    return generate_maps(6, SIZE, seed=5, n_starts=1, moves="moore")


@pytest.fixture(scope="module")
def val_maps():
    return generate_maps(3, SIZE, seed=6, n_starts=1, moves="moore")


def config(**kw) -> NeuralAstarTrainConfig:
    return NeuralAstarTrainConfig(**{"epochs": 1, "batch_size": 6, "depth": 1, "seed": 3, **kw})


def test_optimal_path_map_is_the_expert_path_without_its_goal(maps):
    rows = np.array([4, 1])
    got = optimal_path_maps(maps, rows)
    for k, row in enumerate(rows):
        want = np.zeros((SIZE, SIZE), dtype=np.float32)
        path = maps.expert[int(row)]
        for r, c in path[:-1]:  # the authors' opt_traj: start .. the cell before the goal
            want[r, c] = 1.0
        assert tuple(path[-1]) == tuple(maps.goals[row])
        np.testing.assert_array_equal(got[k], want)


def test_history_loss_is_the_mean_absolute_difference_over_cells():
    rng = np.random.default_rng(0)
    h, t = rng.random((3, 4, 4)).astype(np.float32), (rng.random((3, 4, 4)) > 0.5).astype(np.float32)
    total = 0.0
    for b in range(3):
        for r in range(4):
            for c in range(4):
                total += abs(float(h[b, r, c]) - float(t[b, r, c]))
    got = history_loss(torch.from_numpy(h), torch.from_numpy(t))
    assert float(got) == pytest.approx(total / 48, rel=1e-6)


@pytest.mark.slow
def test_first_epoch_loss_is_the_literal_searchs_history_against_the_path(maps, val_maps):
    # one batch holding every map: the recorded loss is the freshly initialised model's, before its only step
    _, record = train_neural_astar(maps, val_maps, config())
    torch.manual_seed(3)
    model = NeuralAstar(NeuralAstarConfig(depth=1)).train()
    obs = torch.from_numpy(maps.obstacles.astype(np.float32))
    with torch.no_grad():  # batch norm on the batch's statistics, as in training: the batch is all six maps
        cost = model(obs, torch.from_numpy(maps.starts[:, 0]), torch.from_numpy(maps.goals))
    budget = int(0.25 * SIZE * SIZE)
    total = 0.0
    for b in range(len(maps)):
        _, expanded, _ = literal_search(cost[b], ~maps.obstacles[b], maps.starts[b, 0], maps.goals[b], budget)
        on_path = {tuple(int(v) for v in cell) for cell in maps.expert[b][:-1]}
        for r in range(SIZE):
            for c in range(SIZE):
                total += abs(float(expanded[r, c]) - float((r, c) in on_path))
    assert record["epochs"][0]["train_loss"] == pytest.approx(total / (len(maps) * SIZE * SIZE), rel=1e-6)


@pytest.mark.slow
def test_resumed_training_ends_with_the_uninterrupted_runs_weights(maps, val_maps, tmp_path):
    straight, rec_a = train_neural_astar(maps, val_maps, config(epochs=3, batch_size=3))
    ck = tmp_path / "run.ckpt"
    train_neural_astar(maps, val_maps, config(epochs=1, batch_size=3), checkpoint=ck, data_sha256="x")
    assert ck.exists()
    resumed, rec_b = train_neural_astar(
        maps, val_maps, config(epochs=3, batch_size=3), checkpoint=ck, resume=True, data_sha256="x"
    )
    for key, value in straight.encoder.state_dict().items():
        assert torch.equal(value, resumed.encoder.state_dict()[key]), key
    drop = ("epoch_s", "wall_s")
    assert [{k: v for k, v in e.items() if k not in drop} for e in rec_a["epochs"]] == [
        {k: v for k, v in e.items() if k not in drop} for e in rec_b["epochs"]
    ]
    assert rec_b["epochs_done"] == 3 and rec_a["best_epoch"] == rec_b["best_epoch"]
    best = max(rec_a["epochs"], key=lambda e: e["val_h_mean"])  # first on ties, as max
    assert rec_a["best_epoch"] == best["epoch"]
    # a checkpoint of other settings or other maps is refused, naming what differs
    with pytest.raises(InputError, match="lr=0.001"):
        train_neural_astar(maps, val_maps, config(epochs=3, lr=0.01), checkpoint=ck, resume=True, data_sha256="x")
    with pytest.raises(InputError, match="other maps"):
        train_neural_astar(maps, val_maps, config(epochs=3, batch_size=3), checkpoint=ck, resume=True, data_sha256="y")


def test_training_refuses_bad_settings_and_other_movement_models(maps, val_maps):
    bad_settings = ((dict(tmax=0.0), "tmax"), (dict(lr=-1.0), "lr"), (dict(epochs=0), "epochs"))
    bad_settings += ((dict(depth=5), "depth"),)
    for bad, word in bad_settings:
        with pytest.raises(InputError, match=word):
            train_neural_astar(maps, val_maps, config(**bad))
    octile = generate_maps(2, SIZE, seed=1, n_starts=1)
    with pytest.raises(InputError, match="'octile'"):
        train_neural_astar(octile, val_maps, config())
    with pytest.raises(InputError, match="validation maps are 12x12"):
        train_neural_astar(maps, generate_maps(2, 12, seed=1, n_starts=1, moves="moore"), config())


def test_the_shipped_mpd5_model_is_registered_with_its_training_record():
    path = WEIGHTS_DIR / "neural_astar_mpd5.pt"
    planner = load_planner("neural-astar-mpd5", 32, moves="moore")
    assert planner.name == "neural-astar-mpd5" and planner.checksum == weights_checksum(path)
    record = planner.model.record
    assert record == json.loads(path.with_suffix(".json").read_text())
    assert record["format"] == RECORD_FORMAT and record["train_config"]["tmax"] == 0.25
    assert record["best_epoch"] == max(record["epochs"], key=lambda e: e["val_h_mean"])["epoch"]
    assert {d["path"].rsplit("/", 1)[-1] for d in record["data"]} == {
        f"{f}_train.npz" for f in ("alternating_gaps", "forest", "multiple_bugtraps", "shifting_gaps", "single_bugtrap")
    }
    # its own file names the same planner (`resolve_choice`); any other file is refused
    assert load_planner("neural-astar-mpd5", 32, weights=str(path), moves="moore").checksum == planner.checksum
    with pytest.raises(PlannerError, match="takes no weights file"):
        load_planner("neural-astar-mpd5", 32, weights=str(WEIGHTS_DIR / "neural_astar_mazes32.pt"), moves="moore")
