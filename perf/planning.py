"""Planning throughput, side by side in one process on the same maps and weights.

    nice .venv/bin/python perf/planning.py [--n 5000] [--size 28] [--ref-n 20] [--torch-n 400] [--json]

1. per-step reference (`plan_reference`): re-runs the full PyTorch VIN, batch size 1, at every step, as the public
   ports do (on the first --ref-n maps);
2. a plain batched PyTorch forward: `VIN.action_logits` on batches of 100 maps + argmax, no rollouts at all (maps/s,
   counted as plans/s: generous to PyTorch);
3. the engine (`plan_batch`), one start per map, so every plan computes its own value map.

Prints plans/s, the ratios, and the engine's share of the FMA peak: k * N * N * l_q * 9 multiply-adds per map
against cores x 2 FMA units x 8 float32 lanes x clock (Zen 4 runs AVX-512 as two 256-bit halves, so AVX-512
does not raise the FMA peak over AVX2 there; on a CPU with two full 512-bit FMA units the peak would be twice that).
Weights: the shipped weights for the size if present (or --weights), else `planning_vin`.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import time

import numpy as np
import torch

from vinadv.grid import generate_maps
from vinadv.planners.batching import N_THREADS
from vinadv.planners.vin import make_input
from vinadv.planners.vin.engine import action_maps, plan_batch
from vinadv.planners.vin.reference import plan_reference
from vinadv.planners.vin.weights import load_vin
from vinadv.testing.planners import planning_vin


def cpu_clock_hz() -> float:
    with open("/proc/cpuinfo") as fh:
        mhz = [float(x) for x in re.findall(r"cpu MHz\s*:\s*([\d.]+)", fh.read())]
    return max(mhz) * 1e6 if mhz else float("nan")


def load_model(size: int, weights: str | None):
    try:
        return load_vin(weights, size=size), weights or "shipped"
    except Exception:
        if weights is not None:
            raise
        return planning_vin(size, seed=0), "planning_vin(seed=0) (no shipped weights)"


def timed(fn, repeat: int = 1) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=5000, help="maps for the engine")
    ap.add_argument("--size", type=int, default=28)
    ap.add_argument("--ref-n", type=int, default=20, help="maps for the per-step reference")
    ap.add_argument("--torch-n", type=int, default=400, help="maps for the batched PyTorch forward")
    ap.add_argument("--weights", default=None)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    model, weights_name = load_model(args.size, args.weights)
    model.eval()
    maps = generate_maps(args.n, args.size, args.seed, n_starts=1)
    obs, starts, goals = maps.obstacles, maps.starts[:, 0], maps.goals
    plan_batch(obs[:50], starts[:50], goals[:50], model)  # compile / load the Numba cache

    t_engine = timed(lambda: plan_batch(obs, starts, goals, model), repeat=3)
    t_actions = timed(lambda: action_maps(model, obs, goals), repeat=3)
    r = args.ref_n
    t_ref = timed(lambda: plan_reference(obs[:r], starts[:r], goals[:r], model))

    def torch_forward():
        with torch.no_grad():
            for i in range(0, args.torch_n, 100):
                model.action_logits(make_input(obs[i : i + 100], goals[i : i + 100])).argmax(-1)

    torch_forward()
    t_torch = timed(torch_forward, repeat=2)

    fast = plan_batch(obs[:r], starts[:r], goals[:r], model)
    ref = plan_reference(obs[:r], starts[:r], goals[:r], model)
    identical = all(np.array_equal(a, b) for a, b in zip(fast.paths.unpack(), ref.paths.unpack())) and np.array_equal(
        fast.termination, ref.termination
    )

    cfg = model.config
    fma_per_map = cfg.k * args.size * args.size * cfg.l_q * 9
    cores = len(os.sched_getaffinity(0))
    peak = cores * 2 * 8 * cpu_clock_hz()
    engine = args.n / t_engine
    out = {
        "size": args.size,
        "k": cfg.k,
        "weights": weights_name,
        "cores": cores,
        "engine_threads": N_THREADS,
        "torch_threads": torch.get_num_threads(),
        "load_average_1min": os.getloadavg()[0],
        "reference_plans_per_s": round(r / t_ref, 2),
        "torch_batched_maps_per_s": round(args.torch_n / t_torch, 1),
        "engine_plans_per_s": round(engine, 1),
        "engine_action_maps_per_s": round(args.n / t_actions, 1),
        "engine_vs_torch_batched": round(engine / (args.torch_n / t_torch), 1),
        "engine_vs_reference": round(engine / (r / t_ref), 1),
        "fma_per_map": fma_per_map,
        "fma_peak_per_s": peak,
        "engine_share_of_fma_peak": round(engine * fma_per_map / peak, 3),
        "action_maps_share_of_fma_peak": round(args.n / t_actions * fma_per_map / peak, 3),
        "identical_to_reference_on_sample": bool(identical),
    }
    if args.json:
        print(json.dumps(out))
        return
    print(
        f"{args.size}x{args.size}, k={cfg.k}, weights: {weights_name}; {cores} cores, "
        f"load average {out['load_average_1min']:.1f}"
    )
    print(f"  per-step reference   {out['reference_plans_per_s']:>10.1f} plans/s   ({r} maps)")
    print(
        f"  batched torch fwd    {out['torch_batched_maps_per_s']:>10.1f} maps/s    ({args.torch_n} maps, no rollouts)"
    )
    print(f"  engine (plan_batch)  {engine:>10.1f} plans/s   ({args.n} maps, 1 start each)")
    print(f"    of which value maps {out['engine_action_maps_per_s']:>9.1f} maps/s")
    print(
        f"  engine / torch batched = {out['engine_vs_torch_batched']}x, engine / reference = "
        f"{out['engine_vs_reference']}x"
    )
    print(
        f"  FMA: {fma_per_map / 1e6:.2f} M per map; peak {peak / 1e9:.1f} G/s = {cores} cores x 2 FMA units x 8 "
        f"float32 lanes x {cpu_clock_hz() / 1e9:.2f} GHz; engine uses {out['engine_share_of_fma_peak']:.1%} "
        f"(value maps alone {out['action_maps_share_of_fma_peak']:.1%})"
    )
    print(f"  engine identical to the reference on the {r} sampled maps: {identical}")


if __name__ == "__main__":
    main()
