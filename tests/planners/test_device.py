"""`--device` in the library: device names checked (`resolve_device`), and every torch planner's device plumbing on the
CPU: `device="cpu"` plans what the default plans (GPPN, a file planner, `+d4`), records its type, travels in a
`PlannerRef`; the VIN's PyTorch forward (`device=` given) plans the exact engine's paths, the engine being the
oracle (tested against the re-run-every-step reference in tests/planners/vin)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from tests.planner_files import NO_PARAMETERS
from vinadv.attacks.strategies import make_attack
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.planners.device import resolve_device
from vinadv.planners.gppn import GPPN, GPPNConfig, save_gppn
from vinadv.planners.interface import TorchPlanner, VINPlanner
from vinadv.planners.registry import PlannerRef, load_planner

SIZE = 10


@pytest.fixture(scope="module")
def gppn_file(tmp_path_factory):
    """A small GPPN's weights (untrained: its logits are as good as any for comparing two paths to them)."""
    torch.manual_seed(3)
    path = tmp_path_factory.mktemp("g") / "gppn.pt"
    save_gppn(GPPN(GPPNConfig(k=6, l_h=5, f=3)), path, {"size": SIZE})
    return str(path)


@pytest.fixture(scope="module")
def maps():
    return generate_maps(12, SIZE, seed=4, n_starts=2)


@pytest.fixture
def no_cuda(monkeypatch):
    """This machine without CUDA, whatever it has."""
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)


def test_device_names(no_cuda):
    assert resolve_device("cpu") == torch.device("cpu")
    assert resolve_device(" auto ") == torch.device("cpu")  # no CUDA here: auto is the CPU
    for name, message in [
        ("cuda", "CUDA is not available on this machine"),
        ("cuda:1", "CUDA is not available on this machine"),
        ("tpu", "is not a device; use cpu, cuda, cuda:N or auto"),
        ("", "is not a device"),
        ("meta", "use cpu, cuda, cuda:N or auto"),
    ]:
        with pytest.raises(InputError, match=message) as info:
            resolve_device(name)
        assert info.value.parameters == ("device",) and "\n" not in str(info.value)


def test_auto_and_gpu_indices_where_cuda_is_there(monkeypatch):
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: 2)
    assert resolve_device("auto") == torch.device("cuda")
    assert resolve_device("cuda:1") == torch.device("cuda", 1)
    with pytest.raises(InputError, match=r"has 2 CUDA device\(s\), cuda:0..cuda:1"):
        resolve_device("cuda:2")


def test_a_device_the_machine_lacks_is_refused_before_the_planner_loads(no_cuda, tmp_path):
    with pytest.raises(InputError, match="'cuda': CUDA is not available"):
        load_planner(str(tmp_path / "no_such_file.py") + ":make", SIZE, device="cuda")  # the device first


def _planners(spec: str, weights: str | None):
    default = load_planner(spec, SIZE, weights=weights)
    on_cpu = load_planner(spec, SIZE, weights=weights, device="cpu")
    return default, on_cpu


@pytest.mark.parametrize("spec", ["gppn", "gppn+d4", "file"])
def test_torch_planners_on_the_cpu_plan_what_the_default_plans(spec, gppn_file, maps, tmp_path):
    weights = gppn_file if spec.startswith("gppn") else None
    if spec == "file":
        (tmp_path / "p.py").write_text(NO_PARAMETERS)
        spec = f"{tmp_path / 'p.py'}:make"
    default, on_cpu = _planners(spec, weights)
    assert isinstance(on_cpu, TorchPlanner) and on_cpu.device == torch.device("cpu")
    assert default.device_type is None and "device" not in default.spec()
    assert on_cpu.spec() == {**default.spec(), "device": "cpu"}
    a = default.plan_maps(maps.obstacles, maps.goals, maps.starts)
    b = on_cpu.plan_maps(maps.obstacles, maps.goals, maps.starts)
    assert a.paths == b.paths and np.array_equal(a.termination, b.termination)
    np.testing.assert_array_equal(default.logits(maps.obstacles, maps.goals), on_cpu.logits(maps.obstacles, maps.goals))


def test_the_vin_on_a_device_plans_the_engines_paths_with_its_torch_forward(planning_weights, maps, monkeypatch):
    weights = planning_weights(SIZE)
    engine, forward = _planners("vin", weights)
    assert isinstance(forward, VINPlanner) and forward.device_type == "cpu" and engine.device_type is None
    assert forward.spec() == {**engine.spec(), "device": "cpu"}
    expected = engine.plan_maps(maps.obstacles, maps.goals, maps.starts)
    # the device path never calls the engine: the generic rollout of the torch logits
    monkeypatch.setattr("vinadv.planners.interface.engine.plan_maps", _fail)
    got = forward.plan_maps(maps.obstacles, maps.goals, maps.starts)
    assert got.paths == expected.paths and np.array_equal(got.termination, expected.termination)
    np.testing.assert_array_equal(
        engine.value_maps(maps.obstacles, maps.goals), forward.value_maps(maps.obstacles, maps.goals)
    )
    # the weights' own module stays where it was (the forward runs on a copy)
    assert forward.module.vin is not engine.module.vin


def _fail(*args, **kwargs):
    raise AssertionError("the engine ran")


@pytest.mark.slow
@pytest.mark.parametrize("strategy", ["saliency", "exhaustive"])
def test_attacks_on_the_cpu_device_make_the_defaults_pairs(strategy, gppn_file, planning_weights, maps):
    """The gradient attack's backward and the exhaustive search's batches, through the device's planner: the pairs
    of the default (for the VIN: its engine's, an independent computation)."""
    for spec, weights in (("gppn", gppn_file), ("vin", planning_weights(SIZE))):
        default, on_cpu = _planners(spec, weights)
        attack = make_attack(strategy, per_map=0 if strategy == "exhaustive" else 1, budget=4)
        a = attack.attack(maps.obstacles, maps.starts[:, 0], maps.goals, default)
        b = attack.attack(maps.obstacles, maps.starts[:, 0], maps.goals, on_cpu)
        assert len(a.pairs) > 0 and np.array_equal(a.pairs.added, b.pairs.added)
        assert a.pairs.path_a == b.pairs.path_a and np.array_equal(a.pairs.term_a, b.pairs.term_a)
        assert b.pairs.params["planner"]["device"] == "cpu" and "device" not in a.pairs.params["planner"]


def test_a_planner_ref_carries_the_device(gppn_file, planning_weights):
    for spec, weights in (("gppn", gppn_file), ("vin", planning_weights(SIZE))):
        default, on_cpu = _planners(spec, weights)
        assert PlannerRef.of(default, spec, weights, True).device is None
        ref = PlannerRef.of(on_cpu, spec, weights, True)
        assert ref.device == "cpu"
        loaded = ref.load()  # a worker: the client's device
        assert loaded.device_type == "cpu" and loaded.spec() == on_cpu.spec()
        assert PlannerRef.of(default, spec, weights, True).load().spec() == default.spec()


def test_a_worker_without_the_clients_device_refuses_it(gppn_file, no_cuda):
    ref = PlannerRef("gppn", gppn_file, SIZE, True, None, device="cuda")
    with pytest.raises(InputError, match="CUDA is not available"):
        ref.load()
