"""The exhaustive attack against planning its candidate maps alone: what the attack adds to the planner's own time.

    .venv/bin/python perf/exhaustive.py [--n 1000] [--size 28] [--planner vin] [--rounds 2] [--json]

On `--n` generated maps (one start each), side by side in this run, taking turns, best of `--rounds`:
- `attack`: `make_attack("exhaustive").attack(...)` with the harm ranking `vinadv robustness` uses (every valid
  cell of every map: the original maps planned, every candidate map built, planned, paired, labelled, ranked);
- `plan_batch`: the same candidate maps (every valid cell of every map added in turn) planned with
  `planner.plan` in chunks of the attack's `EVAL_CHUNK`, nothing else.
Goal (issue 19): the attack at most 1.3x `plan_batch`.
"""

from __future__ import annotations

import argparse

import numpy as np

from common import add_maps_arguments, add_output_arguments, print_figures, timed_side_by_side  # perf/common.py
from vinadv.attacks.strategies import EVAL_CHUNK, make_attack
from vinadv.attacks.validity import valid_cells
from vinadv.grid import generate_maps
from vinadv.identify import harm_strength
from vinadv.planners.registry import load_planner


def plan_candidates(planner, obstacles, starts, goals) -> int:
    """Plan every candidate map (each valid cell of each map added) in chunks; the number of plans."""
    maps, rows, cols = np.nonzero(valid_cells(obstacles, starts, goals, True))
    for lo in range(0, len(maps), EVAL_CHUNK):
        m = maps[lo : lo + EVAL_CHUNK]
        adversarial = obstacles[m].copy()
        adversarial[np.arange(len(m)), rows[lo : lo + EVAL_CHUNK], cols[lo : lo + EVAL_CHUNK]] = True
        planner.plan(adversarial, starts[m], goals[m], True)
    return len(maps)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_maps_arguments(parser, n=1000, seed=2026, planner="vin")
    add_output_arguments(parser, rounds=2)
    args = parser.parse_args()
    planner = load_planner(args.planner, args.size)
    maps = generate_maps(args.n, args.size, seed=args.seed, n_starts=1)
    obstacles, starts, goals = maps.obstacles, maps.starts[:, 0], maps.goals
    attack = make_attack("exhaustive")
    warm = generate_maps(8, args.size, seed=1, n_starts=1)  # compiles the engine and its checks before timing
    attack.attack(warm.obstacles, warm.starts[:, 0], warm.goals, planner, strength=harm_strength)

    (attack_s, plan_batch_s), (calls, candidates) = timed_side_by_side(
        [
            lambda: attack.attack(obstacles, starts, goals, planner, strength=harm_strength).planner_calls,
            lambda: plan_candidates(planner, obstacles, starts, goals),
        ],
        args.rounds,
    )
    row = {
        "planner": args.planner,
        "maps": args.n,
        "candidates": candidates,
        "attack_planner_calls": calls,
        "attack_s": attack_s,
        "plan_batch_s": plan_batch_s,
        "ratio": attack_s / plan_batch_s,
        "plans_per_second": candidates / plan_batch_s,
    }
    print_figures(row, args.json, describe(row, args.size, args.rounds))


def describe(row: dict, size: int, rounds: int) -> list[str]:
    """The figures in words: the maps, both times and their ratio beside the goal."""
    return [
        f"{row['maps']} maps of {size}x{size}, planner {row['planner']}: {row['candidates']:,} candidate maps "
        f"({row['attack_planner_calls']:,} planner calls in the attack, the original maps included), "
        f"best of {rounds}",
        f"  exhaustive attack {row['attack_s']:8.2f} s",
        f"  plan_batch alone  {row['plan_batch_s']:8.2f} s  ({row['plans_per_second']:,.0f} plans/s)",
        f"  ratio {row['ratio']:.2f}x (goal: at most 1.3x)",
    ]


if __name__ == "__main__":
    main()
