"""The Neural A* encoder against a plain functional reference on the authors' checkpoint tensors, its input, and
vinadv's weights file for it."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from tests.needs import public_data
from tests.planners.neural_astar.literal import (
    CHECKPOINT,
    checkpoint_state,
    mazes_test_split,
    plain_encoder,
)
from vinadv.errors import InputError
from vinadv.planners.neural_astar.checkpoint import from_lightning_checkpoint
from vinadv.planners.neural_astar.model import (
    SHIPPED_WEIGHTS,
    NeuralAstar,
    NeuralAstarConfig,
    encoder_inputs,
    load_neural_astar,
    save_neural_astar,
)
from vinadv.planners.weights import weights_checksum


@pytest.fixture(scope="module")
def few_mazes():
    free, starts, goals = mazes_test_split()
    return free[:4], starts[:4], goals[:4]


def test_encoder_inputs_are_the_map_and_the_start_plus_goal_map():
    obstacles = torch.zeros(2, 5, 5)
    obstacles[0, 1, 2] = 1.0
    starts = torch.tensor([[0, 0], [3, 3]])
    goals = torch.tensor([[4, 4], [3, 3]])
    x = encoder_inputs(obstacles, starts, goals)
    assert x.shape == (2, 2, 5, 5)
    assert torch.equal(x[:, 0], 1.0 - obstacles)
    assert x[0, 1, 0, 0] == 1 and x[0, 1, 4, 4] == 1 and x[0, 1].sum() == 2
    assert x[1, 1, 3, 3] == 2 and x[1, 1].sum() == 2  # a start on the goal counts twice, as start + goal maps do
    only_goal = encoder_inputs(obstacles, None, goals)
    assert only_goal[0, 1, 4, 4] == 1 and only_goal[0, 1].sum() == 1


@pytest.mark.parametrize("source", ["checkpoint", "shipped"])
def test_encoder_equals_the_plain_reference_on_the_checkpoint_tensors(source, few_mazes):
    free, starts, goals = few_mazes
    state = checkpoint_state()
    if source == "checkpoint":
        model, _ = from_lightning_checkpoint(public_data(CHECKPOINT))
    else:
        model = load_neural_astar()
    with torch.no_grad():
        ours = model(torch.from_numpy((~free).astype(np.float32)), torch.from_numpy(starts), torch.from_numpy(goals))
        expected = plain_encoder(state, free, starts, goals)
    assert ours.shape == (4, 32, 32)
    torch.testing.assert_close(ours, expected, rtol=0, atol=1e-6)
    assert float(ours.min()) > 0 and float(ours.max()) < 1


def test_the_encoder_runs_on_other_sizes():
    model = load_neural_astar()
    with torch.no_grad():
        out = model(torch.zeros(3, 20, 20), torch.tensor([[1, 1]] * 3), torch.tensor([[18, 18]] * 3))
    assert out.shape == (3, 20, 20) and torch.isfinite(out).all()


def test_save_and_load_keep_the_model(tmp_path):
    torch.manual_seed(0)
    model = NeuralAstar(NeuralAstarConfig(depth=2, g_ratio=0.3)).eval()
    for p in model.parameters():
        p.data.uniform_(-1, 1)
    path = tmp_path / "na.pt"
    save_neural_astar(model, path, {"note": "x"})
    back = load_neural_astar(path)
    assert back.config == model.config and back.record == {"note": "x"} and back.weights_path == str(path)
    x = (torch.rand(2, 9, 9) < 0.3).float()
    s, g = torch.tensor([[0, 0], [1, 1]]), torch.tensor([[8, 8], [7, 2]])
    with torch.no_grad():
        assert torch.equal(back(x, s, g), model(x, s, g))


def test_load_refuses_a_lightning_checkpoint_and_other_files(tmp_path):
    with pytest.raises(
        InputError, match="a Lightning checkpoint, not a vinadv Neural A\\* weights file.*import-weights"
    ):
        load_neural_astar(public_data(CHECKPOINT))
    other = tmp_path / "other.pt"
    torch.save({"format": "vinadv.gppn/1"}, other)
    with pytest.raises(InputError, match="not a Neural A\\* weights file"):
        load_neural_astar(other)
    bad = tmp_path / "bad.pt"
    torch.save({"format": "vinadv.neural-astar/1", "config": {"depth": 4}, "state_dict": {}}, bad)
    with pytest.raises(InputError, match="do not match a Neural A\\* model"):
        load_neural_astar(bad)


def test_the_shipped_weights_are_the_checkpoint_and_carry_its_record_and_licence():
    state = checkpoint_state()
    shipped = torch.load(SHIPPED_WEIGHTS, map_location="cpu", weights_only=True)
    encoder = {k: v for k, v in state.items() if k.startswith("planner.encoder.")}
    assert set(shipped["state_dict"]) == {k.removeprefix("planner.encoder.") for k in encoder}
    for key, value in encoder.items():
        assert torch.equal(shipped["state_dict"][key.removeprefix("planner.encoder.")], value), key
    record = shipped["record"]
    assert record["imported_from"]["sha256"] == weights_checksum(public_data(CHECKPOINT))
    assert record["train_config"]["encoder"] == {"input": "m+", "arch": "CNN", "depth": 4}
    licence = public_data("neural-astar/LICENSE").read_text()
    assert record["license"] == licence
    assert SHIPPED_WEIGHTS.with_name("neural_astar_mazes32.LICENSE.txt").read_text() == licence
    assert SHIPPED_WEIGHTS.with_suffix(".json").exists()
