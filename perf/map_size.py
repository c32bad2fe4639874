"""The VIN engine and its exhaustive attack as maps grow (28x28, 32x32, 64x64), side by side in one run, beside the
multiply-adds a map needs: how the cost grows from 28 to 64, against the physical limit.

    nice -n 15 .venv/bin/python perf/map_size.py [--sizes 28,32,64] [--n 500] [--attack-n 4] [--rounds 2]
        [--weights W] [--out FILE.json]

The same tensors at every size, `--weights` (default the shipped `vin64.pt`: the shift start fine-tuned at 64x64,
whose value iteration is the shortest-path recursion, so it plans every size here: 100% of 300 generated maps at 28
and 32), with their own k on maps of the size they were trained on (100 at 64) and k = `default_k(N)` on others (36
at 28, 42 at 32). Only k and N change the arithmetic per map; the weights change where the paths go and how often a
decision is a near tie. Per size, on `--n` generated maps of one start each (seed 2026), best of `--rounds` after a
first, untimed plan of the same maps (`first_plan`: its seconds; it pays the engine's compilation and the near-tie
replay's first checks against PyTorch, seconds each time a process meets a new size, and again when sizes take
turns, so the sizes do not take turns here: each runs its rounds in a row):

- `value maps`: `engine.action_maps`, every cell's action from the value map: the multiply-adds below and nothing
  else, maps/s;
- `engine`: `VINPlanner.plan_batch`, the exact CPU engine, one plan per map (each its own value map): plans/s,
  with the maps whose rollout met a near tie (`near_tie_maps`): those are re-decided by replaying PyTorch's float32
  arithmetic (`vinadv.planners.vin.replay`);
- `attack`: the exhaustive attack (`make_attack("exhaustive")` with `vinadv robustness`' harm ranking: every valid
  cell of every map added in turn, each candidate map planned, paired, labelled, ranked) on the first `--attack-n`
  maps: seconds per map, and the candidate maps per map (valid cells, `vinadv.attacks.validity.valid_cells`).

The FMA count per map (float32 multiply-adds of the VIN forward, N x N cells, l_i input channels, l_h hidden,
l_q q channels, 3x3 kernels):

    h conv   (l_i -> l_h, 3x3):        N^2 * l_h * l_i * 9
    r conv   (l_h -> 1, 1x1):          N^2 * l_h
    q conv of r (1 -> l_q, 3x3), once: N^2 * l_q * 9        (the reward's part of q does not change between steps)
    k steps, w conv of v (1 -> l_q):   k * N^2 * l_q * 9
    forward = N^2 * (9 l_h l_i + l_h + 9 l_q + 9 k l_q)

The engine folds h and r into one 2 -> 1 convolution (no nonlinearity between them: N^2 * l_i * 9 instead of
N^2 * (9 l_h l_i + l_h)), so its count is `engine = N^2 * (9 l_i + 9 l_q + 9 k l_q)`; the action head (l_q x 8 at
the cells a path visits) is left out (under 0.1%). An exhaustive attack of a map plans each candidate map, so it
needs `(candidates + 1) * engine` multiply-adds. The limit: plans/s at the CPU's FMA peak (cores x 2 FMA units x
8 float32 lanes x clock, as `perf/planning.py`), and the engine's share of it.

Growth from the first size: each figure's ratio to its value at the first size (time per map; the FMA count;
candidates per map). The machine's load average is recorded before and after: on a shared machine the absolute
rates are noisy, the ratios (same run, minutes apart) less so. `--out` writes the JSON with the command that made it
(docs/results/map_size.json, shown in docs/guide/gpu.md).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shlex
import sys
import time
from pathlib import Path

import numpy as np

from vinadv.attacks.strategies import make_attack
from vinadv.attacks.validity import valid_cells
from vinadv.grid import generate_maps
from vinadv.identify import harm_strength
from vinadv.planners.batching import N_THREADS
from vinadv.planners.vin.arrays import VINWeights, default_k
from vinadv.planners.vin.engine import action_maps, plan_maps
from vinadv.planners.vin.planner import VINPlanner
from vinadv.planners.vin.weights import load_vin_weights
from vinadv.planners.weights import WEIGHTS_DIR

sys.path.insert(0, str(Path(__file__).resolve().parent))
from planning import cpu_clock_hz  # noqa: E402 (the one reading of the clock the FMA peak uses)

SEED = 2026


def fma_per_map(size: int, k: int, l_i: int, l_h: int, l_q: int) -> dict[str, int]:
    """Multiply-adds of one VIN forward on a `size x size` map: `forward` (as the network is written) and `engine`
    (h and r folded into one 2 -> 1 convolution, as the planning engine computes it); see the module doc."""
    cells = size * size
    loop = cells * 9 * k * l_q
    q_of_r = cells * 9 * l_q
    return {
        "h_conv": cells * 9 * l_h * l_i,
        "r_conv": cells * l_h,
        "q_conv_of_r": q_of_r,
        "value_iteration": loop,
        "forward": cells * (9 * l_h * l_i + l_h) + q_of_r + loop,
        "engine": cells * 9 * l_i + q_of_r + loop,
    }


def size_weights(path: str, size: int) -> VINWeights:
    """The VIN of `path` for `size x size` maps: its own k on maps of the size it was trained on, else
    k = `default_k(size)`."""
    weights = load_vin_weights(path, size=size)
    if weights.record.get("size") == size:
        return weights
    return load_vin_weights(path, size=size, k=default_k(size))


def load_average() -> float:
    return round(os.getloadavg()[0], 2)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="28,32,64")
    parser.add_argument("--n", type=int, default=500, help="maps per size for the engine's plans/s")
    parser.add_argument("--attack-n", type=int, default=4, help="maps per size for the exhaustive attack")
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--weights", default=str(WEIGHTS_DIR / "vin64.pt"))
    parser.add_argument("--out", default=None, help="also write the JSON here")
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    record = {
        "command": "python perf/map_size.py " + shlex.join(sys.argv[1:]),
        "machine": {
            "cpu": platform.processor() or platform.machine(),
            "cores": len(os.sched_getaffinity(0)),
            "engine_threads": N_THREADS,
            "clock_ghz": round(cpu_clock_hz() / 1e9, 2),
            "load_average_before": load_average(),
        },
        "seed": SEED,
        "sizes": [],
    }
    try:
        with open("/proc/cpuinfo") as fh:
            record["machine"]["cpu"] = next(x.split(":", 1)[1].strip() for x in fh if x.startswith("model name"))
    except (OSError, StopIteration):
        pass
    peak = record["machine"]["cores"] * 2 * 8 * cpu_clock_hz()
    attack = make_attack("exhaustive")

    cases, best, near_ties, warm_ties = {}, {}, {}, {}
    for size in sizes:  # each size warmed up, then its rounds (see the module doc: the replay's checks)
        weights = size_weights(args.weights, size)
        planner = VINPlanner(weights, size=size)
        maps = generate_maps(args.n, size, seed=SEED, n_starts=1)
        obstacles, starts, goals = maps.obstacles, maps.starts[:, 0], maps.goals
        a = slice(0, args.attack_n)
        candidates = int(valid_cells(obstacles[a], starts[a], goals[a], True).sum())
        warm = generate_maps(4, size, seed=1, n_starts=1)  # compiles the engine and the attack's kernels
        attack.attack(warm.obstacles, warm.starts[:, 0], warm.goals, planner, strength=harm_strength)
        action_maps(weights, warm.obstacles, warm.goals)
        warm_stats: dict = {}
        t0 = time.perf_counter()
        plan_maps(obstacles, goals, starts[:, None], weights, stats=warm_stats)  # the replay's first checks
        warm_ties[size] = {"near_tie_maps": warm_stats.get("near_tie_maps", 0), "seconds": time.perf_counter() - t0}
        cases[size] = (weights, planner, obstacles, starts, goals, a, candidates)
        best[size] = {"value_maps": np.inf, "engine": np.inf, "attack": np.inf}
        for _ in range(args.rounds):
            t0 = time.perf_counter()
            action_maps(weights, obstacles, goals)
            best[size]["value_maps"] = min(best[size]["value_maps"], time.perf_counter() - t0)
            stats: dict = {}
            t0 = time.perf_counter()
            plan_maps(obstacles, goals, starts[:, None], weights, stats=stats)  # what plan_batch runs, with stats
            best[size]["engine"] = min(best[size]["engine"], time.perf_counter() - t0)
            near_ties[size] = stats.get("near_tie_maps", 0)
            t0 = time.perf_counter()
            attack.attack(obstacles[a], starts[a], goals[a], planner, strength=harm_strength)
            best[size]["attack"] = min(best[size]["attack"], time.perf_counter() - t0)
            print(
                f"{size}x{size}: value maps {best[size]['value_maps']:.2f} s, engine {best[size]['engine']:.2f} s, "
                f"attack {best[size]['attack']:.2f} s",
                flush=True,
            )

    for size in sizes:
        weights, _, obstacles, _, _, a, candidates = cases[size]
        config = weights.config
        fma = fma_per_map(size, config.k, config.l_i, config.l_h, config.l_q)
        plans_per_s = args.n / best[size]["engine"]
        value_maps_per_s = args.n / best[size]["value_maps"]
        n_attacked = len(obstacles[a])
        attack_s = best[size]["attack"] / n_attacked
        record["sizes"].append(
            {
                "size": size,
                "weights": Path(weights.path).name,
                "k": config.k,
                "maps": args.n,
                "attack_maps": n_attacked,
                "value_maps_per_s": round(value_maps_per_s, 1),
                "engine_plans_per_s": round(plans_per_s, 1),
                "near_tie_maps": near_ties[size],
                "first_plan": {k: round(v, 2) for k, v in warm_ties[size].items()},
                "attack_s_per_map": round(attack_s, 4),
                "candidates_per_map": round(candidates / n_attacked, 1),
                "fma_per_map": fma,
                "fma_limit_plans_per_s": round(peak / fma["engine"], 1),
                "engine_share_of_fma_peak": round(plans_per_s * fma["engine"] / peak, 3),
                "value_maps_share_of_fma_peak": round(value_maps_per_s * fma["engine"] / peak, 3),
                "attack_fma_per_map": int((candidates / n_attacked + 1) * fma["engine"]),
                "attack_share_of_fma_peak": round((candidates / n_attacked + 1) * fma["engine"] / attack_s / peak, 3),
            }
        )
    first = record["sizes"][0]
    for row in record["sizes"]:
        row["growth_from_first"] = {
            "value_map_time_per_map": round(first["value_maps_per_s"] / row["value_maps_per_s"], 2),
            "engine_time_per_map": round(first["engine_plans_per_s"] / row["engine_plans_per_s"], 2),
            "fma_per_map": round(row["fma_per_map"]["engine"] / first["fma_per_map"]["engine"], 2),
            "attack_time_per_map": round(row["attack_s_per_map"] / first["attack_s_per_map"], 2),
            "attack_fma_per_map": round(row["attack_fma_per_map"] / first["attack_fma_per_map"], 2),
            "candidates_per_map": round(row["candidates_per_map"] / first["candidates_per_map"], 2),
        }
    record["machine"]["load_average_after"] = load_average()
    record["machine"]["fma_peak_per_s"] = peak
    text = json.dumps(record, indent=1)
    if args.out:
        Path(args.out).write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
