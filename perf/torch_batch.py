"""A torch planner's CPU forward in batches of 64 maps (before) against `forward_batches` (16 to 31), side by side.

    python perf/torch_batch.py [--maps 64] [--rounds 3] [--json]

For the shipped GPPN (28x28 held-out maps) and the Neural A* encoder (32x32 generated maps, `moore`), on one torch
thread as `over_maps` runs each piece:
- `ms_per_map`: the best of `--rounds` of each way over the same `--maps` maps, taking turns; `ratio` = before / now;
- `bitwise_equal`: whether every map's output is the same bits both ways;
- `sizes_that_differ`: the batch sizes 1..40 whose output for their maps differs from batch 64's (oneDNN takes other
  kernels for small batches; `CPU_MIN_BATCH` must be above every one of them).
"""

from __future__ import annotations

import argparse
import json

import numpy as np
import torch

from common import add_output_arguments, timed_side_by_side
from vinadv.grid import generate_maps
from vinadv.planners.batching import CPU_MIN_BATCH, forward_batches
from vinadv.planners.registry import load_planner


def batched(forward, slices) -> torch.Tensor:
    return torch.cat([forward(sl) for sl in slices])


def compare(name: str, forward, n: int, rounds: int) -> dict:
    before = [slice(i, min(n, i + 64)) for i in range(0, n, 64)]
    now = forward_batches(0, n, True, 64)
    (t_before, t_now), (out_before, out_now) = timed_side_by_side(
        [lambda: batched(forward, before), lambda: batched(forward, now)], rounds
    )
    reference = forward(slice(0, 64))
    differ = [b for b in range(1, 41) if not torch.equal(forward(slice(0, b)), reference[:b])]
    return {
        "planner": name,
        "maps": n,
        "batches_now": sorted({sl.stop - sl.start for sl in now}),
        "ms_per_map": {"batch_64": 1000 * t_before / n, "forward_batches": 1000 * t_now / n},
        "ratio": t_before / t_now,
        "bitwise_equal": bool(torch.equal(out_before, out_now)),
        "sizes_that_differ": differ,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", type=int, default=64, help="maps timed (default 64, at least 64)")
    add_output_arguments(parser, rounds=3)
    args = parser.parse_args()
    n = max(64, args.maps)
    torch.set_num_threads(1)

    maps = generate_maps(n, 28, seed=1000)
    gppn = load_planner("gppn", 28).module
    obstacles = torch.from_numpy(maps.obstacles.astype(np.float32))
    goals = torch.from_numpy(maps.goals.astype(np.int64))

    mp = generate_maps(n, 32, seed=1000, moves="moore")
    neural = load_planner("neural-astar", 32, moves="moore").model
    mp_obstacles = torch.from_numpy(mp.obstacles.astype(np.float32))
    mp_starts = torch.from_numpy(mp.starts[:, 0].astype(np.int64))
    mp_goals = torch.from_numpy(mp.goals.astype(np.int64))

    with torch.no_grad():
        rows = [
            compare("gppn", lambda sl: gppn(obstacles[sl], goals[sl]), n, args.rounds),
            compare("neural-astar", lambda sl: neural(mp_obstacles[sl], mp_starts[sl], mp_goals[sl]), n, args.rounds),
        ]
    result = {"cpu_min_batch": CPU_MIN_BATCH, "torch_threads": 1, "rows": rows}
    if args.json:
        print(json.dumps(result, indent=1))
        return
    for r in rows:
        ms = r["ms_per_map"]
        print(
            f"{r['planner']:>13}: {ms['batch_64']:.1f} ms/map in batches of 64, {ms['forward_batches']:.1f} in "
            f"{r['batches_now']} ({r['ratio']:.2f}x); same bits: {r['bitwise_equal']}; batch sizes whose output "
            f"differs from 64's: {r['sizes_that_differ'] or 'none'}"
        )


if __name__ == "__main__":
    main()
