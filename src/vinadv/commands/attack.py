"""`vinadv attack`: one-obstacle adversarial maps from a maps file."""

from __future__ import annotations

import argparse
import json
import time

from vinadv.cluster import add_cluster_arguments, open_cluster
from vinadv.commands import LazyChoices


def register(subparsers) -> None:
    p = subparsers.add_parser("attack", help="make adversarial maps (one added obstacle) from a maps file")
    p.add_argument("--maps", required=True, help="maps file (.npz from `vinadv maps generate`)")
    p.add_argument("--strategy", required=True, choices=LazyChoices("vinadv.attacks.strategies", "STRATEGIES"),
                   metavar="STRATEGY", help="attack strategy: %(choices)s")
    p.add_argument("--out", required=True, help="output pairs file (.npz)")
    p.add_argument("--per-map", type=int, default=1,
                   help="pairs per map (default 1; 0 with exhaustive: every valid cell)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--budget", type=int, default=8,
                   help="key-points and saliency: candidates evaluated per map (default 8)")
    p.add_argument("--radius", type=int, default=2, help="near-path: Chebyshev distance to the path (default 2)")
    p.add_argument("--weights", help="VIN weights file (default: the shipped weights)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress bar, no summary")
    add_cluster_arguments(p, shard_size=True)
    p.set_defaults(func=cmd_attack)


def attack_summary(labels, n_maps: int, no_valid: int, planner_calls: int, seconds: float) -> dict:
    from vinadv.identify import LABEL_STRENGTH

    counts = {label: int((labels == label).sum()) for label in LABEL_STRENGTH}
    valid = len(labels) - counts["invalid"]
    success = counts["UrP"] + counts["FP"]
    return {
        "maps": n_maps, "pairs": len(labels), "maps_without_valid_cell": no_valid, "counts": counts,
        "success_rate": success / valid if valid else None, "planner_calls": planner_calls,
        "planner_calls_per_success": planner_calls / success if success else None, "seconds": round(seconds, 3),
    }


def print_counts(summary: dict) -> None:
    counts = summary["counts"]
    total = max(1, sum(counts.values()))
    print(f"{'category':<10}{'pairs':>9}{'share':>9}")
    for label, count in counts.items():
        print(f"{label:<10}{count:>9,}{count / total:>9.1%}")
    rate = summary["success_rate"]
    print(f"attack success rate (UrP + FP over valid pairs): {'n/a' if rate is None else f'{rate:.1%}'}")


def cmd_attack(args: argparse.Namespace) -> int:
    from vinadv.attacks.strategies import make_attack
    from vinadv.grid.mapset import MapSet
    from vinadv.identify import identify, rule_strength  # scikit-learn behind it: imported for this command only
    from vinadv.planners.weights import load_vin

    maps = MapSet.load(args.maps)
    model = load_vin(args.weights, size=maps.size)
    attack = make_attack(args.strategy, per_map=args.per_map, seed=args.seed, budget=args.budget, radius=args.radius)
    t0 = time.perf_counter()
    if args.cluster is None and args.workers is None:
        result = attack.attack(maps.obstacles, maps.starts[:, 0], maps.goals, model, maps.corner_cutting,
                               strength=rule_strength, progress=not args.quiet)
    else:
        from vinadv.cluster import attack_on_cluster

        options = dict(per_map=args.per_map, seed=args.seed, budget=args.budget, radius=args.radius)
        with open_cluster(args.cluster, args.workers) as client:
            result = attack_on_cluster(client, args.strategy, options, maps, args.weights,
                                       shard_size=args.shard_size, progress=not args.quiet)
    elapsed = time.perf_counter() - t0
    result.pairs.save(args.out)
    summary = attack_summary(identify(result.pairs).labels, len(maps), len(result.no_valid_cell),
                             result.planner_calls, elapsed)
    summary.update(strategy=args.strategy, params=attack.params(), out=args.out)
    if args.json:
        print(json.dumps(summary))
    elif not args.quiet:
        print(f"{args.strategy}: {summary['pairs']:,} pairs from {len(maps):,} maps in {elapsed:.1f} s -> {args.out}")
        if result.no_valid_cell.size:
            print(f"{len(result.no_valid_cell)} maps had no valid cell for the added obstacle; no pair was made for them")
        print_counts(summary)
        per = summary["planner_calls_per_success"]
        print(f"planner calls: {result.planner_calls:,} ({'n/a' if per is None else f'{per:.1f}'} per successful attack)")
    return 0
