"""Check that `plan_batch` gives the reference planner's paths and terminations, map for map.

    nice .venv/bin/python perf/identical_paths.py --n 1000 --size 28 [--weights W] [--json]

Weight sets: `planning_vin` (hand-set planning VIN plus 30% random noise), PyTorch's default random
initialisation, and the shipped weights for the size when they exist (or --weights). The reference re-runs the
full float32 PyTorch VIN at every step (slow: minutes for 1,000 maps at 28x28). Also reports how many cells of
the engine's action maps differ from torch's batched `action_logits` argmax and how many were left undecided.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import torch

from vinadv.grid import generate_maps
from vinadv.planners.vin import make_input
from vinadv.planners.vin.engine import action_maps, plan_maps
from vinadv.planners.vin.reference import plan_reference
from vinadv.planners.vin.weights import load_vin
from vinadv.testing.planners import planning_vin, random_vin
from vinadv.vocabulary import TERMINATIONS


def weight_sets(size: int, weights: str | None) -> dict:
    sets = {"planning_vin(seed=0)": planning_vin(size, seed=0), "default_init(seed=0)": random_vin(size, seed=0)}
    try:
        sets["shipped" if weights is None else weights] = load_vin(weights, size=size)
    except Exception as exc:  # no shipped weights yet: say so and go on
        print(f"(no trained weights: {exc})")
    return sets


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--size", type=int, default=28)
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--weights", default=None)
    ap.add_argument(
        "--torch-threads",
        type=int,
        default=1,
        help="torch threads for reference and engine alike (torch's float32 results depend on it)",
    )
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    torch.set_num_threads(args.torch_threads)
    maps = generate_maps(args.n, args.size, args.seed, n_starts=1)
    rows = []
    for name, model in weight_sets(args.size, args.weights).items():
        stats: dict = {}
        fast = plan_maps(maps.obstacles, maps.goals, maps.starts, model, maps.corner_cutting, stats=stats)
        t0 = time.perf_counter()
        ref = plan_reference(maps.obstacles, maps.starts[:, 0], maps.goals, model, maps.corner_cutting)
        ref_s = time.perf_counter() - t0
        same_path = [np.array_equal(a, b) for a, b in zip(fast.paths.unpack(), ref.paths.unpack())]
        actions = action_maps(model, maps.obstacles, maps.goals)
        with torch.no_grad():
            torch_actions = model.action_logits(make_input(maps.obstacles, maps.goals)).argmax(-1).numpy()
        decided = actions >= 0
        rows.append(
            {
                "weights": name,
                "maps": args.n,
                "size": args.size,
                "identical_paths": int(np.sum(same_path)),
                "identical_terminations": int(np.sum(fast.termination == ref.termination)),
                "terminations": dict(zip(TERMINATIONS, np.bincount(ref.termination, minlength=4).tolist())),
                "mean_moves": round(float(ref.paths.lengths.mean() - 1), 2),
                "action_cells": int(actions.size),
                "undecided_cells": int((~decided).sum()),
                "decided_cells_differing_from_torch_argmax": int((actions[decided] != torch_actions[decided]).sum()),
                "near_tie_rollouts": int(stats.get("near_tie_rollouts", 0)),
                "near_tie_maps": int(stats.get("near_tie_maps", 0)),
                "reference_seconds": round(ref_s, 1),
            }
        )
        if not args.json:
            print(rows[-1], flush=True)
    if args.json:
        print(json.dumps(rows))


if __name__ == "__main__":
    main()
