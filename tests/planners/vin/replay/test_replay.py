"""PyTorch's value map replayed: bit for bit against `VIN.q_values` and `conv2d`, and the policy against the ports'."""

import json
import os
import subprocess
import sys
from fractions import Fraction

import numpy as np
import pytest
import torch
import torch.nn.functional as F
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.needs import MODELLED_CPU, cpu_vendor
from vinadv.grid import generate_maps
from vinadv.planners.vin import engine, make_input
from vinadv.planners.vin.flat import from_flat, layout, to_flat
from vinadv.planners.vin.reference import torch_action_at
from vinadv.planners.vin.replay import (
    CACHE,
    ReplayCache,
    actions,
    cache,
    conv_modes,
    exact_actions,
    fc_order,
    replay_q_values,
    sum_order,
)
from vinadv.planners.vin.replay.fc import fma32, replay_fc
from vinadv.planners.vin.replay.kernels import conv_chains, conv_fused, conv_plain, replay_kernel, sum_channels
from vinadv.planners.vin.weights import load_vin, load_vin_weights
from vinadv.testing.planners import planning_vin, random_vin


# 2-thread PyTorch waits for the busy core of a shared 2-core machine (several times slower than one thread): the
# 2-thread variants are slow, the quick tier checks each replay with one thread
@pytest.fixture(params=[pytest.param(1, id="1-thread"), pytest.param(2, id="2-threads", marks=pytest.mark.slow)])
def torch_threads(request):
    before = torch.get_num_threads()
    torch.set_num_threads(request.param)
    yield request.param
    torch.set_num_threads(before)


@pytest.fixture
def fresh_settings(monkeypatch):
    """Nothing measured yet, in memory or on disk (and nothing kept there)."""
    monkeypatch.setenv(cache.CACHE_ENV, "")
    for name, empty in vars(ReplayCache()).items():
        monkeypatch.setattr(CACHE, name, empty)


def require_replay(found: bool, what: str) -> None:
    """Skip a test of the replay itself where this CPU's BLAS order is not modelled; fail where it must be."""
    if not found:
        assert not MODELLED_CPU, f"no {what} found on a CPU whose BLAS orders are modelled"
        pytest.skip(f"{what}: this CPU's BLAS summation order is not modelled ({cpu_vendor()}); PyTorch is used")


def q_replayed_here(n: int, l_h: int = 150, l_q: int = 10, l_i: int = 2) -> bool:
    """Whether `replay_q_values` replays VIN maps of side n here: the convolutions' modes were found (r's order
    need not be: without it PyTorch computes r alone and the rest is replayed)."""
    return conv_modes(n, l_h, l_i, bias=True) is not None and conv_modes(n, l_q) is not None


def bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float32).view(np.int32)


def torch_q(model, x):
    with torch.no_grad():
        return model.q_values(x)[0].numpy()


@pytest.mark.parametrize("size", [9, 16, 28])
def test_modes_reproduce_conv2d_on_other_data(size, torch_threads):
    # the modes come from one random probe; the BLAS kernel depends on shapes only, so they must hold for any data
    modes = conv_modes(size, 10)
    if modes is None:
        pytest.skip("this BLAS chains the taps in neither order: the engine uses VIN.q_values itself")
    rng = np.random.default_rng(size)
    for _ in range(5):
        v = rng.standard_normal((size, size)).astype(np.float32) * rng.uniform(0.1, 100)
        w = rng.standard_normal((10, 3, 3)).astype(np.float32)
        with torch.no_grad():
            want = F.conv2d(torch.from_numpy(v)[None, None], torch.from_numpy(w)[:, None], padding=1)[0].numpy()
        flat = to_flat(v[None])
        fused, plain = np.zeros((10, flat.shape[1]), np.float32), np.zeros((10, flat.shape[1]), np.float32)
        conv_fused(flat, w[:, None], size, fused)
        conv_plain(flat, w[:, None], size, plain)
        got = np.where(modes[:, None, None], from_flat(fused, size), from_flat(plain, size))
        np.testing.assert_array_equal(bits(got), bits(want))


@pytest.mark.parametrize("size, l_h", [(9, 150), (28, 150), (28, 20)])
def test_h_modes_reproduce_the_h_layer_on_other_data(size, l_h, torch_threads):
    # h: 2 input channels, a bias; probed on random data, checked here on other random data and on real inputs
    modes = conv_modes(size, l_h, 2, bias=True)
    if modes is None:
        pytest.skip("this BLAS chains the taps in neither order: the engine uses VIN.q_values itself")
    rng = np.random.default_rng(size + l_h)
    maps = generate_maps(3, size, seed=size, n_starts=1)
    inputs = [rng.standard_normal((2, size, size)).astype(np.float32) * rng.uniform(0.1, 100) for _ in range(3)]
    inputs += [make_input(maps.obstacles[i : i + 1], maps.goals[i : i + 1])[0].numpy() for i in range(3)]
    for x in inputs:
        w = rng.standard_normal((l_h, 2, 3, 3)).astype(np.float32)
        b = rng.standard_normal(l_h).astype(np.float32)
        with torch.no_grad():
            want = F.conv2d(torch.from_numpy(x)[None], torch.from_numpy(w), torch.from_numpy(b), padding=1)[0]
        out = np.zeros((l_h, layout(size)[3]), np.float32)
        conv_chains(to_flat(x), w, size, modes, out)
        np.testing.assert_array_equal(bits(from_flat(out, size) + b[:, None, None]), bits(want.numpy()))


@pytest.mark.parametrize("size, l_h", [(9, 150), (28, 150), (28, 20)])
def test_sum_order_reproduces_the_r_layer_on_other_data(size, l_h, torch_threads):
    order = sum_order(size, l_h)
    if order is None:
        pytest.skip("this BLAS sums in none of the orders tried: the engine uses VIN.q_values itself")
    rng = np.random.default_rng(size + l_h)
    for _ in range(4):
        h = (rng.standard_normal((l_h, size, size)) * rng.uniform(0.01, 100)).astype(np.float32)
        w = rng.standard_normal(l_h).astype(np.float32)
        with torch.no_grad():
            want = F.conv2d(torch.from_numpy(h)[None], torch.from_numpy(w)[None, :, None, None])[0, 0].numpy()
        np.testing.assert_array_equal(bits(sum_channels(h, w, *order)), bits(want))


@pytest.mark.parametrize("size, make", [(9, planning_vin), (16, planning_vin), (16, random_vin), (28, planning_vin)])
def test_replay_kernel_is_q_values_bit_for_bit(size, make, torch_threads):
    modes = conv_modes(size, 10)
    if modes is None:
        pytest.skip("no replay on this BLAS")
    model = make(size, seed=3).eval()
    maps = generate_maps(12, size, seed=8, n_starts=1)
    w = np.ascontiguousarray(model.w.detach().numpy())
    for i in range(len(maps)):
        x = make_input(maps.obstacles[i : i + 1], maps.goals[i : i + 1])
        with torch.no_grad():
            flat = to_flat(model.q(model.r(model.h(x)))[0].numpy())
        replay_kernel(flat, w, model.config.k, size, modes)
        np.testing.assert_array_equal(bits(from_flat(flat, size)), bits(torch_q(model, x)))


def test_shipped_weights_replay_bit_for_bit(torch_threads):
    model = load_vin(None, size=28).eval()
    maps = generate_maps(20, 28, seed=9, n_starts=1)
    for i in range(len(maps)):
        x = make_input(maps.obstacles[i : i + 1], maps.goals[i : i + 1])
        np.testing.assert_array_equal(bits(replay_q_values(model, x)), bits(torch_q(model, x)))


def test_unknown_modes_use_q_values(fresh_settings, monkeypatch):
    model = planning_vin(16, seed=1).eval()
    maps = generate_maps(3, 16, seed=2, n_starts=1)
    x = make_input(maps.obstacles[:1], maps.goals[:1])
    CACHE.conv_modes[(16, 10, 1, False, torch.get_num_threads())] = None

    def must_not_run(*args):
        raise AssertionError("replayed although the modes are unknown")

    monkeypatch.setattr(actions, "replay_kernel", must_not_run)
    np.testing.assert_array_equal(bits(replay_q_values(model, x)), bits(torch_q(model, x)))


def test_unknown_r_order_replays_the_rest_with_pytorchs_r(fresh_settings, monkeypatch):
    model = planning_vin(16, seed=1).eval()
    maps = generate_maps(4, 16, seed=2, n_starts=1)
    threads = torch.get_num_threads()
    require_replay(q_replayed_here(16), "value-map replay")
    CACHE.sum_orders[(16, 150, threads)] = None  # as MKL's 2-thread r layer at 32x32 and 64x64
    kernel_calls = []

    def counted(*args):
        kernel_calls.append(1)
        replay_kernel(*args)

    monkeypatch.setattr(actions, "replay_kernel", counted)
    for i in range(len(maps)):
        x = make_input(maps.obstacles[i : i + 1], maps.goals[i : i + 1])
        np.testing.assert_array_equal(bits(replay_q_values(model, x)), bits(torch_q(model, x)))
    assert len(kernel_calls) == len(maps) and (16, 150, 10, threads) not in CACHE.q_failed


@pytest.mark.parametrize("size, k", [(32, 42), (64, 100)])
def test_vin64_replays_bit_for_bit_at_32_and_64(size, k, torch_threads):
    model = load_vin(None, size=64, k=k).eval()
    maps = generate_maps(3, size, seed=9, n_starts=1)
    for i in range(len(maps)):
        x = make_input(maps.obstacles[i : i + 1], maps.goals[i : i + 1])
        np.testing.assert_array_equal(bits(replay_q_values(model, x)), bits(torch_q(model, x)))
    setting = (size, 150, 10, torch_threads)
    require_replay(q_replayed_here(size), "value-map replay")
    assert setting not in CACHE.q_failed


def test_failed_verification_turns_the_replay_off(fresh_settings, monkeypatch):
    model = planning_vin(16, seed=1).eval()
    maps = generate_maps(3, 16, seed=2, n_starts=1)
    x = make_input(maps.obstacles[:1], maps.goals[:1])
    real_kernel = replay_kernel

    def off_by_one_ulp(q, *args):
        real_kernel(q, *args)
        width, p0 = layout(16)[:2]
        q.view(np.int32)[0, p0 + 5 * width + 5] += 1  # cell (5, 5)

    monkeypatch.setattr(actions, "replay_kernel", off_by_one_ulp)
    np.testing.assert_array_equal(bits(replay_q_values(model, x)), bits(torch_q(model, x)))
    require_replay(q_replayed_here(16), "value-map replay")
    assert (16, 150, 10, torch.get_num_threads()) in CACHE.q_failed


@pytest.mark.parametrize("make", [planning_vin, random_vin])
def test_exact_actions_are_the_ports_policy_on_every_cell(make, torch_threads):
    model = make(16, seed=5).eval()
    maps = generate_maps(6, 16, seed=4, n_starts=1)
    fast = exact_actions(model, maps.obstacles, maps.goals)
    for i in range(len(maps)):
        x = make_input(maps.obstacles[i : i + 1], maps.goals[i : i + 1])
        with torch.no_grad():
            ports = torch_action_at(model, x, model.q_values(x))  # forward's numbers, its value map computed once
        assert [[ports(r, c) for c in range(16)] for r in range(16)] == fast[i].tolist(), i


def test_exact_actions_break_exact_ties_as_the_ports_do():
    # all eight rows of fc alike: every cell is an exact tie, which PyTorch's argmax settles on the lowest index
    model = planning_vin(16, seed=6).eval()
    with torch.no_grad():
        model.fc.weight[:] = model.fc.weight[3].clone()
    maps = generate_maps(2, 16, seed=1, n_starts=1)
    x = make_input(maps.obstacles[:1], maps.goals[:1])
    with torch.no_grad():
        ports = torch_action_at(model, x, model.q_values(x))
    fast = exact_actions(model, maps.obstacles[:1], maps.goals[:1])[0]
    assert all(fast[r, c] == ports(r, c) == 0 for r in range(16) for c in range(16))


def test_replay_calls_no_torch_once_verified(monkeypatch):
    # past a setting's checks, a near-tie map costs no PyTorch call at all (none that could wait on OpenMP threads)
    model = planning_vin(16, seed=7).eval()
    maps = generate_maps(6, 16, seed=3, n_starts=1)
    exact_actions(model, maps.obstacles[:3], maps.goals[:3])  # measures and verifies the setting
    # no PyTorch at all needs every order: the convolutions', r's (else PyTorch computes r) and fc's (else PyTorch
    # decides the near ties); AVX-512 MKL (Intel Xeon) sums r at 16x16 and fc in orders not modelled
    whole = q_replayed_here(16) and sum_order(16, 150) is not None and fc_order(10, 8) is not None
    require_replay(whole, "the whole replay (convolutions, r and fc)")

    def no_torch(*args, **kwargs):
        raise AssertionError("PyTorch called for a verified setting")

    monkeypatch.setattr(F, "conv2d", no_torch)  # every convolution of the VIN (h, r, q, w) goes through it
    monkeypatch.setattr(type(model), "q_values", no_torch)
    got = exact_actions(model, maps.obstacles[3:], maps.goals[3:])
    assert got.shape == (3, 16, 16) and (got >= 0).all()


@pytest.mark.parametrize("l_q", [4, 10, 16, 33])
def test_fc_order_reproduces_linear_bit_for_bit(l_q, torch_threads, fresh_settings):
    order = fc_order(l_q, 8)
    if order is None:  # allowed (PyTorch's own fc is used then), but not for the VIN's width on a modelled CPU
        require_replay(l_q != 10, "summation tree of the VIN's fc")
        return
    rng = np.random.default_rng(l_q)
    for scale in np.logspace(-4, 4, 200):
        q = (scale * rng.standard_normal(l_q)).astype(np.float32)
        w = rng.standard_normal((8, l_q)).astype(np.float32)
        with torch.no_grad():
            want = F.linear(torch.from_numpy(q)[None], torch.from_numpy(w))[0].numpy()
        np.testing.assert_array_equal(bits(replay_fc(w, q, *order)), bits(want))


def float32_nearest(x: Fraction) -> np.float32:
    """The float32 nearest to the exact rational x, ties to even: an oracle by exact comparison."""
    guess = np.float32(float(x))
    candidates = [np.nextafter(guess, np.float32(-np.inf)), guess, np.nextafter(guess, np.float32(np.inf))]
    dist = [abs(Fraction(float(c)) - x) for c in candidates]
    best = min(dist)
    ties = [c for c, d in zip(candidates, dist) if d == best]
    return ties[0] if len(ties) == 1 else next(c for c in ties if int(np.array(c).view(np.int32)) % 2 == 0)


finite32 = st.floats(width=32, allow_nan=False, allow_infinity=False, min_value=-(2.0**60), max_value=2.0**60)


@settings(max_examples=400, deadline=None)
@given(finite32, finite32, finite32)
def test_fma32_rounds_once(a, b, c):
    a, b, c = np.float32(a), np.float32(b), np.float32(c)
    exact = Fraction(float(a)) * Fraction(float(b)) + Fraction(float(c))
    assert fma32(a, b, c) == float32_nearest(exact)


def test_fma32_on_halfway_sums():
    # a * b + c = 1 + 2^-24 + 2^-70: float64 drops the tail and lands halfway between 1 and 1 + 2^-23, where
    # rounding twice picks the even 1; one rounding of the exact value gives 1 + 2^-23
    a, b = np.float32(-(2.0**-12) * (1 + 2.0**-23)), np.float32(2.0**-12 * (1 - 2.0**-23))
    c = np.float32(1 + 2.0**-23)
    assert np.float32(float(a) * float(b) + float(c)) == np.float32(1.0)  # the double rounding avoided
    exact = Fraction(float(a)) * Fraction(float(b)) + Fraction(float(c))
    assert fma32(a, b, c) == float32_nearest(exact) == np.float32(1 + 2.0**-23)


def test_fc_replay_calls_no_torch_once_verified(monkeypatch, fresh_settings):
    # fc rows all alike: every cell is a near tie, decided by the replayed fc (PyTorch only for the first checks)
    model = planning_vin(16, seed=6).eval()
    with torch.no_grad():
        model.fc.weight[:] = model.fc.weight[3].clone()
    maps = generate_maps(3, 16, seed=1, n_starts=1)
    exact_actions(model, maps.obstacles[:1], maps.goals[:1])
    assert fc_order(10, 8) is None or CACHE.fc_verified[(10, 8, torch.get_num_threads())] > 0

    def no_torch(*args, **kwargs):
        raise AssertionError("PyTorch's fc called for a verified setting")

    if fc_order(10, 8) is not None:
        monkeypatch.setattr(type(model.fc), "forward", no_torch)
    assert (exact_actions(model, maps.obstacles[1:], maps.goals[1:]) == 0).all()


def test_failed_fc_verification_turns_the_fc_replay_off(monkeypatch, fresh_settings):
    model = planning_vin(16, seed=6).eval()
    with torch.no_grad():
        model.fc.weight[:] = model.fc.weight[3].clone()
        model.fc.weight[5] *= 1.0000001  # one action a little stronger: ties no longer hide a wrong replay
    maps = generate_maps(2, 16, seed=1, n_starts=1)
    x = make_input(maps.obstacles[:1], maps.goals[:1])
    with torch.no_grad():
        ports = torch_action_at(model, x, model.q_values(x))
    real = replay_fc

    def wrong(w, q, tree, fused):
        out = real(w, q, tree, fused)
        out[0] = np.float32(np.inf)  # action 0 always wins
        return out

    monkeypatch.setattr(actions, "replay_fc", wrong)
    fast = exact_actions(model, maps.obstacles[:1], maps.goals[:1])[0]
    assert all(fast[r, c] == ports(r, c) for r in range(16) for c in range(16))
    assert fc_order(10, 8) is None or (10, 8, torch.get_num_threads()) in CACHE.fc_failed


PLAN_WITHOUT_TORCH = """
import sys
import numpy as np

class NoTorch:
    def find_spec(self, name, path=None, target=None):
        if name == "torch" or name.startswith("torch."):
            raise ImportError("PyTorch must not be loaded")

if sys.argv[1] == "blocked":
    sys.meta_path.insert(0, NoTorch())
from vinadv.grid import generate_maps
from vinadv.planners.vin import engine
from vinadv.planners.vin.weights import load_vin_weights

maps = generate_maps(300, 28, seed=4, n_starts=1)
stats = {}
result = engine.plan_maps(maps.obstacles, maps.goals, maps.starts, load_vin_weights(None, 28), stats=stats)
np.savez(sys.argv[2], cells=result.paths.cells, offsets=result.paths.offsets, terms=result.termination)
print(stats["near_tie_maps"])
"""


@pytest.mark.slow
def test_a_process_without_pytorch_plans_what_pytorch_would(tmp_path):
    # the first process measures PyTorch's arithmetic and keeps it; the second plans without PyTorch, near ties
    # included, and gets the paths of the engine checked against PyTorch in this process (same thread count)
    env = {**os.environ, "VINADV_CACHE_DIR": str(tmp_path / "cache"), "OMP_NUM_THREADS": "1"}
    runs = {}
    for mode in ("measure", "blocked"):
        done = subprocess.run(
            [sys.executable, "-c", PLAN_WITHOUT_TORCH, mode, str(tmp_path / f"{mode}.npz")],
            capture_output=True,
            text=True,
            env=env,
            timeout=600,
        )
        assert done.returncode == 0, done.stderr[-3000:]
        runs[mode] = (int(done.stdout.split()[-1]), np.load(tmp_path / f"{mode}.npz"))
        if mode == "measure":
            (kept,) = json.loads((tmp_path / "cache" / "torch_replay.json").read_text())["machines"].values()
            require_replay("q_verified" in kept, "a verified replay of the value map")
    near_ties, blocked = runs["blocked"]
    assert near_ties > 0  # the near-tie replay did run without PyTorch
    maps = generate_maps(300, 28, seed=4, n_starts=1)
    with_torch = engine.plan_maps(maps.obstacles, maps.goals, maps.starts, load_vin_weights(None, 28))
    assert torch.get_num_threads() == 1
    np.testing.assert_array_equal(blocked["cells"], with_torch.paths.cells)
    np.testing.assert_array_equal(blocked["offsets"], with_torch.paths.offsets)
    np.testing.assert_array_equal(blocked["terms"], with_torch.termination)


def test_kept_settings_are_per_machine_key(fresh_settings, monkeypatch, tmp_path):
    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path))
    monkeypatch.delenv("MKL_CBWR", raising=False)
    cache.machine_key.cache_clear()  # the key of this test's environment (others may have changed it)
    try:
        model = planning_vin(16, seed=7).eval()
        maps = generate_maps(4, 16, seed=3, n_starts=1)
        exact_actions(model, maps.obstacles, maps.goals)
        kept = json.loads(cache.cache_path().read_text())
        before = cache.machine_key()
        assert list(kept["machines"]) == [before]
        cache.machine_key.cache_clear()
        assert cache.machine_key() == before
        cache.machine_key.cache_clear()
        monkeypatch.setenv("MKL_CBWR", "COMPATIBLE")  # MKL's results may change: nothing measured applies
        assert cache.machine_key() != before
    finally:
        cache.machine_key.cache_clear()
