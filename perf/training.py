"""VIN training step speed, side by side in one process on the same maps and weights.

    nice .venv/bin/python perf/training.py [--n 256] [--size 28] [--batch-size 16] [--threads 1] [--json]

One training step = forward over every cell of a batch of maps, the optimal-set loss, backward and an RMSprop
step, as `vinadv vin train` does it. Two ways of computing the same function and gradients:
1. plain PyTorch: `VIN.action_logits` (the h and r convolutions, then k steps of conv + max as separate ops);
2. vinadv's CPU path (`vinadv.planners.vin.value_iteration`): h and r folded into one convolution and the k-step loop
   as one compiled autograd function whose backward follows only the argmax channel.
Prints ms per map per step for each and the ratio. Weights: the shipped ones for the size if present.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import torch

from vinadv.grid import generate_maps
from vinadv.planners.imitation import bits_to_mask, optimal_action_bits, optimal_set_loss
from vinadv.planners.vin import VIN, VINConfig, default_k, make_input, value_iteration
from vinadv.planners.vin.weights import default_weights_path, load_vin


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=256, help="maps per measurement (default 256)")
    ap.add_argument("--size", type=int, default=28)
    ap.add_argument("--batch-size", type=int, default=16)
    ap.add_argument("--threads", type=int, default=1, help="torch threads (default 1, as `vin train --threads 1`)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    maps = generate_maps(args.n, args.size, seed=5, n_starts=1)
    bits = optimal_action_bits(maps)
    model = _model(args.size)

    def q_torch(x):
        return model.q_values(x)

    def q_fast(x):
        return value_iteration.q_values(model, x)

    def epoch(q_values) -> float:
        optimizer = torch.optim.RMSprop(model.parameters(), lr=1e-6, eps=1e-6)  # tiny: weights barely move
        start = time.perf_counter()
        for i in range(0, args.n, args.batch_size):
            b = slice(i, i + args.batch_size)
            logits = model.fc(q_values(make_input(maps.obstacles[b], maps.goals[b])).permute(0, 2, 3, 1))
            mask = bits_to_mask(torch.from_numpy(bits[b]), logits.shape[-1])
            supervised = mask.any(dim=-1)
            loss = optimal_set_loss(logits[supervised], mask[supervised])
            optimizer.zero_grad(set_to_none=True)
            loss.backward()
            optimizer.step()
        return (time.perf_counter() - start) / args.n * 1e3

    epoch(q_fast)  # compile / load the Numba cache
    t_torch = min(epoch(q_torch) for _ in range(2))
    t_fast = min(epoch(q_fast) for _ in range(2))
    out = {
        "size": args.size,
        "k": model.config.k,
        "maps": args.n,
        "batch_size": args.batch_size,
        "threads": args.threads,
        "load_average": os.getloadavg()[0],
        "torch_ms_per_map": round(t_torch, 3),
        "fast_ms_per_map": round(t_fast, 3),
        "speedup": round(t_torch / t_fast, 2),
    }
    if args.json:
        print(json.dumps(out))
        return
    print(
        f"{args.size}x{args.size}, k={model.config.k}, batch {args.batch_size}, {args.threads} torch thread(s), "
        f"load average {out['load_average']:.1f}"
    )
    print(f"  plain PyTorch step      {t_torch:7.3f} ms per map")
    print(f"  vinadv CPU step         {t_fast:7.3f} ms per map")
    print(f"  speedup                 {out['speedup']:.2f}x")


def _model(size: int) -> VIN:
    path = default_weights_path(size)
    if path.exists():
        return load_vin(path, size=size)
    torch.manual_seed(0)
    return VIN(VINConfig(k=default_k(size)))


if __name__ == "__main__":
    main()
