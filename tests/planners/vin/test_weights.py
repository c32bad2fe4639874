"""VIN layout, the port-style value iteration, and weights files (vinadv format, port state dicts, bad files)."""

import math

import pytest
import torch
import torch.nn.functional as F

from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.planners.vin import VIN, VINConfig, make_input
from vinadv.planners.vin.weights import (
    STATE_KEYS,
    WEIGHTS_FORMAT,
    default_weights_path,
    load_vin,
    save_vin,
)
from vinadv.planners.weights import weights_checksum
from vinadv.testing.planners import planning_vin


@pytest.mark.parametrize("size,k", [(8, 10), (16, 20), (28, 36)])
def test_state_dict_layout_and_shapes(size, k):
    model = VIN(VINConfig(k=k))
    shapes = {name: tuple(t.shape) for name, t in model.state_dict().items()}
    # DESIGN.md: h 3x3 2->150 with bias, r 1x1 150->1, q 3x3 1->10, w 10x1x3x3, fc 10->8 (the ports' layout).
    assert shapes == {
        "h.weight": (150, 2, 3, 3),
        "h.bias": (150,),
        "r.weight": (1, 150, 1, 1),
        "q.weight": (10, 1, 3, 3),
        "w": (10, 1, 3, 3),
        "fc.weight": (8, 10),
    }
    assert set(shapes) == set(STATE_KEYS)
    maps = generate_maps(3, size, seed=1, n_starts=1)
    x = make_input(maps.obstacles, maps.goals)
    assert x.shape == (3, 2, size, size)
    assert model.action_logits(x).shape == (3, size, size, 8)
    rows, cols = torch.tensor(maps.starts[:, 0, 0]), torch.tensor(maps.starts[:, 0, 1])
    assert model(x, rows, cols).shape == (3, 8)


def port_q_values(model, x):
    """Value iteration exactly as the common PyTorch port writes it (conv of cat([r, v]) each step)."""
    h = F.conv2d(x, model.h.weight, model.h.bias, padding=1)
    r = F.conv2d(h, model.r.weight)
    q = F.conv2d(r, model.q.weight, padding=1)
    v, _ = torch.max(q, dim=1, keepdim=True)
    weight = torch.cat([model.q.weight, model.w], 1)
    for _ in range(model.config.k - 1):
        q = F.conv2d(torch.cat([r, v], 1), weight, padding=1)
        v, _ = torch.max(q, dim=1, keepdim=True)
    return F.conv2d(torch.cat([r, v], 1), weight, padding=1)


def test_value_iteration_matches_the_port_formulation():
    model = planning_vin(16, seed=2)
    maps = generate_maps(4, 16, seed=5, n_starts=1)
    x = make_input(maps.obstacles, maps.goals)
    with torch.no_grad():
        torch.testing.assert_close(model.q_values(x), port_q_values(model, x), rtol=1e-4, atol=1e-4)


def test_roundtrip_keeps_weights_config_and_record(tmp_path):
    model = planning_vin(8, seed=1, k=7)
    save_vin(model, tmp_path / "w.pt", {"seed": 3, "metrics": [0.5]})
    back = load_vin(tmp_path / "w.pt", size=8)
    assert back.config == model.config  # k=7 comes from the file, not from the size
    assert back.record == {"seed": 3, "metrics": [0.5]}
    for key in STATE_KEYS:
        torch.testing.assert_close(back.state_dict()[key], model.state_dict()[key], rtol=0, atol=0)
    raw = torch.load(tmp_path / "w.pt", weights_only=True)
    assert raw["format"] == WEIGHTS_FORMAT and set(raw["state_dict"]) == set(STATE_KEYS)
    assert len(weights_checksum(tmp_path / "w.pt")) == 64
    assert load_vin(tmp_path / "w.pt", size=8, k=12).config.k == 12


def test_loads_a_port_style_plain_state_dict(tmp_path):
    torch.manual_seed(0)
    # The ports use other widths too (e.g. l_h=150, l_q=10 at 28x28; smaller in examples): infer them from shapes.
    state = {
        "h.weight": torch.randn(20, 2, 3, 3),
        "h.bias": torch.randn(20),
        "r.weight": torch.randn(1, 20, 1, 1),
        "q.weight": torch.randn(6, 1, 3, 3),
        "w": torch.randn(6, 1, 3, 3),
        "fc.weight": torch.randn(8, 6),
    }
    torch.save(state, tmp_path / "port.pth")
    model = load_vin(tmp_path / "port.pth", size=16)
    assert model.config == VINConfig(k=20, l_i=2, l_h=20, l_q=6, n_actions=8)
    assert model.record == {}
    for key, value in state.items():
        assert torch.equal(model.state_dict()[key], value)
    assert load_vin(tmp_path / "port.pth", size=16, k=5).config.k == 5
    # also wrapped as {"state_dict": ...}
    torch.save({"state_dict": state, "epoch": 3}, tmp_path / "wrapped.pth")
    assert load_vin(tmp_path / "wrapped.pth", size=8).config.k == 10


def test_shipped_default_weights_load():
    path = default_weights_path(28)
    assert path.name == "vin28.pt" and path.exists()
    model = load_vin()
    assert model.config == VINConfig(k=36, l_i=2, l_h=150, l_q=10, n_actions=8)
    assert model.record["size"] == 28 and model.record["data"]["sha256"]


def test_missing_shipped_size_is_a_clear_error():
    with pytest.raises(InputError, match="no shipped VIN weights for 13x13"):
        load_vin(size=13)


def bad_files(tmp_path):
    good = planning_vin(8, seed=0)
    (tmp_path / "garbage.pt").write_bytes(b"this is not a torch file")
    save_vin(good, tmp_path / "good.pt")
    blob = (tmp_path / "good.pt").read_bytes()
    (tmp_path / "truncated.pt").write_bytes(blob[: len(blob) // 2])
    state = {k: v.clone() for k, v in good.state_dict().items()}
    torch.save(
        {
            "format": WEIGHTS_FORMAT,
            "config": good.config.to_dict(),
            "state_dict": {**state, "fc.weight": torch.zeros(8, 7)},
        },
        tmp_path / "shape.pt",
    )
    torch.save({"format": "vinadv.vin/9", "config": {}, "state_dict": state}, tmp_path / "version.pt")
    torch.save({k: v for k, v in state.items() if k != "w"}, tmp_path / "missing_key.pt")
    torch.save({**state, "extra": torch.zeros(1)}, tmp_path / "extra_key.pt")
    torch.save({**state, "w": torch.full((10, 1, 3, 3), math.nan)}, tmp_path / "nan.pt")
    torch.save({"format": WEIGHTS_FORMAT, "config": {"k": -1}, "state_dict": state}, tmp_path / "config.pt")
    torch.save([1, 2, 3], tmp_path / "list.pt")
    return {
        "garbage.pt": "not a vinadv/PyTorch weights file",
        "truncated.pt": "not a vinadv/PyTorch weights file",
        "shape.pt": "'fc.weight' has shape",
        "version.pt": "not supported",
        "missing_key.pt": "lacks",
        "extra_key.pt": "unexpected",
        "nan.pt": "finite",
        "config.pt": "positive integer",
        "list.pt": "expected a dict",
        "absent.pt": "no such weights file",
    }


def test_bad_weights_files_raise_input_error_naming_the_file(tmp_path):
    for name, problem in bad_files(tmp_path).items():
        with pytest.raises(InputError) as info:
            load_vin(tmp_path / name, size=8)
        assert str(tmp_path / name) in str(info.value) and problem in str(info.value), (name, str(info.value))


def test_cli_bad_weights_exit_2(tmp_path, capsys):
    bad_files(tmp_path)
    for name in ("garbage.pt", "shape.pt"):
        code = main(["vin", "eval", "--weights", str(tmp_path / name), "--n", "2", "--size", "8", "--quiet"])
        assert code == 2
        err = capsys.readouterr().err
        assert err.startswith("vinadv: error:") and name in err and "Traceback" not in err
