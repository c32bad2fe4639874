"""The cost of TransPath (`transpath-cf`, `transpath-focal`) beside A*'s on 64x64 maps, side by side: a forward, a
plan, each attack strategy per map; and, with the network's output cached, the compiled replica's search against
the differentiable search on the CPU.

    nice .venv/bin/python perf/transpath.py [--n 8] [--seed 48] [--rounds 3] [--exhaustive-maps 1] [--json]
        [--out docs/results/transpath_cost.json]

With `--out`, the figures also go to a JSON record with the command, the date, the machine (cpu, cores, niceness,
load averages before and after) and the run's wall time, which `docs/hooks.py` renders on docs/guide/transpath.md
("Cost"): no number there is copied by hand.

Rows: `--n` generated 64x64 maps (corner cutting, TransPath's rule), their first start. Timed in this run, taking
turns (`timed_side_by_side`), best of `--rounds`:
- `forward`: the network's values alone (`TransPathPlanner.outputs`, PyTorch on the CPU, the planner's batching);
- `plan`: `plan_paths` (forward, then the compiled replica) of each model, and `astar`'s `plan_paths` (octile);
- `replica search` and `differentiable search`, on the cached values: `transpath_search` (compiled, Numba) against
  `transpath_differentiable_search` (PyTorch, one thread, no gradients): the ratio is the done-when's (at least 10x);
  both give the same paths and expansions (counted);
- each strategy (`random`, `near-path`, `key-points`, `saliency`: one added obstacle, per_map 1, budget 8) per map,
  for the two models and `astar` (once, not best of: an attack plans many maps; after one untimed map with each, so
  that no strategy's first compilation is timed); `exhaustive` on the first `--exhaustive-maps` maps only (every
  valid cell a candidate, each one forward; their number counted), 0 to skip it.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import shlex
import sys
import time
from pathlib import Path

import numpy as np
import torch

from common import ROOT, add_output_arguments, cpu_model, load_average, timed_side_by_side  # perf/common.py
from vinadv.attacks.strategies import make_attack
from vinadv.attacks.validity import valid_cells
from vinadv.grid import generate_maps
from vinadv.planners.registry import load_planner
from vinadv.planners.transpath.differentiable import as_search_arrays, transpath_differentiable_search
from vinadv.planners.transpath.search import transpath_search

NAMES = {"cf": "transpath-cf", "f": "transpath-focal"}
STRATEGIES = ("random", "near-path", "key-points", "saliency", "exhaustive")


def write_record(args: argparse.Namespace, figures: dict, date: str) -> None:
    """`figures` as the record `--out` (module doc), with the command that makes it again."""
    out = args.out.resolve()
    shown_out = os.path.relpath(out, ROOT) if out.is_relative_to(ROOT) else "OUT"
    command_args = ["--n", str(args.n), "--seed", str(args.seed), "--rounds", str(args.rounds)]
    command_args += ["--exhaustive-maps", str(args.exhaustive_maps), "--out", shown_out]
    record = {
        "command": "python perf/transpath.py " + shlex.join(command_args),
        "date": date,
        "machine": {
            "cpu": cpu_model(),
            "cores": len(os.sched_getaffinity(0)),
            "niceness": os.nice(0),
            "load_average_before": figures["load_average"]["before"],
            "load_average_after": figures["load_average"]["after"],
        },
        "seconds": figures["seconds"],
        "figures": {k: v for k, v in figures.items() if k not in ("load_average", "seconds")},
    }
    out.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {out}", file=sys.stderr)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=8, help="generated 64x64 maps (default 8)")
    parser.add_argument("--seed", type=int, default=48, help="the generator's seed (default 48)")
    parser.add_argument("--exhaustive-maps", type=int, default=1, help="maps the exhaustive attack runs on (default 1)")
    parser.add_argument("--out", type=Path, default=None, help="also write the figures to this JSON record")
    add_output_arguments(parser, rounds=3)
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    load_before = load_average()
    started = time.perf_counter()
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")

    maps = generate_maps(args.n, 64, seed=args.seed, n_starts=1)
    obstacles, starts, goals = maps.obstacles, maps.starts[:, 0], maps.goals
    free = torch.from_numpy((~obstacles).astype(np.float32))
    planners = {mode: load_planner(name, 64) for mode, name in NAMES.items()}
    astar = load_planner("astar", 64)
    astar.plan_paths(obstacles[:1], starts[:1], goals[:1])  # compile (or load the cache) before timing
    cached = {}
    for mode, planner in planners.items():
        planner.plan_paths(obstacles[:1], starts[:1], goals[:1])
        cached[mode] = planner.outputs(obstacles, starts, goals)

    def differentiable(mode):
        with torch.no_grad():
            return transpath_differentiable_search(
                torch.from_numpy(cached[mode][0]), free, torch.from_numpy(starts), torch.from_numpy(goals), mode
            )

    fns = {"astar plan": lambda: astar.plan_paths(obstacles, starts, goals)}
    for mode, planner in planners.items():
        name = NAMES[mode]
        fns[f"{name} forward"] = lambda p=planner: p.outputs(obstacles, starts, goals)
        fns[f"{name} plan"] = lambda p=planner: p.plan_paths(obstacles, starts, goals)
        fns[f"{name} replica search"] = lambda m=mode: transpath_search(
            cached[m][0], obstacles, starts, goals, m, focal_exp=cached[m][1]
        )
        fns[f"{name} differentiable search"] = lambda m=mode: differentiable(m)
    times, results = timed_side_by_side(list(fns.values()), args.rounds)
    timing = dict(zip(fns, times))
    per_map = {name: t / args.n for name, t in timing.items()}
    out = {
        "maps": f"generate_maps({args.n}, 64, seed={args.seed}, n_starts=1), corner cutting",
        "rounds": args.rounds,
        "torch_threads": torch.get_num_threads(),
        "seconds_per_map": {k: round(v, 5) for k, v in per_map.items()},
        "ratios": {},
        "identical_searches": {},
        "attack_seconds_per_map": {},
    }
    for mode in planners:
        name = NAMES[mode]
        replica = results[list(fns).index(f"{name} replica search")]
        paths, reached, expanded = as_search_arrays(
            results[list(fns).index(f"{name} differentiable search")], starts, goals
        )
        same = [
            np.array_equal(paths[b], replica.paths[b]) and np.array_equal(expanded[b], replica.expanded[b])
            for b in range(args.n)
        ]
        out["identical_searches"][name] = f"{sum(same)}/{args.n}"
        out["ratios"][f"{name}: differentiable search / replica search"] = round(
            timing[f"{name} differentiable search"] / timing[f"{name} replica search"], 1
        )
        out["ratios"][f"{name}: forward / astar plan"] = round(timing[f"{name} forward"] / timing["astar plan"], 1)
        out["ratios"][f"{name}: plan / astar plan"] = round(timing[f"{name} plan"] / timing["astar plan"], 1)

    for strategy in STRATEGIES:
        count = min(args.n, args.exhaustive_maps) if strategy == "exhaustive" else args.n
        if count == 0:
            continue
        row = {}
        entries = (("astar", astar), *((NAMES[m], p) for m, p in planners.items()))
        # the strategies' own compiled code (Numba) is built on its first call: one untimed map first, with each
        # planner (the exhaustive attack with `astar` alone: its candidates are the same code for every planner)
        for _name, planner in entries[:1] if strategy == "exhaustive" else entries:
            make_attack(strategy, per_map=1, seed=0, budget=8).attack(obstacles[:1], starts[:1], goals[:1], planner)
        for name, planner in entries:
            attack = make_attack(strategy, per_map=1, seed=0, budget=8)
            start = time.perf_counter()
            attack.attack(obstacles[:count], starts[:count], goals[:count], planner)
            row[name] = round((time.perf_counter() - start) / count, 3)
        row["maps"] = count
        if strategy == "exhaustive":
            # its candidates, each one planned map (for TransPath one forward): every valid cell
            valid = valid_cells(obstacles[:count], starts[:count], goals[:count], True, astar.moves)
            row["candidates_per_map"] = round(float(valid.sum()) / count, 1)
        out["attack_seconds_per_map"][strategy] = row
        for mode in planners:
            out["ratios"][f"{NAMES[mode]}: {strategy} / astar {strategy}"] = round(row[NAMES[mode]] / row["astar"], 1)
    out["load_average"] = {"before": load_before, "after": load_average()}
    out["seconds"] = round(time.perf_counter() - started, 1)
    if args.out is not None:
        write_record(args, out, date)

    if args.json:
        print(json.dumps(out))
        return 0
    print(f"{out['maps']}; load average {load_before} before, {out['load_average']['after']} after")
    for name, t in out["seconds_per_map"].items():
        print(f"  {name:<44} {t * 1000:>10.2f} ms a map")
    for strategy, row in out["attack_seconds_per_map"].items():
        cells = ", ".join(f"{k} {v:.3f} s" for k, v in row.items() if k not in ("maps", "candidates_per_map"))
        print(f"  attack {strategy:<11} a map ({row['maps']} maps): {cells}")
    for what, ratio in out["ratios"].items():
        print(f"  {what}: {ratio}x")
    for name, same in out["identical_searches"].items():
        print(f"  {name}: replica and differentiable searches identical on {same}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
