"""The exhaustive attack with its candidates judged in chunks of `EVAL_CHUNK` (1024: the progress bar moves about
once a map) against chunks of 8192 (before issue 46), side by side: the same pairs, and the time each takes.

    .venv/bin/python perf/eval_chunk.py [--n 60] [--size 28] [--planner vin] [--moves octile] [--rounds 2] [--json]

On `--n` generated maps (one start each), taking turns, best of `--rounds`: `make_attack("exhaustive").attack(...)`
with the harm ranking `vinadv robustness` uses, once per chunk size. Goal: the ratio (1024 over 8192) near 1, and
the pairs equal (the planners give a map the same plan in whatever batch it lands).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from common import add_maps_arguments, add_output_arguments, timed_side_by_side  # perf/common.py
from vinadv.attacks import strategies
from vinadv.grid import generate_maps
from vinadv.identify import harm_strength
from vinadv.planners.registry import load_planner_for

BEFORE = 8192


def attack_with(chunk: int, attack, maps, planner):
    """The attack's pairs with `EVAL_CHUNK` set to `chunk` for the call."""
    saved, strategies.EVAL_CHUNK = strategies.EVAL_CHUNK, chunk
    try:
        return attack.attack(maps.obstacles, maps.starts[:, 0], maps.goals, planner, strength=harm_strength).pairs
    finally:
        strategies.EVAL_CHUNK = saved


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_maps_arguments(parser, n=60, seed=2026, planner="vin")
    parser.add_argument("--moves", default="octile", help="the maps' movement model (neural-astar: moore)")
    add_output_arguments(parser, rounds=2)
    args = parser.parse_args()
    maps = generate_maps(args.n, args.size, seed=args.seed, n_starts=1, moves=args.moves)
    planner = load_planner_for(args.planner, None, maps)
    attack = strategies.make_attack("exhaustive")
    now = strategies.EVAL_CHUNK
    warm = generate_maps(4, args.size, seed=1, n_starts=1, moves=args.moves)
    attack_with(now, attack, warm, planner)  # compiles the engine and its checks before timing
    (now_s, before_s), (now_pairs, before_pairs) = timed_side_by_side(
        [lambda: attack_with(now, attack, maps, planner), lambda: attack_with(BEFORE, attack, maps, planner)],
        args.rounds,
    )
    arrays = ("map_index", "added", "obstacles_a", "term_a")
    same = all(np.array_equal(getattr(now_pairs, a), getattr(before_pairs, a)) for a in arrays) and all(
        np.array_equal(getattr(now_pairs.path_a, a), getattr(before_pairs.path_a, a)) for a in ("cells", "offsets")
    )
    row = {
        "planner": args.planner,
        "maps": args.n,
        "size": args.size,
        "eval_chunk": now,
        "eval_chunk_s": now_s,
        "before": BEFORE,
        "before_s": before_s,
        "ratio": now_s / before_s,
        "same_pairs": same,
    }
    if args.json:
        print(json.dumps(row))
        return
    print(
        f"{args.n} maps of {args.size}x{args.size}, planner {args.planner}, exhaustive attack, best of {args.rounds}:\n"
        f"  chunks of {now:>5} candidates {now_s:8.2f} s\n"
        f"  chunks of {BEFORE:>5} candidates {before_s:8.2f} s\n"
        f"  ratio {row['ratio']:.2f}x; the same pairs: {same}"
    )


if __name__ == "__main__":
    main()
