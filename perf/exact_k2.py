"""The greedy's gap to the exact k = 2 worst case on a bench suite's maps (`vinadv.exact_k2`), and what it costs.

    nice .venv/bin/python perf/exact_k2.py [--suite vin28-quick-v1] [--planner vin] [--mode harmful|regret]
        [--n N] [--out docs/results/exact_k2/vin28-quick-v1.vin.harmful.json]

On the first `--n` maps of the suite (default all; the suite's maps are checked against its checksum when all are
taken): the suite's adding attacks, greedy, at k = 1 and 2 (its settings: objective, seed, budget, radius,
tolerances; the first maps of a suite draw as in the whole run), then the exact diagnostic in `--mode`. Prints and
writes (with `--out`) one JSON record: the command, the machine and its load, the greedy figures, the diagnostic's
figures and per-map rows, and the cost: seconds of each part and the pair search's planned pairs per second, from
which the full run's cost is estimated (the pairs of the maps it did not run, at the measured rate).
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import sys
import time
from pathlib import Path

from common import cpu_model, load_average
from vinadv.attacks.validity import valid_cells
from vinadv.bench.suites import get_suite, maps_sha256
from vinadv.exact_k2 import MODES, exact_k2
from vinadv.planners.registry import load_planner
from vinadv.robustness import attack_settings, heldout_maps, robustness


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", default="vin28-quick-v1", help="a generated-maps suite (default vin28-quick-v1)")
    ap.add_argument("--planner", default="vin")
    ap.add_argument("--mode", choices=MODES, default="harmful")
    ap.add_argument("--n", type=int, default=None, help="the suite's first N maps (default all)")
    ap.add_argument("--out", help="write the record here (JSON)")
    args = ap.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "1")

    suite = get_suite(args.suite)
    if hasattr(suite, "files"):
        sys.exit(f"{args.suite}: a data suite; this script takes the generated suites")
    maps = heldout_maps(suite.n, suite.size, seed=suite.maps_seed)
    if maps_sha256(maps.obstacles, maps.starts, maps.goals) != suite.maps_sha256:
        sys.exit(f"{args.suite}: the generated maps differ from the suite's checksum")
    n = suite.n if args.n is None else args.n
    maps = maps.take(slice(0, n))
    group = next(g for g in suite.attacks if g.edit == "add")
    planner = load_planner(args.planner, suite.size, moves=maps.moves)
    settings = attack_settings(suite)

    t0 = time.perf_counter()
    greedy = robustness(planner, maps, group.strategies, 2, **settings)
    greedy_s = time.perf_counter() - t0
    result = exact_k2(
        planner,
        maps,
        args.mode,
        harm_tol=suite.harm_tolerance,
        harm_rtol=suite.harm_rtol,
        greedy=greedy,
        progress=sys.stderr.isatty(),
    )
    exact = result.to_dict()
    search_s = exact["seconds"]
    rate = exact["planned_pairs"] / search_s if search_s else None
    record = {
        "command": "python perf/exact_k2.py " + shlex.join(sys.argv[1:]),
        "suite": {"name": suite.name, "checksum": suite.checksum, "maps": n, "of": suite.n},
        "planner": planner.spec(),
        "machine": {"cpu": cpu_model(), "cpus": len(os.sched_getaffinity(0)), "load_average": load_average()},
        "greedy": {
            "strategies": list(group.strategies),
            "seconds": round(greedy_s, 3),
            "worst_case": [f.to_dict(intervals=True) for f in greedy.overall[:2]],
        },
        "exact_k2": exact,
        "cost": _cost(suite, maps, planner, result, rate, n),
    }
    text = json.dumps(record, indent=1)
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(text + "\n")
    print(json.dumps({k: v for k, v in record.items() if k != "exact_k2"} | {"exact_k2": _short(exact)}, indent=1))


def _short(exact: dict) -> dict:
    return {k: v for k, v in exact.items() if k != "per_map"}


def _cost(suite, maps, planner, result, rate: float | None, n: int) -> dict:
    """The pairs of this run's maps, the planned pairs per second (the diagnostic's seconds, the one-cell search's
    included), and for `regret` on fewer maps than the suite's the pairs a whole run plans: every candidate pair of its
    maps not harmed at one cell, estimated from this run's share of such maps."""
    starts = maps.starts[:, 0]
    cells = valid_cells(maps.obstacles, starts, maps.goals, maps.corner_cutting, planner.moves, maps.frozen)
    per_map = cells.reshape(len(maps), -1).sum(axis=1)
    out = {
        "valid_cells_mean": float(per_map.mean()),
        "candidate_pairs_mean": float((per_map * (per_map - 1) // 2).mean()),
        "planned_pairs_per_second": None if rate is None else round(rate, 1),
    }
    if result.mode == "regret" and rate:
        searched = result.search.searched
        pairs = result.search.candidate_pairs[searched]
        full = float(pairs.mean()) * searched.mean() * suite.n if searched.any() else 0.0
        out["whole_suite_pairs_estimate"] = round(full)
        out["whole_suite_seconds_estimate"] = round(full / rate)
    return out


if __name__ == "__main__":
    main()
