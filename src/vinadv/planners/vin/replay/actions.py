"""The reference's decisions, replayed: PyTorch's value map of one map (`replay_q_values`) and the action of every
cell (`exact_actions`), each checked against PyTorch itself for the first maps and cells of a setting.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numba
import numpy as np

from vinadv.planners.vin.arrays import VINWeights, as_vin_weights, input_array
from vinadv.planners.vin.flat import from_flat, to_flat
from vinadv.planners.vin.replay.cache import CACHE, torch_threads_now
from vinadv.planners.vin.replay.fc import fc_order, replay_fc
from vinadv.planners.vin.replay.kernels import add_bias, conv_chains, replay_kernel, sum_channels
from vinadv.planners.vin.replay.orders import conv_modes, sum_order

if TYPE_CHECKING:
    from vinadv.planners.vin.model import VIN

__all__ = ["VERIFY_CELLS", "VERIFY_MAPS", "best_and_gap", "exact_actions", "replay_q_values"]

#: maps per setting whose replayed value map is compared with `VIN.q_values` before the replay is trusted alone
VERIFY_MAPS = 2
#: near-tie cells per setting whose replayed `fc` logits are compared with PyTorch's before the replay is trusted
VERIFY_CELLS = 2
_FLOAT32_UNIT_ROUNDOFF = 2.0**-24


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
    if order is None or setting in CACHE.fc_failed:
        return int(np.argmax(_torch_fc(p.vin, q)))
    logits = replay_fc(p.fc32, q, *order)
    if not CACHE.trusted("fc_verified", setting, CACHE.fc_verified, VERIFY_CELLS):
        want = _torch_fc(p.vin, q)
        if not np.array_equal(logits.view(np.int32), want.view(np.int32)):
            CACHE.fc_failed.add(setting)
            return int(np.argmax(want))
        CACHE.passed("fc_verified", setting, CACHE.fc_verified, VERIFY_CELLS)
    return int(np.argmax(logits))


def _torch_fc(weights: VINWeights, q: np.ndarray) -> np.ndarray:
    """PyTorch's `fc` on one value vector `(l_q,)`, as `VIN.forward` applies it: `(A,)` float32."""
    import torch  # noqa: PLC0415 (PyTorch: the replay is there to plan without it)

    with torch.no_grad():
        return weights.module().fc(torch.from_numpy(np.ascontiguousarray(q, dtype=np.float32))[None])[0].numpy()


def _q_values(p: _Weights, x: np.ndarray) -> np.ndarray:
    """q of one map `x (l_i, N, N)` float32: replayed where the setting's chains are known and verified, else
    `VIN.q_values` itself. `(l_q, N, N)` float32. Where only the r layer's order is unknown (MKL on 2 threads sums
    32x32 and 64x64 maps' 1x1 convolution in an order `sum_order` does not find), PyTorch computes r alone from
    the replayed h, one small op instead of the k steps' thousands, and the rest is replayed."""
    l_i, n = x.shape[0], x.shape[-1]
    l_h, l_q = p.h.shape[0], p.q.shape[0]
    h_modes, q_modes, order = conv_modes(n, l_h, l_i, bias=True), conv_modes(n, l_q), sum_order(n, l_h)
    setting = (n, l_h, l_q, torch_threads_now())
    if h_modes is None or q_modes is None or setting in CACHE.q_failed:
        return _torch_q_values(p.vin, x)
    flat_x = to_flat(x)
    h = np.empty((l_h, flat_x.shape[1]), dtype=np.float32)
    conv_chains(flat_x, p.h, n, h_modes, h)
    h = add_bias(from_flat(h, n), p.h_bias)
    r = _torch_r(p.vin, h) if order is None else sum_channels(h, p.r, *order)
    q = np.empty((l_q, flat_x.shape[1]), dtype=np.float32)
    conv_chains(to_flat(r[None]), p.q, n, q_modes, q)
    replay_kernel(q, p.w, p.k, n, q_modes)
    q = from_flat(q, n)
    if not CACHE.trusted("q_verified", setting, CACHE.q_verified, VERIFY_MAPS):
        want = _torch_q_values(p.vin, x)
        if not np.array_equal(q.view(np.int32), want.view(np.int32)):
            CACHE.q_failed.add(setting)
            return want
        CACHE.passed("q_verified", setting, CACHE.q_verified, VERIFY_MAPS)
    return q


def _torch_r(weights: VINWeights, h: np.ndarray) -> np.ndarray:
    """PyTorch's r layer on one map's h `(l_h, N, N)`, as `VIN.q_values` applies it: `(N, N)` float32."""
    import torch  # noqa: PLC0415 (as above)

    with torch.no_grad():
        # a copy in PyTorch's own (aligned) memory: MKL may sum otherwise for other alignments
        return weights.module().r(torch.from_numpy(h).clone()[None])[0, 0].numpy()


def _torch_q_values(weights: VINWeights, x: np.ndarray) -> np.ndarray:
    import torch  # noqa: PLC0415 (as above)

    with torch.no_grad():
        return weights.module().q_values(torch.from_numpy(np.ascontiguousarray(x))[None])[0].numpy()


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
