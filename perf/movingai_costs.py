"""What a Moving AI suite's entry costs, per planner: each attack group of `movingai64-v1` timed on a few of its maps.

    PYTHONPATH=src .venv/bin/python perf/movingai_costs.py --data ../shared/data/movingai [--planners astar,optimal]
        [--maps 2] [--json]

On the first `--maps` maps of `movingai64-quick-v1` taken alternately from its city crops and its MAPF problems (a
city crop first), each group of the full suite's ensemble (`robustness` as `vinadv bench run` calls it: the cheap
strategies adding k = 1..3, the exhaustive adding 1, all five removing 1; and the quick suite's cheap four removing
1) is run and timed per planner, side by side in this run; the seconds per map, and what they come to on the 275
maps of `movingai64-v1` and the 70 of the quick suite (each suite's groups). A rough figure (a handful of maps; the
cost of a map grows with its free cells and its path): the guide's "How long" gives the entries' own times.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from vinadv.bench.scoring import suite_maps
from vinadv.bench.suites import get_suite
from vinadv.planners.registry import load_planner
from vinadv.robustness import attack_settings, robustness


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default="../shared/data/movingai", help="the folder of the Moving AI files")
    parser.add_argument("--planners", default="astar,wastar:w=2,optimal", help="planner specs, comma-separated")
    parser.add_argument("--maps", type=int, default=2, help="maps timed (alternately a city crop and a MAPF map)")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = parser.parse_args()
    import torch  # noqa: PLC0415 (one thread: the figures are per core)

    torch.set_num_threads(1)
    full, quick = get_suite("movingai64-v1"), get_suite("movingai64-quick-v1")
    maps = suite_maps(quick, args.data)
    city = np.flatnonzero(np.char.find(maps.source.astype(str), "_256") >= 0)
    mapf = np.flatnonzero(np.char.find(maps.source.astype(str), "_256") < 0)
    order = np.ravel(np.column_stack([city[: len(mapf)], mapf]))[: args.maps]
    sub = maps.take(order)
    groups = list(dict.fromkeys([*full.attacks, *quick.attacks]))  # each suite's groups, timed once
    out = {}
    for spec in args.planners.split(","):
        planner = load_planner(spec, sub.size, corner_cutting=sub.corner_cutting, moves=sub.moves)
        seconds = {}
        for g in groups:
            t0 = time.perf_counter()
            robustness(planner, sub, g.strategies, g.max_obstacles, edit=g.edit, **attack_settings(full))
            seconds[g] = (time.perf_counter() - t0) / len(sub)
        out[spec] = {
            "groups": {f"{g.edit} {'+'.join(g.strategies)} k<={g.max_obstacles}": s for g, s in seconds.items()},
            "full_suite_min": sum(seconds[g] for g in full.attacks) * full.n / 60,
            "quick_suite_min": sum(seconds[g] for g in quick.attacks) * quick.n / 60,
        }
    if args.json:
        print(json.dumps({"maps": len(sub), "planners": out}, indent=2))
        return
    for spec, figures in out.items():
        print(f"{spec} ({len(sub)} maps):")
        for key, per_map in figures["groups"].items():
            print(f"  {key:62s} {per_map:7.2f} s/map")
        print(
            f"  movingai64-v1: ~{figures['full_suite_min']:.0f} min; "
            f"movingai64-quick-v1: ~{figures['quick_suite_min']:.1f} min (attacks only)"
        )


if __name__ == "__main__":
    main()
