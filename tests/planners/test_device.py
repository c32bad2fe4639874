"""`--device` in the library: device names checked (`resolve_device`), and every torch planner's device plumbing on the
CPU: `device="cpu"` plans what the default plans (GPPN, a file planner, `+d4`), records its type, travels in a
`PlannerRef`; the VIN's PyTorch forward (`device=` given) plans the exact engine's paths, the engine being the
oracle (tested against the re-run-every-step reference in tests/planners/vin)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from tests.planner_files import NO_PARAMETERS, write_gppn
from vinadv.attacks.strategies import AttackContext, make_attack
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.planners.device import resolve_device
from vinadv.planners.interface import TorchPlanner
from vinadv.planners.registry import PlannerRef, load_planner
from vinadv.planners.vin.planner import VINPlanner
from vinadv.testing.planners import tie_flips

SIZE = 10


@pytest.fixture(scope="module")
def gppn_file(tmp_path_factory):
    return write_gppn(tmp_path_factory.mktemp("g") / "gppn.pt", SIZE, seed=3)


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
    a = default.plan(maps.obstacles, maps.starts, maps.goals)
    b = on_cpu.plan(maps.obstacles, maps.starts, maps.goals)
    assert a.paths == b.paths and np.array_equal(a.termination, b.termination)
    np.testing.assert_array_equal(default.logits(maps.obstacles, maps.goals), on_cpu.logits(maps.obstacles, maps.goals))


def test_the_vin_on_a_device_plans_the_engines_paths_with_its_torch_forward(planning_weights, maps, monkeypatch):
    weights = planning_weights(SIZE)
    engine, forward = _planners("vin", weights)
    assert isinstance(forward, VINPlanner) and forward.device_type == "cpu" and engine.device_type is None
    assert forward.spec() == {**engine.spec(), "device": "cpu"}
    expected = engine.plan_maps(maps.obstacles, maps.goals, maps.starts)
    # the device path never calls the engine: the generic rollout of the torch logits
    monkeypatch.setattr("vinadv.planners.vin.planner.engine.plan_maps", _fail)
    got = forward.plan(maps.obstacles, maps.starts, maps.goals)
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


def test_tie_flips_finds_the_flipped_cells_and_tells_ties_from_differences():
    reference = np.zeros((2, 8, 3, 3))
    reference[:, 0] = 1.0  # action 0 everywhere, by 1 over the rest
    reference[1, 3, 2, 2] = 1.0 - 1e-6  # a near tie at map 1, cell (2, 2)
    other = reference.copy()
    other[1, 3, 2, 2] = 1.0 + 1e-6  # the tie flipped
    other[0, 5, 0, 1] = 2.0  # map 0, cell (0, 1): another choice, by a whole unit
    flips = tie_flips(reference, other, rel_tol=1e-4)
    assert flips["cells"] == 2 and flips["not_ties"] == 1 and flips["maps"].tolist() == [True, True]
    assert tie_flips(reference, reference)["cells"] == 0


# On a CUDA GPU (marked `cuda`: skipped without one; perf/device_check.sh runs them).
#: the shipped 28x28 weights, on maps held out from every training (the robustness benchmark's seed)
GPU_MAPS = 50


@pytest.fixture(scope="module")
def maps28():
    return generate_maps(GPU_MAPS, 28, seed=1000)


def _compare_devices(cpu, gpu, maps) -> dict:
    """Logits and paths of one planner on the CPU and on the GPU: every action that differs is a near tie of the
    CPU's logits, and a path differs only on a map where an action does. Returns the counts."""
    flips = tie_flips(cpu.logits(maps.obstacles, maps.goals), gpu.logits(maps.obstacles, maps.goals))
    a = cpu.plan(maps.obstacles, maps.starts, maps.goals)
    b = gpu.plan(maps.obstacles, maps.starts, maps.goals)
    differ = ~a.paths.same_as(b.paths)
    owner = np.repeat(np.arange(len(maps)), maps.n_starts)
    assert flips["not_ties"] == 0, flips
    assert not (differ & ~flips["maps"][owner]).any()
    return {"flipped_cells": flips["cells"], "paths": len(differ), "paths_differing": int(differ.sum())}


@pytest.mark.cuda
@pytest.mark.parametrize("spec", ["gppn", "gppn+d4", "file"])
def test_torch_planners_on_cuda_plan_the_cpus_paths_but_at_near_ties(spec, maps28, record_property):
    if spec == "file":
        spec = f"{Path(__file__).resolve().parents[2] / 'examples' / 'my_planner.py'}:make"
    cpu, gpu = load_planner(spec, 28), load_planner(spec, 28, device="cuda")
    assert gpu.device.type == "cuda" and gpu.spec()["device"] == "cuda"
    counts = _compare_devices(cpu, gpu, maps28)
    record_property("counts", counts)
    print(spec, counts)


@pytest.mark.cuda
def test_the_vins_forward_on_cuda_plans_the_engines_paths_but_at_near_ties(maps28, record_property):
    engine, cpu, gpu = (load_planner("vin", 28, device=d) for d in (None, "cpu", "cuda"))
    counts = _compare_devices(cpu, gpu, maps28)
    a = engine.plan_maps(maps28.obstacles, maps28.goals, maps28.starts)
    b = gpu.plan(maps28.obstacles, maps28.starts, maps28.goals)
    counts["paths_differing_from_the_engine"] = int((~a.paths.same_as(b.paths)).sum())
    assert counts["paths_differing_from_the_engine"] <= counts["paths_differing"] + int(
        (~a.paths.same_as(cpu.plan(maps28.obstacles, maps28.starts, maps28.goals).paths)).sum()
    )
    record_property("counts", counts)
    print("vin", counts)


@pytest.mark.cuda
def test_the_exhaustive_search_and_saliency_on_cuda_match_the_cpu_but_at_near_ties(maps28):
    """Every candidate of 2 maps in batches on the GPU: the same candidates, each adversarial path the CPU's unless
    its map has a near tie that flipped; saliency's gradients the CPU's to float32 rounding."""
    cpu, gpu = load_planner("gppn", 28), load_planner("gppn", 28, device="cuda")
    m = slice(0, 2)
    obstacles, starts, goals = maps28.obstacles[m], maps28.starts[m, 0], maps28.goals[m]
    a = make_attack("exhaustive", per_map=0).attack(obstacles, starts, goals, cpu)
    b = make_attack("exhaustive", per_map=0).attack(obstacles, starts, goals, gpu)
    assert len(a.pairs) > 500 and np.array_equal(a.pairs.added, b.pairs.added)
    flips = tie_flips(cpu.logits(a.pairs.obstacles_a, a.pairs.goals), gpu.logits(a.pairs.obstacles_a, a.pairs.goals))
    assert flips["not_ties"] == 0
    differ = ~a.pairs.path_a.same_as(b.pairs.path_a)
    assert not (differ & ~flips["maps"]).any()
    print("exhaustive", {"candidates": len(differ), "differing": int(differ.sum()), "flipped_cells": flips["cells"]})

    saliency = make_attack("saliency")
    base = cpu.plan(obstacles, starts, goals)
    ctx = [
        AttackContext(obstacles, starts, goals, np.ones_like(obstacles), base, planner, np.random.default_rng(0))
        for planner in (cpu, gpu)
    ]
    one, two = (saliency.candidate_scores(c) for c in ctx)
    np.testing.assert_allclose(two, one, rtol=1e-3, atol=1e-4 * np.abs(one).max())
