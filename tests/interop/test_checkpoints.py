"""Plain state-dict export for the PyTorch ports, and GPPN checkpoints read through an allow-list."""

from __future__ import annotations

import argparse
import io
import json
import os
import pickle
import warnings

import numpy as np
import pytest
import torch
import torch.nn.functional as F
from torch import nn

from tests.needs import skip_or_fail
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.interop import read_checkpoint
from vinadv.planners.vin import VINConfig, make_input
from vinadv.planners.vin.weights import default_weights_path, save_vin
from vinadv.testing.planners import planning_vin


class PortVIN(nn.Module):
    """The kentsommer port's VIN, written from its published layout: the parameters it declares and its forward
    (cat of reward and value convolved with cat(q.weight, w) at every step)."""

    def __init__(self, l_i=2, l_h=150, l_q=10, k=36):
        super().__init__()
        self.k = k
        self.h = nn.Conv2d(l_i, l_h, 3, padding=1, bias=True)
        self.r = nn.Conv2d(l_h, 1, 1, padding=0, bias=False)
        self.q = nn.Conv2d(1, l_q, 3, padding=1, bias=False)
        self.fc = nn.Linear(l_q, 8, bias=False)
        self.w = nn.Parameter(torch.zeros(l_q, 1, 3, 3))
        self.sm = nn.Softmax(dim=1)

    def forward(self, x):
        r = self.r(self.h(x))
        q = self.q(r)
        v, _ = torch.max(q, dim=1, keepdim=True)
        for _ in range(self.k):
            q = F.conv2d(torch.cat([r, v], 1), torch.cat([self.q.weight, self.w], 1), padding=1)
            v, _ = torch.max(q, dim=1, keepdim=True)
        return self.fc(q.permute(0, 2, 3, 1))


@pytest.mark.slow  # over a second: the quick tier keeps the module's other tests
def test_export_weights_loads_into_the_port_class(tmp_path, capsys):
    model = planning_vin(16, seed=3)
    save_vin(model, tmp_path / "w.pt", {"note": "test"})
    assert (
        main(
            [
                "vin",
                "export-weights",
                str(tmp_path / "w.pt"),
                "--format",
                "state-dict",
                "--out",
                str(tmp_path / "plain.pth"),
                "--json",
            ]
        )
        == 0
    )
    assert json.loads(capsys.readouterr().out)["k"] == model.config.k
    plain = torch.load(tmp_path / "plain.pth", weights_only=True)
    assert list(plain) == ["h.weight", "h.bias", "r.weight", "q.weight", "w", "fc.weight"]
    for key, value in plain.items():
        assert value.dtype == torch.float32
        torch.testing.assert_close(value, model.state_dict()[key], rtol=0, atol=0)
    port = PortVIN(k=model.config.k)
    port.load_state_dict(plain, strict=True)
    rng = np.random.default_rng(0)
    obstacles = rng.random((3, 16, 16)) < 0.3
    goals = np.array([[2, 3], [8, 8], [14, 1]])
    obstacles[np.arange(3), goals[:, 0], goals[:, 1]] = False
    x = make_input(obstacles, goals)
    with torch.no_grad():
        torch.testing.assert_close(port(x), model.action_logits(x), rtol=1e-4, atol=1e-4)


def test_export_shipped_weights(tmp_path):
    if not default_weights_path(28).exists():
        skip_or_fail(f"the shipped 28x28 weights {default_weights_path(28)} are not present")
    assert (
        main(
            [
                "vin",
                "export-weights",
                str(default_weights_path(28)),
                "--format",
                "state-dict",
                "--out",
                str(tmp_path / "p.pth"),
            ]
        )
        == 0
    )
    plain = torch.load(tmp_path / "p.pth", weights_only=True)
    # a default VIN's layout, which tests/planners/vin/test_weights.py holds to the ports' (150 hidden, 10 q channels)
    assert {k: tuple(v.shape) for k, v in plain.items()} == VINConfig().state_shapes()


def gppn_vin_state(f=3, l_h=150, l_q=600, actions=8, as_numpy=False):
    torch.manual_seed(0)
    state = {
        "h.weight": torch.randn(l_h, 2, f, f),
        "h.bias": torch.randn(l_h),
        "r.weight": torch.randn(1, l_h, 1, 1),
        "q.weight": torch.randn(l_q, 1, f, f),
        "w": torch.randn(l_q, 1, f, f),
        "policy.weight": torch.randn(actions, l_q, 1, 1),
    }
    return {k: v.double().numpy() for k, v in state.items()} if as_numpy else state


def test_gppn_checkpoint_with_numpy_values_is_read_generically(tmp_path):
    state = gppn_vin_state(f=5, as_numpy=True)
    ckpt = {
        "model": state,
        "best_model": {k: v * 2 for k, v in state.items()},
        "best_val_acc": np.float64(0.93),
        "epoch": np.int64(30),
        "args": argparse.Namespace(k=20, f=5, l_q=600, mechanism="moore"),
    }
    torch.save(ckpt, tmp_path / "gppn.pth")
    got, meta = read_checkpoint(tmp_path / "gppn.pth")
    assert meta["entry"] == "best_model" and meta["best_val_acc"] == pytest.approx(0.93) and meta["epoch"] == 30
    assert meta["args"] == {"k": 20, "f": 5, "l_q": 600, "mechanism": "moore"}
    np.testing.assert_array_equal(got["q.weight"].numpy(), state["q.weight"] * 2)
    assert got["w"].dtype == torch.float64
    model_state, _ = read_checkpoint(tmp_path / "gppn.pth", which="model")
    np.testing.assert_array_equal(model_state["h.bias"].numpy(), state["h.bias"])


class Payload:
    """An object a checkpoint must never build (outside the allow-list)."""

    def __reduce__(self):
        return (os.getcwd, ())  # harmless if it ran, but a call all the same


@pytest.mark.parametrize("kind", ["hostile", "pickle"])
def test_gppn_import_weights_refuses_unsafe_files_in_one_line_of_its_own(tmp_path, capsys, kind):
    path = tmp_path / f"{kind}.pth"
    if kind == "hostile":  # torch.save of an object outside the allow-list
        torch.save({"model": gppn_vin_state(), "extra": Payload()}, path)
        why = "it holds Python objects, not only tensors and plain values; building them would run code"
    else:  # a plain pickle (protocol 4): torch warns of the protocol before it fails
        path.write_bytes(pickle.dumps({"model": {"w": 1}}, protocol=4))
        why = "a Python pickle, not a file torch.save wrote; loading it would run code"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["gppn", "import-weights", str(path), "--k", "10", "--out", str(tmp_path / "o.pt")]) == 2
    assert not caught  # no torch warnings before the error
    assert capsys.readouterr().err == f"vinadv: error: {path}: not a readable checkpoint ({why})\n"


def test_objects_outside_the_allow_list_are_refused(tmp_path):
    torch.save({"model": gppn_vin_state(), "extra": Payload()}, tmp_path / "evil.pth")
    with pytest.raises(InputError, match=r"evil\.pth: not a readable checkpoint"):
        read_checkpoint(tmp_path / "evil.pth")
    torch.save({"other": 1}, tmp_path / "nomodel.pth")
    with pytest.raises(InputError, match="entry 'model' is missing"):
        read_checkpoint(tmp_path / "nomodel.pth")


@pytest.mark.parametrize("f", [3, 11])
def test_gppn_vin_weights_are_refused_with_what_is_missing(tmp_path, f, capsys):
    torch.save({"model": gppn_vin_state(f=f), "best_model": gppn_vin_state(f=f)}, tmp_path / "g.pth")
    code = main(
        ["vin", "export-weights", str(tmp_path / "g.pth"), "--format", "state-dict", "--out", str(tmp_path / "o.pth")]
    )
    err = capsys.readouterr().err
    assert code == 2 and "cannot represent it" in err and "input polarity" in err
    assert ("kernel size f = 11" in err) == (f == 11)
    assert not (tmp_path / "o.pth").exists()


def test_numpy_1_names_in_old_checkpoints(tmp_path):
    # GPPN's checkpoints were pickled under numpy 1, whose reconstructors live in numpy.core.multiarray
    buf = io.BytesIO()
    torch.save({"model": {"w": np.ones((2, 3))}, "acc": np.float64(0.5)}, buf, _use_new_zipfile_serialization=False)
    data = buf.getvalue()
    assert b"numpy._core.multiarray" in data
    (tmp_path / "old.pth").write_bytes(data.replace(b"numpy._core.multiarray", b"numpy.core.multiarray"))
    state, meta = read_checkpoint(tmp_path / "old.pth")
    np.testing.assert_array_equal(state["w"].numpy(), np.ones((2, 3)))
    assert meta == {"entry": "model", "acc": 0.5}
