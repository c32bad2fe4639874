"""What a suite's entry costs, per planner: each attack group of a suite timed on a few of its maps.

    PYTHONPATH=src .venv/bin/python perf/suite_costs.py --suite mpd32-v2 --quick mpd32-quick-v2 \
        --data ../shared/data/mpd --planners neural-astar,gppn-mpd32 [--maps 3] [--json]
    PYTHONPATH=src .venv/bin/python perf/suite_costs.py --data ../shared/data/movingai   # movingai64-v1 (default)

On `--maps` maps of the quick suite, taken from its sources in turn (the MP families; the Moving AI city crops and
MAPF problems), each group of the full suite's ensemble and of the quick suite's (`robustness` as `vinadv bench run`
calls it, a chained group from the exhaustive group's one-cell cells as `compute_chunk` does) is run and timed per
planner, on one thread, after a warm-up on one map (the compiled kernels), side by side in this run; the seconds per
map, and what they come to on each suite's maps (the attacks only: the clean protocols and loading the files come on
top). A rough figure (a handful of maps; the cost of a map grows with its free cells and its path): the guide's "How
long" gives the entries' own times.
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


def spread_maps(sources: np.ndarray, n: int) -> np.ndarray:
    """The first `n` indices taking one map of each source in turn (sources in order of first appearance)."""
    _, first, owner = np.unique(sources.astype(str), return_index=True, return_inverse=True)
    by_source = [np.flatnonzero(owner == s) for s in np.argsort(first)]
    order = [idx[i] for i in range(max(map(len, by_source))) for idx in by_source if i < len(idx)]
    return np.asarray(order[:n], dtype=np.int64)


def time_groups(planner, maps, groups, settings: dict) -> dict:
    """Seconds per map of each attack group on `maps`; a group with a `start` chains from the cells its start
    group kept (timed before it: groups in suite order)."""
    seconds, cells = {}, {}
    for g in groups:
        start = None if g.start is None else cells[f"{g.edit}:{g.start}"]
        t0 = time.perf_counter()
        result = robustness(planner, maps, g.strategies, g.max_obstacles, edit=g.edit, start=start, **settings)
        seconds[g] = (time.perf_counter() - t0) / len(maps)
        cells.update({key: s.cells[0] for key, s in zip(g.keys(), result.strategies.values()) if g.start is None})
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="movingai64-v1", help="the full suite")
    parser.add_argument("--quick", default="movingai64-quick-v1", help="the quick suite (its maps are timed)")
    parser.add_argument("--data", default="../shared/data/movingai", help="the folder of the suites' files")
    parser.add_argument("--planners", default="astar,wastar:w=2,optimal", help="planner specs, comma-separated")
    parser.add_argument("--maps", type=int, default=2, help="maps timed (one of each source in turn)")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = parser.parse_args()
    import torch  # noqa: PLC0415 (one thread: the figures are per core)

    torch.set_num_threads(1)
    full, quick = get_suite(args.suite), get_suite(args.quick)
    maps = suite_maps(quick, args.data)
    # each map's source: its file's name as the maps record it, else the suite's file it was read from (in order)
    sources = (
        maps.source
        if maps.source is not None
        else np.repeat([f.name for f in quick.files], [f.maps for f in quick.files])
    )
    sub = maps.take(spread_maps(sources, args.maps))
    groups = list(dict.fromkeys([*full.attacks, *quick.attacks]))  # each suite's groups, timed once
    out = {}
    for spec in args.planners.split(","):
        planner = load_planner(spec, sub.size, corner_cutting=sub.corner_cutting, moves=sub.moves)
        time_groups(planner, sub.take(np.arange(1)), groups, attack_settings(full))  # warm-up: compiles, caches
        seconds = time_groups(planner, sub, groups, attack_settings(full))
        out[spec] = {
            "groups": {
                f"{g.edit} {'+'.join(g.strategies)} k<={g.max_obstacles}" + (f" from {g.start}" if g.start else ""): s
                for g, s in seconds.items()
            },
            "full_suite_min": sum(seconds[g] for g in full.attacks) * full.n / 60,
            "quick_suite_min": sum(seconds[g] for g in quick.attacks) * quick.n / 60,
        }
    if args.json:
        print(json.dumps({"suite": full.name, "quick": quick.name, "maps": len(sub), "planners": out}, indent=2))
        return
    for spec, figures in out.items():
        print(f"{spec} ({len(sub)} maps):")
        for key, per_map in figures["groups"].items():
            print(f"  {key:72s} {per_map:7.2f} s/map")
        print(
            f"  {full.name}: ~{figures['full_suite_min']:.0f} min; "
            f"{quick.name}: ~{figures['quick_suite_min']:.1f} min (attacks only)"
        )


if __name__ == "__main__":
    main()
