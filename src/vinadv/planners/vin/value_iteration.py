"""The VIN's value-iteration loop as one compiled autograd function, for training on CPU.

PyTorch runs the k steps `q = q_r + conv(v, w); v = max_c q` as 3k small ops forward and more backward, each
with its dispatch and memory traffic; on a 2-core CPU that loop is most of a training step. Here the forward is
one Numba kernel that also records, per step, the padded value map and the argmax channel of every cell. The
backward then needs no dense work except at the last step: the gradient of `max_c` reaches only the argmax
channel, so each earlier step costs 18 multiply-adds per cell (9 for `dL/dw`, 9 for `dL/dv`) instead of 90.

`value_iteration(q_r, w, k)` returns the same q as `VIN.q_values` computes after `q_r = q(r(h(x)))` (equal up to
float rounding: the sums run in another order) and the same gradients (ties in the max send the gradient to the
lowest channel, as any subgradient would do).
"""

from __future__ import annotations

import numba
import numpy as np
import torch
import torch.nn.functional as F

from vinadv.planners.batching import over_maps
from vinadv.planners.vin.flat import kernel_taps


def _over_maps(kernel, b: int, *arrays) -> None:
    """Run `kernel(lo, hi, *arrays)` over map ranges split between as many threads as torch may use
    (`vin train --threads`)."""
    over_maps(b, lambda lo, hi: kernel(lo, hi, *arrays), threads=torch.get_num_threads())


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def _forward(lo, hi, q_r, w, k, q_out, v_saved, arg_saved):
    """Maps lo..hi-1. q_r (B, L, N, N), w (L, 3, 3) -> q_out (B, L, N, N) = q after k steps;
    v_saved (B, k, N+2, N+2) = zero-padded v_0..v_{k-1}; arg_saved (B, k, N, N) uint8 = argmax channel of q_t.

    The loop runs as the planning engine's (`vinadv.planners.vin.engine._value_iteration`): each padded value map
    seen as one flat array, one long vector loop per channel over the whole map, the nine neighbours read through
    views at their offsets. The argmax is kept as a float channel number, updated by arithmetic (a conditional
    store would stop the loop vectorising); ties keep the lowest channel.
    """
    lq, n = q_r.shape[1], q_r.shape[2]
    width = n + 2
    size, p0, length = width * width, width + 1, (n - 1) * width + n
    rq = np.zeros((lq, size), dtype=q_r.dtype)
    best = np.empty(length, dtype=q_r.dtype)
    arg = np.empty(length, dtype=q_r.dtype)
    for b in range(lo, hi):
        for c in range(lq):
            for i in range(n):
                for j in range(n):
                    rq[c, (i + 1) * width + j + 1] = q_r[b, c, i, j]
        vs = v_saved[b].reshape((k, size))
        vs[:, :] = 0.0
        best[:] = rq[0, p0 : p0 + length]
        arg[:] = 0.0
        for c in range(1, lq):  # v_0 = max_c q_r
            _max_update(rq[c, p0 : p0 + length], c, best, arg)
        _store_step(best, arg, vs[0], arg_saved[b, 0], n)
        for t in range(1, k + 1):
            vp = vs[t - 1]
            u0, u1, u2 = vp[p0 - width - 1 :], vp[p0 - 1 :], vp[p0 + width - 1 :]
            best[:] = -np.inf
            arg[:] = 0.0
            for c in range(lq):
                r = rq[c, p0 : p0 + length]
                w00, w01, w02, w10, w11, w12, w20, w21, w22 = kernel_taps(w[c])
                if t == k:
                    out = q_out[b, c]
                    for i in range(n):
                        for j in range(n):
                            x = i * width + j
                            out[i, j] = (
                                (r[x] + w00 * u0[x] + w01 * u0[x + 1] + w02 * u0[x + 2])
                                + (w10 * u1[x] + w11 * u1[x + 1] + w12 * u1[x + 2])
                                + (w20 * u2[x] + w21 * u2[x + 1] + w22 * u2[x + 2])
                            )
                else:
                    cf = q_r.dtype.type(c)
                    for x in range(length):
                        a = (
                            (r[x] + w00 * u0[x] + w01 * u0[x + 1] + w02 * u0[x + 2])
                            + (w10 * u1[x] + w11 * u1[x + 1] + w12 * u1[x + 2])
                            + (w20 * u2[x] + w21 * u2[x + 1] + w22 * u2[x + 2])
                        )
                        greater = a > best[x]
                        arg[x] += (cf - arg[x]) * greater
                        best[x] = np.maximum(best[x], a)
            if t < k:
                _store_step(best, arg, vs[t], arg_saved[b, t], n)


@numba.njit(cache=True, nogil=True)
def _max_update(values, c, best, arg):
    """best = max(best, values), arg = c where values is strictly greater (flat, same length)."""
    cf = best.dtype.type(c)
    for x in range(len(values)):
        greater = values[x] > best[x]
        arg[x] += (cf - arg[x]) * greater
        best[x] = np.maximum(best[x], values[x])


@numba.njit(cache=True, nogil=True)
def _store_step(best, arg, v_flat, arg_out, n):
    """The step's value map into the padded flat `v_flat` (padding stays 0) and its argmax into `arg_out (N, N)`."""
    width = n + 2
    for i in range(n):
        for j in range(n):
            x = i * width + j
            v_flat[(i + 1) * width + j + 1] = best[x]
            arg_out[i, j] = np.uint8(arg[x])


@numba.njit(cache=True, nogil=True)
def _backward(lo, hi, grad_q, w, k, v_saved, arg_saved, grad_qr, grad_w):
    """Maps lo..hi-1: grad_q (B, L, N, N) = dL/dq_k -> grad_qr (B, L, N, N) = dL/dq_r, grad_w (B, L, 3, 3) per map."""
    lq, n = grad_q.shape[1], grad_q.shape[2]
    gv = np.zeros((n + 2, n + 2), dtype=grad_q.dtype)
    gv_next = np.zeros((n + 2, n + 2), dtype=grad_q.dtype)
    for b in range(lo, hi):
        g_q, gqr, gw = grad_q[b], grad_qr[b], grad_w[b]
        gqr[:, :, :] = g_q
        gw[:, :, :] = 0.0
        gv[:, :] = 0.0
        vp = v_saved[b, k - 1]
        for c in range(lq):  # q_k = q_r + conv(v_{k-1}, w): dense in every channel
            for di in range(3):
                for dj in range(3):
                    wc, s = w[c, di, dj], 0.0
                    for i in range(n):
                        for j in range(n):
                            g = g_q[c, i, j]
                            s += g * vp[i + di, j + dj]
                            gv[i + di, j + dj] += g * wc
                    gw[c, di, dj] += s
        for t in range(k - 1, -1, -1):  # v_t = max_c q_t: only the argmax channel gets the gradient
            gv_next[:, :] = 0.0
            for i in range(n):
                for j in range(n):
                    g = gv[i + 1, j + 1]
                    if g == 0.0:
                        continue
                    c = arg_saved[b, t, i, j]
                    gqr[c, i, j] += g
                    if t > 0:
                        vp = v_saved[b, t - 1]
                        for di in range(3):
                            for dj in range(3):
                                gw[c, di, dj] += g * vp[i + di, j + dj]
                                gv_next[i + di, j + dj] += g * w[c, di, dj]
            gv, gv_next = gv_next, gv


class _ValueIteration(torch.autograd.Function):
    @staticmethod
    def forward(ctx, q_r: torch.Tensor, w: torch.Tensor, k: int) -> torch.Tensor:
        qr = q_r.detach().contiguous().numpy()
        wk = np.ascontiguousarray(w.detach().numpy()[:, 0])
        b, _, n, _ = qr.shape
        q = np.empty_like(qr)
        v_saved = np.empty((b, k, n + 2, n + 2), dtype=qr.dtype)
        arg_saved = np.empty((b, k, n, n), dtype=np.uint8)
        _over_maps(_forward, b, qr, wk, k, q, v_saved, arg_saved)
        ctx.k, ctx.wk, ctx.saved = k, wk, (v_saved, arg_saved)
        return torch.from_numpy(q)

    @staticmethod
    def backward(ctx, grad_q: torch.Tensor):
        v_saved, arg_saved = ctx.saved
        g = grad_q.detach().contiguous().numpy()
        grad_qr = np.empty_like(g)
        grad_w = np.empty((len(g),) + ctx.wk.shape, dtype=g.dtype)
        _over_maps(_backward, len(g), g, ctx.wk, ctx.k, v_saved, arg_saved, grad_qr, grad_w)
        return torch.from_numpy(grad_qr), torch.from_numpy(grad_w.sum(axis=0)[:, None]), None


def value_iteration(q_r: torch.Tensor, w: torch.Tensor, k: int) -> torch.Tensor:
    """q after k value-iteration steps: `q_r (B, L, N, N)` the reward term, `w (L, 1, 3, 3)` -> `(B, L, N, N)`.

    CPU tensors, float32 or float64; differentiable in `q_r` and `w`.
    """
    if q_r.device.type != "cpu" or w.device.type != "cpu":
        raise ValueError("value_iteration runs on CPU tensors; use VIN.q_values on other devices")
    return _ValueIteration.apply(q_r, w.to(q_r.dtype), int(k))


def q_values(model, x: torch.Tensor) -> torch.Tensor:
    """`model.q_values(x)` computed faster, same function and gradients: `x (B, 2, N, N) -> (B, l_q, N, N)`, CPU.

    `r(h(x))` has no nonlinearity inside, so it is one 2 -> 1 convolution with the folded kernel
    `sum_c r_c h_c` and bias `sum_c r_c b_c`; autograd carries the gradient back through the fold to `h` and `r`
    (the chain rule gives exactly the unfolded gradients), at 1/150 of the 2 -> 150 convolution's cost.
    """
    r_w = model.r.weight[0, :, 0, 0]
    kernel = torch.einsum("h,hcij->cij", r_w, model.h.weight).unsqueeze(0)
    q_r = model.q(F.conv2d(x, kernel, (r_w @ model.h.bias).reshape(1), padding=1))
    return value_iteration(q_r, model.w, model.config.k)
