"""Plans per second of `neural-astar` (exact mode) and `astar`, beside Neural A*'s differentiable search, on the same
32x32 maps, side by side.

    nice .venv/bin/python perf/neural_astar.py [--data MPD.npz] [--n 200] [--size 32] [--device cpu] [--json]

Rows are (map, start) searches: with `--data` the test maps of an MP dataset file (one start per map drawn from the
cells that reach the goal, `perf/search.py`'s rule), else `--n` generated `moore` maps of `--size` with their
first start. Timed in this run, taking turns, best of `--rounds`:
- `astar`: vanilla A* (`AStarPlanner.plan_paths`), the compiled search with unit costs;
- `neural-astar exact`: `NeuralAstarPlanner.plan_paths`, the encoder's guidance costs then the compiled search;
- `encoder only`: the guidance costs alone (how much of the exact mode is the CNN);
- `differentiable`: `plan_paths_differentiable`, the encoder then the authors' differentiable A* in PyTorch, no
  gradients, `--batch` rows per forward;
- `differentiable + gradient`: the saliency module (`differentiable_paths`) forward and backward to the obstacles.
The exact and the differentiable mode give the same paths and expansions (counted and printed). PyTorch runs on
`--device` (one torch thread per encoder batch on the CPU, as the planner does); the compiled search on the CPU.
"""

from __future__ import annotations

import argparse

import numba
import numpy as np
import torch

# perf/common.py
from common import add_output_arguments, add_rows_arguments, print_figures, search_rows, timed_side_by_side
from vinadv.planners.classical.astar import AStarPlanner
from vinadv.planners.neural_astar.model import load_neural_astar
from vinadv.planners.neural_astar.planner import NeuralAstarPlanner


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_rows_arguments(parser, n=200, size=32)
    parser.add_argument("--batch", type=int, default=64, help="rows per torch forward (default 64)")
    parser.add_argument("--device", default="cpu", help="torch device (default cpu)")
    add_output_arguments(parser, rounds=3)
    args = parser.parse_args(argv)

    obstacles, starts, goals, source = search_rows(args)
    size = obstacles.shape[1]
    astar = AStarPlanner(size, "moore")
    neural = NeuralAstarPlanner(load_neural_astar(), size, device=args.device, batch_size=args.batch)
    astar.plan_paths(obstacles[:2], starts[:2], goals[:2])  # compile (or load the cache) before timing
    neural.plan_paths(obstacles[:2], starts[:2], goals[:2])
    module = neural.differentiable_paths

    def with_gradient():
        grads = []
        for i in range(0, len(starts), args.batch):
            sl = slice(i, i + args.batch)
            obs = torch.from_numpy(obstacles[sl].astype(np.float32)).to(args.device).requires_grad_(True)
            path = module(
                obs, torch.from_numpy(starts[sl]).to(args.device), torch.from_numpy(goals[sl]).to(args.device)
            )
            path.sum().backward()
            grads.append(obs.grad.cpu())
        return torch.cat(grads)

    fns = {
        "astar": lambda: astar.plan_paths(obstacles, starts, goals),
        "neural-astar exact": lambda: neural.plan_paths(obstacles, starts, goals),
        "encoder only": lambda: neural.guidance(obstacles, starts, goals),
        "differentiable": lambda: neural.plan_paths_differentiable(obstacles, starts, goals),
        "differentiable + gradient": with_gradient,
    }
    times, results = timed_side_by_side(list(fns.values()), args.rounds)
    timing = dict(zip(fns, times))
    exact, diff = results[1], results[3]
    same = exact.paths.same_as(diff.paths) & (exact.expanded == diff.expanded).all(axis=(1, 2))
    rows = len(starts)
    out = {
        "source": source,
        "rows": rows,
        "device": args.device,
        "numba_threads": numba.get_num_threads(),
        "torch_threads": torch.get_num_threads(),
        "mean_expansions": {
            "astar": float(results[0].expansions.mean()),
            "neural-astar": float(exact.expansions.mean()),
        },
        "plans_per_s": {name: round(rows / t, 1) for name, t in timing.items()},
        "exact_over_differentiable": round(timing["differentiable"] / timing["neural-astar exact"], 2),
        "astar_over_neural_exact": round(timing["neural-astar exact"] / timing["astar"], 2),
        "identical_searches": int(same.sum()),
    }
    print_figures(
        out,
        args.json,
        [
            f"{source}; torch on {args.device}, {out['numba_threads']} Numba threads",
            *(f"  {name:<26} {rate:>10.1f} plans/s" for name, rate in out["plans_per_s"].items()),
            f"  expansions per search: astar {out['mean_expansions']['astar']:.1f}, neural-astar "
            f"{out['mean_expansions']['neural-astar']:.1f}",
            f"  neural-astar exact is {out['exact_over_differentiable']:.2f}x the differentiable search's rate",
            f"  astar is {out['astar_over_neural_exact']:.2f}x neural-astar exact's rate",
            f"  identical paths and expansions, exact vs differentiable: {out['identical_searches']} of {rows}",
        ],
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
