"""The authors' Lightning checkpoint: read as tensors, checked key by key; foreign checkpoints refused in one line
naming the keys; train.yaml read."""

from __future__ import annotations

import pytest
import torch

from tests.needs import public_data
from tests.planners.neural_astar.literal import CHECKPOINT
from vinadv.errors import InputError
from vinadv.planners.neural_astar.checkpoint import (
    check_train_config,
    from_lightning_checkpoint,
    read_train_config,
)
from vinadv.planners.neural_astar.model import GuidanceEncoder


def lightning(tmp_path, state: dict, name: str = "fake.ckpt"):
    """A Lightning-like checkpoint of `state` written with torch.save."""
    path = tmp_path / name
    torch.save({"epoch": 1, "global_step": 2, "pytorch-lightning_version": "1.8.5", "state_dict": state}, path)
    return path


def moore() -> torch.Tensor:
    f = torch.ones(1, 1, 3, 3)
    f[0, 0, 1, 1] = 0
    return f


def cnn_state(depth: int = 4, inputs: int = 2) -> dict:
    """A CNN-encoder Neural A* state dict as the authors' Lightning module names it, random tensors."""
    torch.manual_seed(depth)
    enc = GuidanceEncoder(depth)
    state = {f"planner.encoder.{k}": v.clone() for k, v in enc.state_dict().items()}
    if inputs != 2:
        state["planner.encoder.model.0.weight"] = torch.randn(32, inputs, 3, 3)
    state["planner.astar.neighbor_filter"] = moore()
    state["vanilla_astar.astar.neighbor_filter"] = moore()
    return state


def refusal(path) -> str:
    with pytest.raises(InputError) as info:
        from_lightning_checkpoint(path)
    message = str(info.value)
    assert len(message.splitlines()) == 1, message
    return message


def test_the_authors_checkpoint_reads_as_depth_4():
    model, source = from_lightning_checkpoint(public_data(CHECKPOINT))
    assert model.config.depth == 4 and model.config.g_ratio == 0.5 and not model.training
    assert source["epoch"] == 33 and source["global_step"] == 272 and source["depth"] == 4


def test_a_cnn_of_another_depth_reads(tmp_path):
    state = cnn_state(depth=2)
    model, source = from_lightning_checkpoint(lightning(tmp_path, state))
    assert model.config.depth == 2 and source["depth"] == 2
    assert torch.equal(model.encoder.model[3].weight, state["planner.encoder.model.3.weight"])


def test_a_unet_encoder_is_refused_naming_its_keys(tmp_path):
    state = {
        "planner.encoder.model.encoder.features.0.weight": torch.zeros(64, 2, 3, 3),
        "planner.encoder.model.encoder.features.1.weight": torch.zeros(64),
        "planner.encoder.model.decoder.blocks.0.conv1.0.weight": torch.zeros(256, 512, 3, 3),
        "planner.encoder.model.segmentation_head.0.weight": torch.zeros(1, 16, 3, 3),
        "planner.astar.neighbor_filter": moore(),
    }
    message = refusal(lightning(tmp_path, state))
    assert "not the Neural A* authors' CNN encoder" in message
    assert "planner.encoder.model.decoder.blocks.0.conv1.0.weight" in message and "missing" in message


def test_the_map_only_input_is_refused_naming_the_shape(tmp_path):
    message = refusal(lightning(tmp_path, cnn_state(inputs=1)))
    assert "planner.encoder.model.0.weight (32, 1, 3, 3) (expected (32, 2, 3, 3))" in message


def test_a_learned_const_or_other_module_is_refused(tmp_path):
    state = cnn_state()
    state["planner.encoder.const"] = torch.ones(1)
    assert "unexpected keys planner.encoder.const" in refusal(lightning(tmp_path, state))
    state = cnn_state()
    state["planner.policy.weight"] = torch.ones(1)
    assert "unexpected keys planner.policy.weight" in refusal(lightning(tmp_path, state, "b.ckpt"))


@pytest.mark.parametrize("key", ["planner.astar.neighbor_filter", "vanilla_astar.astar.neighbor_filter"])
def test_another_neighbour_filter_is_refused(tmp_path, key):
    state = cnn_state()
    news = torch.zeros(1, 1, 3, 3)
    news[0, 0, 0, 1] = news[0, 0, 1, 0] = news[0, 0, 1, 2] = news[0, 0, 2, 1] = 1
    state[key] = news
    message = refusal(lightning(tmp_path, state))
    assert f"{key} is not the 8-neighbour filter" in message


def test_a_missing_filter_and_other_files_are_refused(tmp_path):
    state = cnn_state()
    del state["planner.astar.neighbor_filter"]
    assert "missing planner.astar.neighbor_filter" in refusal(lightning(tmp_path, state))
    plain = tmp_path / "plain.pt"
    torch.save({"h.weight": torch.zeros(1)}, plain)
    assert "not a Lightning checkpoint" in refusal(plain)
    noenc = lightning(tmp_path, {"model.weight": torch.zeros(1)}, "noenc.ckpt")
    assert "no Neural A* encoder" in refusal(noenc)
    garbage = tmp_path / "garbage.ckpt"
    garbage.write_bytes(b"not a checkpoint")
    assert "not a Lightning checkpoint" in refusal(garbage)


def test_read_train_config_reads_the_authors_file():
    config = read_train_config(public_data("neural-astar/train.yaml"))
    assert config["Tmax"] == 0.25 and config["seed"] == 1234
    assert config["encoder"] == {"input": "m+", "arch": "CNN", "depth": 4}
    assert config["params"] == {"batch_size": 100, "num_epochs": 50, "lr": 0.001}
    assert config["hydra"] == {"job": {"chdir": False}}
    check_train_config(config, 4, "train.yaml")


def test_read_train_config_parses_scalars_and_refuses_what_it_does_not_read(tmp_path):
    path = tmp_path / "t.yaml"
    path.write_text("# top\na: 'x y'\nb:\n  c: 1e-3   # note\n  d: null\n\ne: true\n")
    assert read_train_config(path) == {"a": "x y", "b": {"c": 0.001, "d": None}, "e": True}
    for text, line in (("a: [1, 2]\n", 1), ("a: 1\nb:\n  - x\n", 3), ("a: 1\na: 2\n", 2)):
        path.write_text(text)
        with pytest.raises(InputError, match=f"t.yaml:{line}:"):
            read_train_config(path)


def test_check_train_config_refuses_another_encoder():
    with pytest.raises(InputError, match="encoder.arch is 'Unet'"):
        check_train_config({"encoder": {"arch": "Unet", "input": "m+", "depth": 4}}, 4, "t.yaml")
    with pytest.raises(InputError, match="encoder.depth is 3"):
        check_train_config({"encoder": {"arch": "CNN", "depth": 3}}, 4, "t.yaml")
