"""Attack strategies side by side on the same maps: category mix, success rate, planner calls per success, time.

    .venv/bin/python perf/attacks.py [--n 5000] [--size 28] [--weights W] [--strategies a,b,...] [--json]

The paper's mix for 5,000 near-path pairs: UrP 1,632, FP 204, DP 1,076, UcP 2,088 (36.7% success).
Targets (issue 5): key-points or saliency beats near-path's success rate; exhaustive on 5,000 maps < 10 minutes.
"""

from __future__ import annotations

import argparse
import json
import time

from vinadv.attacks.strategies import STRATEGIES, make_attack
from vinadv.grid import generate_maps
from vinadv.identify import identify, rule_strength
from vinadv.planners.vin.weights import load_vin
from vinadv.vocabulary import LABEL_STRENGTH, label_counts, success_count

PAPER = {"invalid": None, "UcP": 2088, "DP": 1076, "FP": 204, "UrP": 1632}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=5000)
    parser.add_argument("--size", type=int, default=28)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--weights")
    parser.add_argument("--strategies", default=",".join(STRATEGIES))
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    model = load_vin(args.weights, size=args.size)
    maps = generate_maps(args.n, args.size, seed=args.seed, n_starts=1)
    warm = generate_maps(20, args.size, seed=1, n_starts=1)
    rows = []
    for name in args.strategies.split(","):
        attack = make_attack(name, seed=args.seed)
        attack.attack(warm.obstacles, warm.starts[:, 0], warm.goals, model, strength=rule_strength)  # compile
        t0 = time.perf_counter()
        result = attack.attack(maps.obstacles, maps.starts[:, 0], maps.goals, model, strength=rule_strength)
        seconds = time.perf_counter() - t0
        labels = identify(result.pairs).labels
        counts = label_counts(labels)
        valid = len(labels) - counts["invalid"]
        success = success_count(counts)
        rows.append(
            {
                "strategy": name,
                "maps": args.n,
                "pairs": len(labels),
                "counts": counts,
                "success_rate": success / valid if valid else None,
                "planner_calls": result.planner_calls,
                "calls_per_success": result.planner_calls / success if success else None,
                "seconds": seconds,
                "plans_per_second": result.planner_calls / seconds,
            }
        )
    if args.json:
        print(json.dumps(rows))
        return
    print(f"{args.n} maps of {args.size}x{args.size}, seed {args.seed}, one pair per map")
    header = (
        f"{'strategy':<12}"
        + "".join(f"{k:>9}" for k in LABEL_STRENGTH)
        + f"{'success':>9}{'calls/succ':>11}{'seconds':>9}{'plans/s':>9}"
    )
    print(header)
    print(f"{'paper':<12}" + "".join(f"{'' if v is None else f'{v:,}':>9}" for v in PAPER.values()) + f"{'36.7%':>9}")
    for row in rows:
        rate = row["success_rate"]
        per = row["calls_per_success"]
        print(
            f"{row['strategy']:<12}"
            + "".join(f"{v:>9,}" for v in row["counts"].values())
            + f"{'-' if rate is None else f'{rate:.1%}':>9}{'-' if per is None else f'{per:.1f}':>11}"
            + f"{row['seconds']:>9.1f}{row['plans_per_second']:>9,.0f}"
        )
    base = next((r for r in rows if r["strategy"] == "near-path"), None)
    if base and base["success_rate"]:
        for row in rows:
            if row["strategy"] != "near-path" and row["success_rate"] is not None:
                print(f"{row['strategy']} / near-path success rate: {row['success_rate'] / base['success_rate']:.2f}x")


if __name__ == "__main__":
    main()
