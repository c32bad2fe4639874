"""The compiled loops that round as PyTorch's CPU kernels do: the 3x3 convolutions as chains over their taps (fused
multiply-adds or not, per output channel), the 1x1 convolution as one or two chains over its channels, and the
k-step value iteration built from them. Which chain a channel takes is measured (`vinadv.planners.vin.replay.orders`).
"""

from __future__ import annotations

import numba
import numpy as np

from vinadv.planners.vin.flat import kernel_taps, layout, zero_row_gaps

__all__ = ["add_bias", "conv_chains", "conv_fused", "conv_plain", "replay_kernel", "sum_channels"]


def add_bias(x: np.ndarray, bias: np.ndarray | None) -> np.ndarray:
    """x `(C, N, N)` float32 plus bias `(C,)` per channel, one float32 add, as the BLAS adds it after the chain."""
    return x if bias is None else x + bias[:, None, None]


# The chains run over the flat layout (`vinadv.planners.vin.flat`), the taps read through views at their offsets; a real
# cell reads zeros where it leaves the grid, as im2col does. Each chain starts from 0, as the BLAS kernels do, and
# goes through the input channels in order, the nine taps of each in kernel order; `out` holds the running sum
# between channels (a float32 store is exact).


@numba.njit(inline="always")
def _conv_taps(v, w, n, out):
    """out[o] = the taps of w[o] chained, acc = w[o, c, tap] * v[c, cell + tap] + acc. v `(C, size)`,
    w `(O, C, 3, 3)`, out `(O, size)` float32. Inlined, so whether a product fuses with its add is the caller's
    `fastmath` (`conv_fused`, `conv_plain`)."""
    width, p0, length = layout(n)[:3]
    for o in range(w.shape[0]):
        acc = out[o, p0 : p0 + length]
        acc[:] = 0.0  # so that each add has one product to fuse with, the chain's own
        for c in range(w.shape[1]):
            x = v[c]
            u0, u1, u2 = x[p0 - width - 1 :], x[p0 - 1 :], x[p0 + width - 1 :]  # rows above, same, below
            w00, w01, w02, w10, w11, w12, w20, w21, w22 = kernel_taps(w[o, c])
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


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def conv_fused(v, w, n, out):
    """`_conv_taps` with every product fused with its add, acc = fma(w[o, c, tap], v[c, cell + tap], acc)."""
    _conv_taps(v, w, n, out)


@numba.njit(cache=True, nogil=True)
def conv_plain(v, w, n, out):
    """`_conv_taps` with each product rounded before it is added (compiled without `contract`: never fused)."""
    _conv_taps(v, w, n, out)


@numba.njit(cache=True, nogil=True)
def conv_chains(v, w, n, fused, out):
    """out[o] = output channel o of the convolution of v (flat, `(C, size)`) with w `(O, C, 3, 3)`, chained as
    `fused[o]` says."""
    for o in range(w.shape[0]):
        if fused[o]:
            conv_fused(v, w[o : o + 1], n, out[o : o + 1])
        else:
            conv_plain(v, w[o : o + 1], n, out[o : o + 1])


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


def sum_channels(h: np.ndarray, w: np.ndarray, fused: bool, split: int) -> np.ndarray:
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
def replay_kernel(q, w, k, n, fused):
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
        conv_chains(v, w, n, fused, q)
        for c in range(lq):
            qc, rc = q[c, p0 : p0 + length], q_r[c, p0 : p0 + length]
            for t in range(length):
                qc[t] = rc[t] + qc[t]
