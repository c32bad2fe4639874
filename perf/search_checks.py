"""What checking a search planner's answer costs (`vinadv.planners.search.check_paths`) beside the search itself.

    .venv/bin/python perf/search_checks.py [--n 2000] [--size 28] [--planner astar] [--rounds 15] [--json]

Plans the first start of `--n` generated maps with `--planner`'s unchecked `plan_paths`, then checks the answer, best
of `--rounds` each, side by side in one run; prints both times and their ratio.
"""

from __future__ import annotations

import argparse
import time

from common import add_maps_arguments, add_output_arguments, print_figures  # perf/common.py
from vinadv.grid import generate_maps
from vinadv.planners.registry import load_planner
from vinadv.planners.search import SearchPlanner, check_paths


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_maps_arguments(parser, n=2000, seed=5, planner="astar")
    add_output_arguments(parser, rounds=15)
    args = parser.parse_args()
    maps = generate_maps(args.n, args.size, seed=args.seed, n_starts=1)
    planner = load_planner(args.planner, args.size)
    if not isinstance(planner, SearchPlanner):
        parser.error(f"--planner {args.planner}: not a search planner")
    obstacles, starts, goals = maps.obstacles, maps.starts[:, 0], maps.goals
    planner.plan_paths(obstacles[:10], starts[:10], goals[:10])  # compile outside the timing
    search = check = float("inf")
    for _ in range(args.rounds):
        t0 = time.perf_counter()
        raw = planner.plan_paths(obstacles, starts, goals)
        t1 = time.perf_counter()
        check_paths(planner.name, raw, obstacles, starts, goals, maps.corner_cutting, planner.moves)
        t2 = time.perf_counter()
        search, check = min(search, t1 - t0), min(check, t2 - t1)
    result = {
        "planner": args.planner,
        "rows": args.n,
        "size": args.size,
        "search_ms": round(1e3 * search, 2),
        "check_ms": round(1e3 * check, 2),
        "check_over_search": round(check / search, 4),
    }
    print_figures(
        result,
        args.json,
        [
            f"{args.planner}: {args.n} rows of {args.size}x{args.size}: search {result['search_ms']} ms, "
            f"check_paths {result['check_ms']} ms ({100 * result['check_over_search']:.1f}% of the search)"
        ],
    )


if __name__ == "__main__":
    main()
