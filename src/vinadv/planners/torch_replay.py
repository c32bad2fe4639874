"""PyTorch's own value map and policy for one map, bit for bit, without PyTorch: how the engine settles near ties.

Where two logits of a cell are within rounding of each other, the engine must take the reference's decision, which is
made by PyTorch's float32 arithmetic: a batch-1 `VIN.q_values`, then `fc` at the cell. That call costs ~3 ms at
28x28 on a quiet core, nearly all of it the overhead of the 3k small ops of the loop, and much more on a busy
machine: with 2 PyTorch threads and another process holding a core, each small op waits for OpenMP threads (the h
layer alone took 23 ms instead of 0.1 ms). Each op is cheap and simple to replay:

- h, the 2 -> l_h 3x3 convolution with bias, and the 1 -> l_q 3x3 convolutions (the first q layer on r, then w on
  v at every step) go through ATen's `slow_conv2d` at batch size 1: im2col (exact copies, zero padding), then a BLAS
  sgemm with K = 9 x input channels, which builds each output as a chain over the taps (input channel, kernel row,
  kernel column), starting from 0, then adds the bias; per output channel the chain is either fused multiply-adds
  or multiply-then-add, depending on the BLAS kernel (MKL, 1 -> l_q on 2 threads: blocks of 8 channels fused, the
  rest not; on 1 thread: all fused; h: all fused on 1 and 2 threads);
- r, the 1x1 convolution l_h -> 1, is an sgemm with M = 1: one or two chains over the l_h channels (MKL on 2
  threads: fused, split at 128; on 1 thread: one unfused chain);
- `q_r + conv` is one float32 add and the max over channels is exact.

`replay_q_values` replays all of it in compiled loops that round exactly as above. Which chains is measured, never
assumed: `conv_modes` and `sum_order` run PyTorch's convolutions on random data once for each (map size, widths,
PyTorch threads) and keep the chains that reproduce them bit for bit; the first `VERIFY_MAPS` maps of each setting
are also compared whole with `VIN.q_values`. If a check fails, that setting uses `VIN.q_values` itself (slow, but
exact). So the only PyTorch calls are those checks, a few per setting and process.

"Bit for bit" means: equal to what PyTorch computes with the caller's `torch.get_num_threads()`, the setting the
reference planner runs under (PyTorch's own float32 results depend on its thread count); in a process that has not
loaded PyTorch, with the thread count PyTorch starts with there.

What was measured and checked is kept on disk per machine (`cache_path()`, keyed by `machine_key()`: PyTorch's
version, the CPU, the cores and the BLAS/OpenMP environment variables), so a later process replays without loading
PyTorch at all: `vinadv run` with the VIN then never imports it. Delete the file to measure again.

`exact_actions` then decides every cell of a map from that value map: in float64 where the two best logits are
further apart than any float32 evaluation of `fc` could move them (a rigorous bound), else (rare: about 50 cells in
a 5,000-map run) with `fc` at the cell replayed as PyTorch computes it, a (1, l_q) x (l_q, A) product whose sum
follows a fixed tree that is neither a chain nor any textbook order (MKL on 1 and 2 threads, l_q = 10: three
products chained, then four lanes, then the lanes summed in halves). `fc_order` reads that tree off PyTorch with
exact probes (a +B and a -B product cancel exactly and a 1 survives only if the two meet before it) and decides
on random data whether the products are fused into the adds; the first `VERIFY_CELLS` cells of each setting are
also compared with PyTorch's own `fc`.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import json
import os
import platform
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numba
import numpy as np

from vinadv.planners.vin.arrays import VINWeights, as_vin_weights, input_array
from vinadv.planners.vin.flat import from_flat, layout, to_flat, zero_row_gaps

if TYPE_CHECKING:
    from vinadv.planners.vin.model import VIN

__all__ = [
    "best_and_gap",
    "cache_path",
    "conv_modes",
    "exact_actions",
    "fc_order",
    "machine_key",
    "replay_q_values",
    "sum_order",
    "torch_threads_now",
]

#: maps per setting whose replayed value map is compared with `VIN.q_values` before the replay is trusted alone
VERIFY_MAPS = 2
#: near-tie cells per setting whose replayed `fc` logits are compared with PyTorch's before the replay is trusted
VERIFY_CELLS = 2
#: random convolutions `conv_modes` compares
PROBES = 16
#: the widest `fc` (l_q) whose summation tree `fc_order` measures (its probes grow as l_q^3 / A); wider ones: PyTorch
MAX_FC_WIDTH = 64
_FLOAT32_UNIT_ROUNDOFF = 2.0**-24

#: environment variable naming the folder of the measured settings ("" keeps nothing on disk)
CACHE_ENV = "VINADV_CACHE_DIR"
CACHE_FORMAT = "vinadv.torch-replay-cache/1"
#: environment variables that can change PyTorch's (MKL's, OpenMP's) float32 results or its thread count
_ENVIRONMENT = (
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "MKL_CBWR",
    "MKL_ENABLE_INSTRUCTIONS",
    "MKL_DEBUG_CPU_TYPE",
    "MKL_DYNAMIC",
    "OMP_DYNAMIC",
    "ATEN_CPU_CAPABILITY",
)

# In memory, per process. (N, out channels, in channels, bias, torch threads) -> per-channel fused flags;
# (N, l_h, torch threads) -> (fused, split); None where no replay reproduces PyTorch
_modes: dict[tuple[int, int, int, bool, int], np.ndarray | None] = {}
_orders: dict[tuple[int, int, int], tuple[bool, int] | None] = {}
# (N, l_h, l_q, torch threads): maps checked whole against VIN.q_values; settings where one differed
_verified: dict[tuple[int, int, int, int], int] = {}
_failed: set[tuple[int, int, int, int]] = set()
# (l_q, actions, torch threads) -> (summation tree, fused) of `fc`, None where none reproduces PyTorch; cells checked
_fc_orders: dict[tuple[int, int, int], tuple[tuple, bool] | None] = {}
_fc_verified: dict[tuple[int, int, int], int] = {}
_fc_failed: set[tuple[int, int, int]] = set()
# this machine's entries of the cache file, `{kind: {key: value}}`, read at the first use
_disk: dict[str, dict] | None = None


def cache_path() -> Path | None:
    """The file keeping the measured settings: `$VINADV_CACHE_DIR/torch_replay.json`, else under
    `$XDG_CACHE_HOME/vinadv` or `~/.cache/vinadv`; None when `VINADV_CACHE_DIR` is set empty (nothing kept)."""
    folder = os.environ.get(CACHE_ENV)
    if folder is None:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        folder = os.path.join(base, "vinadv")
    return Path(folder) / "torch_replay.json" if folder else None


@functools.cache
def machine_key() -> str:
    """What PyTorch's float32 results may depend on besides the thread count, hashed: PyTorch's version (which fixes
    the MKL it ships), the CPU's model and instruction sets, the cores this process may use and the BLAS/OpenMP
    environment variables."""
    model, flags = platform.processor(), ""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                name, _, value = line.partition(":")
                if name.strip() == "model name" and not flags:
                    model = value.strip()
                elif name.strip() in ("flags", "Features"):
                    flags = value.strip()
                    break
    except OSError:
        pass
    try:
        torch_version = importlib.metadata.version("torch")
    except importlib.metadata.PackageNotFoundError:
        torch_version = None
    parts = [
        torch_version,
        platform.machine(),
        model,
        flags,
        len(os.sched_getaffinity(0)),
        {name: os.environ.get(name) for name in _ENVIRONMENT},
    ]
    return hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest()[:24]


def _disk_entries() -> dict[str, dict]:
    global _disk
    if _disk is None:
        data = _read_cache()
        _disk = data["machines"].get(machine_key(), {})
    return _disk


def _read_cache() -> dict:
    path = cache_path()
    try:
        data = json.loads(path.read_text()) if path is not None else None
    except (OSError, ValueError):
        data = None
    ok = isinstance(data, dict) and data.get("format") == CACHE_FORMAT and isinstance(data.get("machines"), dict)
    return data if ok else {"format": CACHE_FORMAT, "machines": {}}


def _recall(kind: str, key: tuple) -> tuple[bool, object]:
    """`(True, value)` if `kind` was measured for `key` on this machine, else `(False, None)`."""
    entries = _disk_entries().get(kind, {})
    name = ",".join(map(str, key))
    return name in entries, entries.get(name)


def _remember(kind: str, key: tuple, value) -> None:
    """Keep a measurement (JSON value) for this machine, in memory and in the cache file (merged with what other
    processes wrote there; a file that cannot be written costs time later, never correctness)."""
    _disk_entries().setdefault(kind, {})[",".join(map(str, key))] = value
    path = cache_path()
    if path is None:
        return
    data = _read_cache()
    mine = data["machines"].setdefault(machine_key(), {})
    for name, entries in _disk_entries().items():
        mine.setdefault(name, {}).update(entries)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp.write_text(json.dumps(data, sort_keys=True))
        os.replace(tmp, path)
    except OSError:
        pass


def _measured(kind: str, key: tuple, measure, decode=lambda value: value):
    """The value of `kind` for `key`: kept on disk for this machine, else `measure()` (with PyTorch) and kept."""
    found, value = _recall(kind, key)
    if not found:
        value = measure()
        _remember(kind, key, value)
    return None if value is None else decode(value)


def torch_threads_now() -> int:
    """PyTorch's intra-op thread count: `torch.get_num_threads()` once PyTorch is loaded; before that, the count it
    starts with on this machine (read once, kept on disk)."""
    if "torch" in sys.modules:
        return sys.modules["torch"].get_num_threads()

    def first_count() -> int:
        import torch

        return torch.get_num_threads()

    return int(_measured("default_threads", (), first_count))


def _trusted(kind: str, setting: tuple, counts: dict, needed: int) -> bool:
    """Whether a setting's checks are done: `needed` checks passed in this process, or before on this machine."""
    if counts.get(setting, 0) < needed and _recall(kind, setting)[0]:
        counts[setting] = needed
    return counts.get(setting, 0) >= needed


def _passed(kind: str, setting: tuple, counts: dict, needed: int) -> None:
    """One check of a setting passed; with the `needed`-th, the setting is trusted on this machine from now on."""
    counts[setting] = counts.get(setting, 0) + 1
    if counts[setting] == needed:
        _remember(kind, setting, True)


def conv_modes(n: int, l_out: int, l_in: int = 1, bias: bool = False) -> np.ndarray | None:
    """Per output channel, whether PyTorch's `conv2d((1, l_in, N, N), (l_out, l_in, 3, 3), padding=1)` (with a
    bias added last when `bias`) chains its 9 * l_in taps with fused multiply-adds (True) or multiply-then-add
    (False), `(l_out,)` bool; None if neither chain reproduces some channel bit for bit. Measured once per
    (N, widths, bias, PyTorch threads) on random data, then cached.

    Several probes at scales from 1e-2 to 1e2: a BLAS may treat a few cells apart (seen: MKL on 2 threads at 9x9 and
    13x13 rounds two cells of the unfused channels otherwise), and one probe can round them alike by chance."""
    key = (n, l_out, l_in, bias, torch_threads_now())
    if key not in _modes:
        _modes[key] = _measured(
            "conv_modes", key, lambda: _measure_conv_modes(n, l_out, l_in, bias), lambda v: np.array(v, dtype=bool)
        )
    return _modes[key]


def _measure_conv_modes(n: int, l_out: int, l_in: int, bias: bool) -> list[bool] | None:
    import torch
    import torch.nn.functional as F

    rng = np.random.default_rng(0)
    fused_ok, plain_ok = np.ones(l_out, bool), np.ones(l_out, bool)
    for scale in np.logspace(-2, 2, PROBES):
        v = (scale * rng.standard_normal((l_in, n, n))).astype(np.float32)
        w = rng.standard_normal((l_out, l_in, 3, 3)).astype(np.float32)
        b = rng.standard_normal(l_out).astype(np.float32) if bias else None
        with torch.no_grad():
            want = F.conv2d(
                torch.from_numpy(v)[None],
                torch.from_numpy(w),
                None if b is None else torch.from_numpy(b),
                padding=1,
            )[0].numpy()
        flat_v = to_flat(v)
        for fused, ok in ((True, fused_ok), (False, plain_ok)):
            out = np.empty((l_out, flat_v.shape[1]), np.float32)
            _conv_chains(flat_v, w, n, np.full(l_out, fused), out)
            got = _add_bias(from_flat(out, n), b)
            ok &= (got == want).reshape(l_out, -1).all(axis=1)
    # a channel that both chains reproduce would leave its mode unknown; random data makes that vanishingly rare
    return fused_ok.tolist() if np.all(fused_ok ^ plain_ok) else None


def sum_order(n: int, l_h: int) -> tuple[bool, int] | None:
    """How PyTorch's 1x1 convolution `(1, l_h, N, N) -> (1, 1, N, N)` (the r layer; a BLAS sgemm with M = 1 and
    K = l_h) sums its l_h products: `(fused, split)`, a chain over k = 0 .. split - 1 and one over split .. l_h - 1
    (split 0: a single chain), added; None if no such order reproduces it bit for bit. Seen: MKL on 1 thread, one
    unfused chain; on 2 threads, fused chains split at 128. Measured once per (N, l_h, PyTorch threads)."""
    key = (n, l_h, torch_threads_now())
    if key not in _orders:
        _orders[key] = _measured("sum_order", key, lambda: _measure_sum_order(n, l_h), tuple)
    return _orders[key]


def _measure_sum_order(n: int, l_h: int) -> list | None:
    import torch
    import torch.nn.functional as F

    candidates = [(fused, split) for fused in (True, False) for split in (0, 64, 128, 256, 512) if split < l_h]
    rng = np.random.default_rng(1)
    for scale in np.logspace(-2, 2, PROBES // 4):
        h = (scale * rng.standard_normal((l_h, n, n))).astype(np.float32)
        w = rng.standard_normal(l_h).astype(np.float32)
        with torch.no_grad():
            want = F.conv2d(torch.from_numpy(h)[None], torch.from_numpy(w)[None, :, None, None])[0, 0].numpy()
        candidates = [
            (fused, split) for fused, split in candidates if np.array_equal(_sum_channels(h, w, fused, split), want)
        ]
    return list(candidates[0]) if len(candidates) == 1 else None


@dataclass(frozen=True)
class _Weights:
    """A VIN's float32 weights as the replay reads them: h `(l_h, l_i, 3, 3)` and its bias, r `(l_h,)`, q and w
    `(l_q, 1, 3, 3)`; fc `(A, l_q)` float64 for the certain decisions and `fc32` as it is; `vin` the weights."""

    h: np.ndarray
    h_bias: np.ndarray
    r: np.ndarray
    q: np.ndarray
    w: np.ndarray
    fc: np.ndarray
    fc32: np.ndarray
    k: int
    vin: VINWeights

    @classmethod
    def of(cls, weights: VINWeights) -> _Weights:
        state = {key: np.ascontiguousarray(value, dtype=np.float32) for key, value in weights.state.items()}
        return cls(
            h=state["h.weight"],
            h_bias=state["h.bias"],
            r=state["r.weight"][0, :, 0, 0].copy(),
            q=state["q.weight"],
            w=state["w"],
            fc=state["fc.weight"].astype(np.float64),
            fc32=state["fc.weight"],
            k=int(weights.config.k),
            vin=weights,
        )


def replay_q_values(model: VINWeights | VIN, x) -> np.ndarray:
    """`model.q_values(x)[0]` for one map `x (1, l_i, N, N)` (array or tensor), bit for bit (with the caller's
    PyTorch threads), for a `VIN` or `VINWeights`: `(l_q, N, N)` float32."""
    return _q_values(_Weights.of(as_vin_weights(model)), np.asarray(x[0], dtype=np.float32))


def exact_actions(model: VINWeights | VIN, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """The reference's action at every cell (argmax of PyTorch's logits, lowest index on ties), `(M, N, N)` int8,
    for a `VIN` or `VINWeights`, obstacles `(M, N, N)` bool and goals `(M, 2)`: the replayed value map
    (`replay_q_values`), each cell decided in float64 where that is certain, else by `fc` at the cell as PyTorch
    computes it (`_fc_action`)."""
    p = _Weights.of(as_vin_weights(model))
    x = input_array(obstacles, np.asarray(goals))
    gamma = p.fc.shape[1] * _FLOAT32_UNIT_ROUNDOFF
    out = np.empty(np.shape(obstacles), dtype=np.int8)
    for m in range(len(x)):  # per map: compiled loops (PyTorch only for a setting's first checks)
        q = _q_values(p, x[m])
        _certain_actions(q, p.fc, gamma, out[m])
        for row, col in np.argwhere(out[m] < 0):
            out[m, row, col] = _fc_action(p, q[:, row, col])
    return out


def _fc_action(p: _Weights, q: np.ndarray) -> int:
    """The reference's decision at one cell with value vector `q (l_q,)` float32: PyTorch's `fc` logits, replayed
    where its summation order is known and verified, argmax with the lowest index on ties (`np.argmax`)."""
    setting = (p.fc.shape[1], p.fc.shape[0], torch_threads_now())
    order = fc_order(p.fc.shape[1], p.fc.shape[0])
    if order is None or setting in _fc_failed:
        return int(np.argmax(_torch_fc(p.vin, q)))
    logits = _replay_fc(p.fc32, q, *order)
    if not _trusted("fc_verified", setting, _fc_verified, VERIFY_CELLS):
        want = _torch_fc(p.vin, q)
        if not np.array_equal(logits.view(np.int32), want.view(np.int32)):
            _fc_failed.add(setting)
            return int(np.argmax(want))
        _passed("fc_verified", setting, _fc_verified, VERIFY_CELLS)
    return int(np.argmax(logits))


def _torch_fc(weights: VINWeights, q: np.ndarray) -> np.ndarray:
    """PyTorch's `fc` on one value vector `(l_q,)`, as `VIN.forward` applies it: `(A,)` float32."""
    import torch

    with torch.no_grad():
        return weights.module().fc(torch.from_numpy(np.ascontiguousarray(q, dtype=np.float32))[None])[0].numpy()


def fc_order(l_q: int, n_actions: int) -> tuple[tuple, bool] | None:
    """How PyTorch's `F.linear((1, l_q), (A, l_q))` (the VIN's `fc` at one cell) sums the l_q products of each
    logit: `(tree, fused)`, a binary tree over the product indices (nested pairs, leaves ints) and whether each add
    with a product beside it is a fused multiply-add (the product of the higher index, where both are products);
    None if no such tree reproduces PyTorch bit for bit. Measured once per (l_q, A, PyTorch threads).

    The tree comes from exact probes: with products +B, -B and 1 at indices i, j and k (B = 2^30, where 1 is below
    half an ulp) the logit is 1 exactly when i and j meet before k, else 0; those relations give every subtree."""
    key = (l_q, n_actions, torch_threads_now())
    if key not in _fc_orders:
        _fc_orders[key] = _measured("fc_order", key, lambda: _measure_fc_order(l_q, n_actions), _tree_of)
    return _fc_orders[key]


def _tree_of(value) -> tuple[tuple, bool]:
    """`(tree, fused)` back from JSON lists."""

    def tree(node):
        return node if isinstance(node, int) else tuple(tree(child) for child in node)

    return tree(value[0]), bool(value[1])


def _linear(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    import torch
    import torch.nn.functional as F

    with torch.no_grad():
        return F.linear(torch.from_numpy(q)[None], torch.from_numpy(w))[0].numpy()


def _measure_fc_order(l_q: int, n_actions: int) -> tuple[tuple, bool] | None:
    if l_q > MAX_FC_WIDTH:
        return None
    big = np.float32(2.0**30)
    ones = np.ones(l_q, np.float32)
    # the leaves under the subtree where i and j meet: i, j and every k that does not survive their cancelling;
    # one probe per logit (each logit is summed on its own; a wrong tree fails the random check below anyway)
    subtrees = {frozenset([k]) for k in range(l_q)} | {frozenset(range(l_q))}
    for i in range(l_q):
        for j in range(i + 1, l_q):
            members, others = {i, j}, [k for k in range(l_q) if k not in (i, j)]
            for lo in range(0, len(others), n_actions):
                ks = others[lo : lo + n_actions]
                w = np.zeros((n_actions, l_q), np.float32)
                w[:, i], w[:, j] = big, -big
                w[np.arange(len(ks)), ks] = 1.0
                logits = _linear(ones, w)[: len(ks)]
                if not np.all((logits == 0.0) | (logits == 1.0)):
                    return None
                members.update(k for k, y in zip(ks, logits) if y == 0.0)
            subtrees.add(frozenset(members))
    tree = _build_tree(frozenset(range(l_q)), subtrees)
    if tree is None:
        return None
    rng = np.random.default_rng(2)
    probes = [
        (
            (scale * rng.standard_normal(l_q)).astype(np.float32),
            rng.standard_normal((n_actions, l_q)).astype(np.float32),
        )
        for scale in np.logspace(-2, 2, PROBES)
    ]
    found = [
        fused
        for fused in (True, False)
        if all(np.array_equal(_replay_fc(w, q, tree, fused), _linear(q, w)) for q, w in probes)
    ]
    return (tree, found[0]) if len(found) == 1 else None


def _build_tree(leaves: frozenset, subtrees: set[frozenset]):
    """The binary tree whose subtrees' leaf sets are `subtrees` under `leaves`, as nested pairs; None if they are not
    the subtrees of one binary tree."""
    if len(leaves) == 1:
        return next(iter(leaves))
    inside = [t for t in subtrees if t < leaves]
    children = [t for t in inside if not any(t < u for u in inside)]
    if len(children) != 2 or children[0] | children[1] != leaves or children[0] & children[1]:
        return None
    first, second = sorted(children, key=min)
    left, right = _build_tree(first, subtrees), _build_tree(second, subtrees)
    return None if left is None or right is None else (left, right)


def _replay_fc(w: np.ndarray, q: np.ndarray, tree, fused: bool) -> np.ndarray:
    """The logits `w (A, l_q) @ q (l_q,)` in float32, summed along `tree` (`fc_order`): `(A,)` float32."""

    def value(node, a):
        if isinstance(node, int):
            return np.float32(w[a, node] * q[node])
        left, right = node
        if fused and (isinstance(left, int) or isinstance(right, int)):
            leaf, other = (right, left) if isinstance(right, int) else (left, right)
            return _fma32(w[a, leaf], q[leaf], value(other, a))
        return np.float32(value(left, a) + value(right, a))

    return np.array([value(tree, a) for a in range(w.shape[0])], dtype=np.float32)


def _fma32(a: np.float32, b: np.float32, c: np.float32) -> np.float32:
    """a * b + c rounded once to float32 (a fused multiply-add): the float64 product is exact, the float64 sum is
    made exact by its rounding error (TwoSum), and only a sum landing exactly halfway between two float32 needs
    that error to round the right way."""
    p, c = float(a) * float(b), float(c)
    s = p + c
    t = s - p
    err = (p - (s - t)) + (c - t)
    r = np.float32(s)
    if err != 0.0 and float(r) != s:
        other = np.nextafter(r, np.float32(np.inf) if s > float(r) else np.float32(-np.inf))
        if abs(float(other) - s) == abs(float(r) - s):  # s is a tie between r and other: the error decides
            r = other if (err > 0) == (float(other) > s) else r
    return np.float32(r)


def _q_values(p: _Weights, x: np.ndarray) -> np.ndarray:
    """q of one map `x (l_i, N, N)` float32: replayed where the setting's chains are known and verified, else
    `VIN.q_values` itself. `(l_q, N, N)` float32."""
    l_i, n = x.shape[0], x.shape[-1]
    l_h, l_q = p.h.shape[0], p.q.shape[0]
    h_modes, q_modes, order = conv_modes(n, l_h, l_i, bias=True), conv_modes(n, l_q), sum_order(n, l_h)
    setting = (n, l_h, l_q, torch_threads_now())
    if h_modes is None or q_modes is None or order is None or setting in _failed:
        return _torch_q_values(p.vin, x)
    flat_x = to_flat(x)
    h = np.empty((l_h, flat_x.shape[1]), dtype=np.float32)
    _conv_chains(flat_x, p.h, n, h_modes, h)
    r = _sum_channels(_add_bias(from_flat(h, n), p.h_bias), p.r, *order)
    q = np.empty((l_q, flat_x.shape[1]), dtype=np.float32)
    _conv_chains(to_flat(r[None]), p.q, n, q_modes, q)
    _replay_kernel(q, p.w, p.k, n, q_modes)
    q = from_flat(q, n)
    if not _trusted("q_verified", setting, _verified, VERIFY_MAPS):
        want = _torch_q_values(p.vin, x)
        if not np.array_equal(q.view(np.int32), want.view(np.int32)):
            _failed.add(setting)
            return want
        _passed("q_verified", setting, _verified, VERIFY_MAPS)
    return q


def _torch_q_values(weights: VINWeights, x: np.ndarray) -> np.ndarray:
    import torch

    with torch.no_grad():
        return weights.module().q_values(torch.from_numpy(np.ascontiguousarray(x))[None])[0].numpy()


def _add_bias(x: np.ndarray, bias: np.ndarray | None) -> np.ndarray:
    """x `(C, N, N)` float32 plus bias `(C,)` per channel, one float32 add, as the BLAS adds it after the chain."""
    return x if bias is None else x + bias[:, None, None]


# The chains run over the flat layout (`vinadv.planners.vin.flat`), the taps read through views at their offsets; a real
# cell reads zeros where it leaves the grid, as im2col does. Each chain starts from 0, as the BLAS kernels do, and
# goes through the input channels in order, the nine taps of each in kernel order; `out` holds the running sum
# between channels (a float32 store is exact).


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def _conv_fused(v, w, n, out):
    """out[o] = the taps of w[o] chained, acc = fma(w[o, c, tap], v[c, cell + tap], acc). v `(C, size)`,
    w `(O, C, 3, 3)`, out `(O, size)` float32."""
    width, p0, length = layout(n)[:3]
    for o in range(w.shape[0]):
        acc = out[o, p0 : p0 + length]
        acc[:] = 0.0  # so that each add has one product to fuse with, the chain's own
        for c in range(w.shape[1]):
            x = v[c]
            u0, u1, u2 = x[p0 - width - 1 :], x[p0 - 1 :], x[p0 + width - 1 :]  # rows above, same, below
            w00, w01, w02, w10, w11, w12, w20, w21, w22 = w[o, c].ravel()
            for t in range(length):
                a = w00 * u0[t] + acc[t]
                a = w01 * u0[t + 1] + a
                a = w02 * u0[t + 2] + a
                a = w10 * u1[t] + a
                a = w11 * u1[t + 1] + a
                a = w12 * u1[t + 2] + a
                a = w20 * u2[t] + a
                a = w21 * u2[t + 1] + a
                acc[t] = w22 * u2[t + 2] + a


@numba.njit(cache=True, nogil=True)
def _conv_plain(v, w, n, out):
    """As `_conv_fused`, each product rounded before it is added (compiled without `contract`: never fused)."""
    width, p0, length = layout(n)[:3]
    for o in range(w.shape[0]):
        acc = out[o, p0 : p0 + length]
        acc[:] = 0.0
        for c in range(w.shape[1]):
            x = v[c]
            u0, u1, u2 = x[p0 - width - 1 :], x[p0 - 1 :], x[p0 + width - 1 :]
            w00, w01, w02, w10, w11, w12, w20, w21, w22 = w[o, c].ravel()
            for t in range(length):
                a = w00 * u0[t] + acc[t]
                a = w01 * u0[t + 1] + a
                a = w02 * u0[t + 2] + a
                a = w10 * u1[t] + a
                a = w11 * u1[t + 1] + a
                a = w12 * u1[t + 2] + a
                a = w20 * u2[t] + a
                a = w21 * u2[t + 1] + a
                acc[t] = w22 * u2[t + 2] + a


@numba.njit(cache=True, nogil=True)
def _conv_chains(v, w, n, fused, out):
    """out[o] = output channel o of the convolution of v (flat, `(C, size)`) with w `(O, C, 3, 3)`, chained as
    `fused[o]` says."""
    for o in range(w.shape[0]):
        if fused[o]:
            _conv_fused(v, w[o : o + 1], n, out[o : o + 1])
        else:
            _conv_plain(v, w[o : o + 1], n, out[o : o + 1])


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def _fused_chain(h, w, lo, hi, acc):
    for k in range(lo, hi):
        wk, hk = w[k], h[k]
        for p in range(acc.size):
            acc[p] = wk * hk[p] + acc[p]


@numba.njit(cache=True, nogil=True)
def _plain_chain(h, w, lo, hi, acc):
    for k in range(lo, hi):
        wk, hk = w[k], h[k]
        for p in range(acc.size):
            acc[p] = acc[p] + wk * hk[p]


def _sum_channels(h: np.ndarray, w: np.ndarray, fused: bool, split: int) -> np.ndarray:
    """sum_k w[k] * h[k] for h `(K, N, N)` float32 in the order (fused, split) of `sum_order`: `(N, N)` float32."""
    chain = _fused_chain if fused else _plain_chain
    flat = np.ascontiguousarray(h, dtype=np.float32).reshape(len(h), -1)
    w = np.ascontiguousarray(w, dtype=np.float32)
    first, second = np.zeros(flat.shape[1], np.float32), np.zeros(flat.shape[1], np.float32)
    chain(flat, w, 0, split or len(w), first)
    if split:
        chain(flat, w, split, len(w), second)
        first += second
    return first.reshape(h.shape[1:])


@numba.njit(cache=True, nogil=True)
def _replay_kernel(q, w, k, n, fused):
    """In place: q `(l_q, size)` holds q_r on entry and the k-th step's q on exit (flat layout); each step
    v = max over channels, q = q_r + conv(v, w), w `(l_q, 1, 3, 3)`, every channel's chain as `fused` says."""
    lq = q.shape[0]
    p0, length = layout(n)[1:3]
    q_r = q.copy()
    v = np.zeros((1, q.shape[1]), dtype=np.float32)
    vc = v[0, p0 : p0 + length]
    for _ in range(k):
        vc[:] = q[0, p0 : p0 + length]
        for c in range(1, lq):
            qc = q[c, p0 : p0 + length]
            for t in range(length):
                vc[t] = np.maximum(vc[t], qc[t])
        zero_row_gaps(v[0], n)
        _conv_chains(v, w, n, fused, q)
        for c in range(lq):
            qc, rc = q[c, p0 : p0 + length], q_r[c, p0 : p0 + length]
            for t in range(length):
                qc[t] = rc[t] + qc[t]


@numba.njit(cache=True, nogil=True)
def _certain_actions(q, fc, gamma, out):
    """`_certain_action` of every cell of q `(l_q, N, N)` into out `(N, N)` int8 (-1: not certain)."""
    for i in range(q.shape[1]):
        for j in range(q.shape[2]):
            out[i, j] = _certain_action(q, fc, gamma, i, j)


@numba.njit(cache=True, nogil=True)
def _certain_action(q, fc, gamma, i, j):
    """argmax of the float64 logits fc @ q[:, i, j] where no float32 evaluation of them can change it, else -1.
    A float32 dot product of K terms, in any order, fused or not, is within gamma = K * u (times 1 + O(Ku), covered
    by the factor 2) of sum |fc[a, c] q[c]|; so the argmax is certain when the two best logits are more than twice
    the largest such bound apart."""
    n_act, lq = fc.shape[0], fc.shape[1]
    logits = np.empty(n_act)
    bound = 0.0
    for a in range(n_act):
        s, m = 0.0, 0.0
        for c in range(lq):
            s += fc[a, c] * q[c, i, j]
            m += abs(fc[a, c] * q[c, i, j])
        logits[a] = s
        bound = max(bound, m)
    top, gap = best_and_gap(logits)
    return top if gap > 4.0 * gamma * bound else -1


@numba.njit(cache=True, nogil=True)
def best_and_gap(logits):
    """The index of the largest logit (the lowest index on ties) and how far it lies above the second largest."""
    top = 0
    for a in range(1, len(logits)):
        if logits[a] > logits[top]:
            top = a
    second = -np.inf
    for a in range(len(logits)):
        if a != top and logits[a] > second:
            second = logits[a]
    return top, logits[top] - second
