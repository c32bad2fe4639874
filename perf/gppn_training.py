"""GPPN training step speed, side by side in one process on the same maps and weights.

    nice .venv/bin/python perf/gppn_training.py [--n 64] [--batch-size 32] [--l-h 32 64] [--k 20 36]
                                                     [--threads 1 2] [--json]

One training step = forward over every cell of a batch of maps, the optimal-set loss, backward and an RMSprop step,
as `vinadv gppn train` does it (`vinadv.planners.imitation.batch_loss`). Two ways of computing the same function:
1. plain: the straightforward code of the published model (`nn.LSTMCell` on `(B*N*N, l_h)` rows, the hidden state
   transposed back to `(B, l_h, N, N)` for the `l_h -> 1` convolution at every step);
2. vinadv's `GPPN`: the state stays in rows; the convolution is one matrix product and f*f shifted sums.
Prints ms per map per step for each configuration (l_h, k, threads) and the ratio. With `--compile`, also vinadv's
`GPPN` through `torch.compile` (`vinadv gppn train --compile`; the compilation runs in the warm-up step, untimed) and
its speedup over the eager `GPPN`.
"""

from __future__ import annotations

import argparse
import json
import time

import torch
from torch import nn

from vinadv.grid import generate_maps
from vinadv.planners.batching import set_torch_threads
from vinadv.planners.gppn import GPPN, GPPNConfig, input_maps
from vinadv.planners.imitation import batch_loss, optimal_action_bits


class PlainGPPN(nn.Module):
    """The published forward written the straightforward way, sharing the parameters of a `GPPN`."""

    def __init__(self, model: GPPN):
        super().__init__()
        self.m = model

    def forward(self, obstacles, goals):
        m, n, l_h = self.m, obstacles.shape[-1], self.m.config.l_h
        hid = m.hid(input_maps(obstacles, goals))
        h = m.h0(hid).transpose(1, 3).contiguous().view(-1, l_h)
        c = m.c0(hid).transpose(1, 3).contiguous().view(-1, l_h)
        for _ in range(m.config.k - 1):
            h_map = h.view(-1, n, n, l_h).transpose(3, 1)
            inp = m.conv(h_map).transpose(1, 3).contiguous().view(-1, 1)
            h, c = m.lstm(inp, (h, c))
        return m.policy(h.view(-1, n, n, l_h).transpose(3, 1))


def step_ms_per_map(model: nn.Module, maps, bits, batch_size: int) -> float:
    """Mean ms per map of a training step over all batches of `maps` after one warm-up step."""
    optimizer = torch.optim.RMSprop(model.parameters(), lr=1e-6, eps=1e-6)  # tiny: weights barely move
    device = torch.device("cpu")

    def step(lo: int) -> None:
        sl = slice(lo, lo + batch_size)
        loss, _, _ = batch_loss(model, maps.obstacles[sl], maps.goals[sl], bits[sl], device)
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        optimizer.step()

    step(0)
    start = time.perf_counter()
    for lo in range(0, len(maps), batch_size):
        step(lo)
    return 1000 * (time.perf_counter() - start) / len(maps)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=64, help="maps per measurement (default 64)")
    ap.add_argument("--size", type=int, default=28)
    ap.add_argument("--batch-size", type=int, default=32)
    ap.add_argument("--l-h", type=int, nargs="+", default=[32, 64])
    ap.add_argument("--k", type=int, nargs="+", default=[20, 36])
    ap.add_argument("--f", type=int, default=3, help="kernel of the recurrent convolution (default 3)")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--skip-plain", action="store_true", help="time vinadv's GPPN only")
    ap.add_argument("--compile", action="store_true", help="also time vinadv's GPPN through torch.compile")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    maps = generate_maps(args.n, args.size, seed=5, n_starts=1)
    bits = optimal_action_bits(maps)
    rows = []
    for threads in args.threads:
        set_torch_threads(threads)  # torch's and Numba's: a Numba kernel would reset torch's otherwise
        for l_h in args.l_h:
            for k in args.k:
                torch.manual_seed(0)
                model = GPPN(GPPNConfig(k=k, l_h=l_h, f=args.f))
                row = {
                    "threads": threads,
                    "l_h": l_h,
                    "k": k,
                    "f": args.f,
                    "batch_size": args.batch_size,
                    "size": args.size,
                    "vinadv_ms_per_map": round(step_ms_per_map(model, maps, bits, args.batch_size), 2),
                }
                if not args.skip_plain:
                    with torch.no_grad():  # the same function: else the comparison means nothing
                        obs = torch.from_numpy(maps.obstacles[:4].astype("float32"))
                        goals = torch.from_numpy(maps.goals[:4])
                        torch.testing.assert_close(
                            PlainGPPN(model)(obs, goals), model(obs, goals), rtol=1e-4, atol=1e-4
                        )
                    row["plain_ms_per_map"] = round(step_ms_per_map(PlainGPPN(model), maps, bits, args.batch_size), 2)
                    row["speedup"] = round(row["plain_ms_per_map"] / row["vinadv_ms_per_map"], 2)
                if args.compile:
                    compiled = torch.compile(model)
                    row["compiled_ms_per_map"] = round(step_ms_per_map(compiled, maps, bits, args.batch_size), 2)
                    row["compile_speedup"] = round(row["vinadv_ms_per_map"] / row["compiled_ms_per_map"], 2)
                rows.append(row)
                if not args.json:
                    print(" ".join(f"{key} {value}" for key, value in row.items()), flush=True)
    if args.json:
        print(json.dumps(rows))


if __name__ == "__main__":
    main()
