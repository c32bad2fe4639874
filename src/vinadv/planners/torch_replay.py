"""PyTorch's own value map for one map, bit for bit, in a fraction of PyTorch's time: how the engine settles near ties.

Where two logits of a cell are within rounding of each other, the engine must take the reference's decision, which is
made by PyTorch's float32 arithmetic: a batch-1 `VIN.q_values`, then `fc` at the cell. That call costs ~3 ms at
28x28, nearly all of it the overhead of the 3k small ops of the loop, each cheap and simple:

- the 1 -> l_q 3x3 convolutions (the first q layer on r, then w on v at every step) go through ATen's
  `slow_conv2d`: im2col (exact copies, zero padding), then a BLAS sgemm with K = 9, which builds each output as a
  chain over the nine taps in kernel order, starting from 0; per output channel the chain is either fused
  multiply-adds or multiply-then-add, depending on the BLAS kernel (with MKL on 2 threads: blocks of 8 channels
  fused, the rest not; on 1 thread: all fused);
- r, the 1x1 convolution l_h -> 1, is an sgemm with M = 1: one or two chains over the l_h channels (MKL on 2
  threads: fused, split at 128; on 1 thread: one unfused chain);
- `q_r + conv` is one float32 add and the max over channels is exact.

`replay_q_values` runs h through PyTorch (oneDNN; the same batch-1 call as `q_values`), then replays r, the first q
layer and the k steps in compiled loops that round exactly as above. Which chains is measured, never assumed:
`conv_modes` and `sum_order` run PyTorch's convolutions on random data once for each (map size, widths, PyTorch
threads) and keep the chains that reproduce them bit for bit; the first `VERIFY_MAPS` maps of each setting are also
compared whole with `VIN.q_values`. If a check fails, that setting uses `VIN.q_values` itself (slow, but exact).

`exact_policy` then decides each cell from that value map: in float64 where the two best logits are further apart
than any float32 evaluation of `fc` could move them (a rigorous bound), else with PyTorch's `fc` at the cell.
"""

from __future__ import annotations

from collections.abc import Callable

import numba
import numpy as np
import torch
import torch.nn.functional as F

from vinadv.planners.flat import from_flat, layout, to_flat, zero_row_gaps
from vinadv.planners.reference import torch_action_at
from vinadv.planners.vin import VIN, make_input

__all__ = ["conv_modes", "exact_policy", "replay_q_values", "sum_order"]

#: maps per setting whose replayed value map is compared with `VIN.q_values` before the replay is trusted alone
VERIFY_MAPS = 2
#: random convolutions `conv_modes` compares
PROBES = 16
_FLOAT32_UNIT_ROUNDOFF = 2.0**-24

# (N, l_q, torch threads) -> per-channel fused flags; (N, l_h, torch threads) -> (fused, split); None where no
# replay reproduces PyTorch
_modes: dict[tuple[int, int, int], np.ndarray | None] = {}
_orders: dict[tuple[int, int, int], tuple[bool, int] | None] = {}
# (N, l_h, l_q, torch threads): maps checked whole against VIN.q_values; settings where one differed
_verified: dict[tuple[int, int, int, int], int] = {}
_failed: set[tuple[int, int, int, int]] = set()


def conv_modes(n: int, l_q: int) -> np.ndarray | None:
    """Per output channel, whether PyTorch's `conv2d((1, 1, N, N), (l_q, 1, 3, 3), padding=1)` chains its nine taps
    with fused multiply-adds (True) or multiply-then-add (False), `(l_q,)` bool; None if neither chain reproduces
    some channel bit for bit. Measured once per (N, l_q, PyTorch threads) on random data, then cached.

    Several probes at scales from 1e-2 to 1e2: a BLAS may treat a few cells apart (seen: MKL on 2 threads at 9x9 and
    13x13 rounds two cells of the unfused channels otherwise), and one probe can round them alike by chance."""
    key = (n, l_q, torch.get_num_threads())
    if key not in _modes:
        rng = np.random.default_rng(0)
        fused_ok, plain_ok = np.ones(l_q, bool), np.ones(l_q, bool)
        for scale in np.logspace(-2, 2, PROBES):
            v = (scale * rng.standard_normal((n, n))).astype(np.float32)
            w = rng.standard_normal((l_q, 3, 3)).astype(np.float32)
            with torch.no_grad():
                want = F.conv2d(torch.from_numpy(v)[None, None], torch.from_numpy(w)[:, None], padding=1)[0].numpy()
            flat_v = to_flat(v[None])[0]
            fused, plain = np.empty((l_q, flat_v.size), np.float32), np.empty((l_q, flat_v.size), np.float32)
            _conv_fused(flat_v, w, n, fused)
            _conv_plain(flat_v, w, n, plain)
            fused_ok &= (from_flat(fused, n) == want).reshape(l_q, -1).all(axis=1)
            plain_ok &= (from_flat(plain, n) == want).reshape(l_q, -1).all(axis=1)
        # a channel that both chains reproduce would leave its mode unknown; random data makes that vanishingly rare
        _modes[key] = fused_ok if np.all(fused_ok ^ plain_ok) else None
    return _modes[key]


def sum_order(n: int, l_h: int) -> tuple[bool, int] | None:
    """How PyTorch's 1x1 convolution `(1, l_h, N, N) -> (1, 1, N, N)` (the r layer; a BLAS sgemm with M = 1 and
    K = l_h) sums its l_h products: `(fused, split)`, a chain over k = 0 .. split - 1 and one over split .. l_h - 1
    (split 0: a single chain), added; None if no such order reproduces it bit for bit. Seen: MKL on 1 thread, one
    unfused chain; on 2 threads, fused chains split at 128. Measured once per (N, l_h, PyTorch threads)."""
    key = (n, l_h, torch.get_num_threads())
    if key not in _orders:
        candidates = [(fused, split) for fused in (True, False) for split in (0, 64, 128, 256, 512) if split < l_h]
        rng = np.random.default_rng(1)
        for scale in np.logspace(-2, 2, PROBES // 4):
            h = (scale * rng.standard_normal((l_h, n, n))).astype(np.float32)
            w = rng.standard_normal(l_h).astype(np.float32)
            with torch.no_grad():
                want = F.conv2d(torch.from_numpy(h)[None], torch.from_numpy(w)[None, :, None, None])[0, 0].numpy()
            candidates = [(fused, split) for fused, split in candidates
                          if np.array_equal(_sum_channels(h, w, fused, split), want)]
        _orders[key] = candidates[0] if len(candidates) == 1 else None
    return _orders[key]


def replay_q_values(model: VIN, x: torch.Tensor) -> np.ndarray:
    """`model.q_values(x)[0]` for one map `x (1, 2, N, N)`, bit for bit: `(l_q, N, N)` float32.

    PyTorch runs h (oneDNN); r, the first q layer and the k steps are replayed (`sum_order`, `conv_modes`)."""
    n, l_h, l_q = x.shape[-1], model.config.l_h, model.config.l_q
    modes, order = conv_modes(n, l_q), sum_order(n, l_h)
    setting = (n, l_h, l_q, torch.get_num_threads())
    if modes is None or order is None or setting in _failed:
        return _torch_q_values(model, x)
    with torch.no_grad():
        h = model.h(x)[0].numpy()
    r = _sum_channels(h, model.r.weight.detach()[0, :, 0, 0].numpy(), *order)
    flat_r = to_flat(r[None])[0]
    q = np.zeros((l_q, flat_r.size), dtype=np.float32)
    _conv_chains(flat_r, np.ascontiguousarray(model.q.weight.detach()[:, 0].numpy()), n, modes, q)
    _replay_kernel(q, np.ascontiguousarray(model.w.detach()[:, 0].numpy()), int(model.config.k), n, modes)
    q = from_flat(q, n)
    if _verified.get(setting, 0) < VERIFY_MAPS:
        want = _torch_q_values(model, x)
        if not np.array_equal(q.view(np.int32), want.view(np.int32)):
            _failed.add(setting)
            return want
        _verified[setting] = _verified.get(setting, 0) + 1
    return q


def exact_policy(model: VIN, obstacles: np.ndarray, goal: np.ndarray) -> Callable[[int, int], int]:
    """The reference's policy on one map (`torch_action_at`: argmax of PyTorch's logits, lowest index on ties),
    without re-running PyTorch: obstacles `(N, N)` bool, goal `(2,)`; returns `action_at(row, col)`."""
    x = make_input(obstacles[None], np.asarray(goal)[None])
    q = replay_q_values(model, x)
    fc = model.fc.weight.detach().to(torch.float64).numpy()
    gamma = fc.shape[1] * _FLOAT32_UNIT_ROUNDOFF
    torch_at = torch_action_at(model, x, torch.from_numpy(q[None]))

    def action_at(row: int, col: int) -> int:
        a = _certain_action(q, fc, gamma, row, col)  # per cell: a rollout visits ~15 of them
        return a if a >= 0 else torch_at(row, col)

    return action_at


def _torch_q_values(model: VIN, x: torch.Tensor) -> np.ndarray:
    with torch.no_grad():
        return model.q_values(x)[0].numpy()


# Both chains run over the flat layout (`vinadv.planners.flat`), the nine taps read through views at their offsets; a real cell reads zeros where it
# leaves the grid, as im2col does. Each chain starts from 0, as the BLAS kernels do.


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def _conv_fused(v, w, n, out):
    """out[c] = the nine taps of w[c] chained in kernel order, acc = fma(w[c, tap], v[cell + tap], acc)."""
    width, p0, length = layout(n)[:3]
    u0, u1, u2 = v[p0 - width - 1 :], v[p0 - 1 :], v[p0 + width - 1 :]  # rows above, same, below
    zero = np.float32(0.0)
    for c in range(w.shape[0]):
        w00, w01, w02, w10, w11, w12, w20, w21, w22 = w[c].ravel()
        o = out[c, p0 : p0 + length]
        for t in range(length):
            acc = w00 * u0[t] + zero  # from 0, so that each add has one product to fuse with, the chain's own
            acc = w01 * u0[t + 1] + acc
            acc = w02 * u0[t + 2] + acc
            acc = w10 * u1[t] + acc
            acc = w11 * u1[t + 1] + acc
            acc = w12 * u1[t + 2] + acc
            acc = w20 * u2[t] + acc
            acc = w21 * u2[t + 1] + acc
            o[t] = w22 * u2[t + 2] + acc


@numba.njit(cache=True, nogil=True)
def _conv_plain(v, w, n, out):
    """As `_conv_fused`, each product rounded before it is added (compiled without `contract`: never fused)."""
    width, p0, length = layout(n)[:3]
    u0, u1, u2 = v[p0 - width - 1 :], v[p0 - 1 :], v[p0 + width - 1 :]
    zero = np.float32(0.0)
    for c in range(w.shape[0]):
        w00, w01, w02, w10, w11, w12, w20, w21, w22 = w[c].ravel()
        o = out[c, p0 : p0 + length]
        for t in range(length):
            acc = w00 * u0[t] + zero
            acc = w01 * u0[t + 1] + acc
            acc = w02 * u0[t + 2] + acc
            acc = w10 * u1[t] + acc
            acc = w11 * u1[t + 1] + acc
            acc = w12 * u1[t + 2] + acc
            acc = w20 * u2[t] + acc
            acc = w21 * u2[t + 1] + acc
            o[t] = w22 * u2[t + 2] + acc


@numba.njit(cache=True, nogil=True)
def _conv_chains(v, w, n, fused, out):
    """out[c] = channel c of the convolution of v (flat) with w[c], chained as `fused[c]` says."""
    for c in range(w.shape[0]):
        if fused[c]:
            _conv_fused(v, w[c : c + 1], n, out[c : c + 1])
        else:
            _conv_plain(v, w[c : c + 1], n, out[c : c + 1])


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
    v = max over channels, q = q_r + conv(v), every channel's chain as `fused` says."""
    lq = q.shape[0]
    p0, length = layout(n)[1:3]
    q_r = q.copy()
    v = np.zeros(q.shape[1], dtype=np.float32)
    vc = v[p0 : p0 + length]
    for _ in range(k):
        vc[:] = q[0, p0 : p0 + length]
        for c in range(1, lq):
            qc = q[c, p0 : p0 + length]
            for t in range(length):
                vc[t] = np.maximum(vc[t], qc[t])
        zero_row_gaps(v, n)
        _conv_chains(v, w, n, fused, q)
        for c in range(lq):
            qc, rc = q[c, p0 : p0 + length], q_r[c, p0 : p0 + length]
            for t in range(length):
                qc[t] = rc[t] + qc[t]


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
