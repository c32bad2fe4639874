"""How PyTorch's convolutions chain their sums on this machine, measured once per setting on random data: the 3x3
convolutions' per-channel modes (`conv_modes`) and the r layer's summation order (`sum_order`).
"""

from __future__ import annotations

import numpy as np

from vinadv.planners.vin.flat import from_flat, to_flat
from vinadv.planners.vin.replay.cache import CACHE, torch_threads_now
from vinadv.planners.vin.replay.kernels import add_bias, conv_chains, sum_channels

__all__ = ["PROBES", "conv_modes", "sum_order"]

#: random convolutions `conv_modes` compares (and random products `fc_order` compares)
PROBES = 16


def conv_modes(n: int, l_out: int, l_in: int = 1, bias: bool = False) -> np.ndarray | None:
    """Per output channel, whether PyTorch's `conv2d((1, l_in, N, N), (l_out, l_in, 3, 3), padding=1)` (with a
    bias added last when `bias`) chains its 9 * l_in taps with fused multiply-adds (True) or multiply-then-add
    (False), `(l_out,)` bool; None if neither chain reproduces some channel bit for bit. Measured once per
    (N, widths, bias, PyTorch threads) on random data, then cached.

    Several probes at scales from 1e-2 to 1e2: a BLAS may treat a few cells apart (seen: MKL on 2 threads at 9x9 and
    13x13 rounds two cells of the unfused channels otherwise), and one probe can round them alike by chance."""
    key = (n, l_out, l_in, bias, torch_threads_now())
    if key not in CACHE.conv_modes:
        CACHE.conv_modes[key] = CACHE.measured(
            "conv_modes", key, lambda: _measure_conv_modes(n, l_out, l_in, bias), lambda v: np.array(v, dtype=bool)
        )
    return CACHE.conv_modes[key]


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
            conv_chains(flat_v, w, n, np.full(l_out, fused), out)
            got = add_bias(from_flat(out, n), b)
            ok &= (got == want).reshape(l_out, -1).all(axis=1)
    # a channel that both chains reproduce would leave its mode unknown; random data makes that vanishingly rare
    return fused_ok.tolist() if np.all(fused_ok ^ plain_ok) else None


def sum_order(n: int, l_h: int) -> tuple[bool, int] | None:
    """How PyTorch's 1x1 convolution `(1, l_h, N, N) -> (1, 1, N, N)` (the r layer; a BLAS sgemm with M = 1 and
    K = l_h) sums its l_h products: `(fused, split)`, a chain over k = 0 .. split - 1 and one over split .. l_h - 1
    (split 0: a single chain), added; None if no such order reproduces it bit for bit. Seen: MKL on 1 thread, one
    unfused chain; on 2 threads, fused chains split at 128. Measured once per (N, l_h, PyTorch threads)."""
    key = (n, l_h, torch_threads_now())
    if key not in CACHE.sum_orders:
        CACHE.sum_orders[key] = CACHE.measured("sum_order", key, lambda: _measure_sum_order(n, l_h), tuple)
    return CACHE.sum_orders[key]


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
            (fused, split) for fused, split in candidates if np.array_equal(sum_channels(h, w, fused, split), want)
        ]
    return list(candidates[0]) if len(candidates) == 1 else None
