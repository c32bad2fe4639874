"""Search throughput: `astar` (vinadv.planners.classical.astar) on a batch of rows at once against one row per call.

    nice .venv/bin/python perf/search.py [--data MPD.npz] [--n 1000] [--size 32] [--moves moore] [--json]

Rows are (map, start) searches: with `--data` the test maps of an MP dataset file (planning-datasets layout, one
start per map drawn from the cells that reach the goal, `moore` moves), else `--n` generated maps of `--size` with
their first start, on the movement model `--moves`. Timed side by side in this run, taking turns, best of
`--rounds`:
- `batched`: `AStarPlanner.plan_paths` of all rows in one call (the kernel runs the rows in parallel, Numba threads);
- `one at a time`: one call per row (what a planner without a batched search would do: the Python call, the input
  checks and the result packing per row).
Both give the same paths and expansions (checked). The kernel is compiled (and cached) before timing.
"""

from __future__ import annotations

import argparse

import numba
import numpy as np

# perf/common.py
from common import add_output_arguments, add_rows_arguments, print_figures, search_rows, timed_side_by_side
from vinadv.planners.classical.astar import AStarPlanner


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_rows_arguments(parser, n=1000, size=32)
    parser.add_argument("--moves", default="moore", help="movement model of the generated maps (default moore)")
    add_output_arguments(parser, rounds=3)
    args = parser.parse_args(argv)

    obstacles, starts, goals, source = search_rows(args, args.moves)
    moves = "moore" if args.data else args.moves
    planner = AStarPlanner(obstacles.shape[1], moves)
    planner.plan_paths(obstacles[:2], starts[:2], goals[:2])  # compile (or load the cache) before timing

    def batched():
        return planner.plan_paths(obstacles, starts, goals)

    def one_at_a_time():
        return [
            planner.plan_paths(obstacles[i : i + 1], starts[i : i + 1], goals[i : i + 1]) for i in range(len(starts))
        ]

    (t_batch, t_one), (whole, parts) = timed_side_by_side([batched, one_at_a_time], args.rounds)
    for i, part in enumerate(parts):
        assert part.paths[0].tolist() == whole.paths[i].tolist()
        assert np.array_equal(part.expanded[0], whole.expanded[i])
    rows = len(starts)
    out = {
        "source": source,
        "moves": moves,
        "rows": rows,
        "threads": numba.get_num_threads(),
        "mean_expansions": float(whole.expansions.mean()),
        "batched_rows_per_s": round(rows / t_batch, 1),
        "one_at_a_time_rows_per_s": round(rows / t_one, 1),
        "speedup": round(t_one / t_batch, 2),
    }
    print_figures(
        out,
        args.json,
        [
            f"{source}, {moves} moves, {out['threads']} Numba threads, {out['mean_expansions']:.1f} expansions/row",
            f"  batched        {out['batched_rows_per_s']:>10.1f} rows/s",
            f"  one at a time  {out['one_at_a_time_rows_per_s']:>10.1f} rows/s",
            f"  batched / one at a time: {out['speedup']:.2f}x",
        ],
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
