"""`vinadv planners` (the registry) and `vinadv eval` (any planner, both conventions)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from vinadv.commands import add_planner_arguments, command_line
from vinadv.commands.evaluation import add_eval_arguments, by_length_text, start_eval, write_figures
from vinadv.commands.output import add_output_options, emit, shows_progress


def register(subparsers) -> None:
    p = subparsers.add_parser("planners", help="list the planners (--planner NAME) and how to bring your own")
    p.add_argument("--size", type=int, default=28, help="map side whose shipped weights to look for (default 28)")
    add_output_options(p, json="the list")
    p.set_defaults(func=cmd_planners)

    ev = subparsers.add_parser(
        "eval",
        help="any planner's figures in both conventions: vinadv's rollouts and GPPN's %%Opt/%%Suc over every free cell",
    )
    add_planner_arguments(ev)
    add_eval_arguments(ev)
    ev.set_defaults(func=cmd_eval)


def cmd_planners(args: argparse.Namespace) -> int:
    from vinadv.planners.registry import SUFFIX, list_planners

    planners = list_planners(args.size)
    listing = {
        "planners": planners,
        "bring_your_own": "FILE.py:FACTORY or MODULE:FACTORY",
        "symmetric": f"NAME{SUFFIX} or SPEC{SUFFIX}: the planner averaged over the 8 rotations and flips",
    }

    def text() -> None:
        for p in planners:
            weights = (
                ""
                if p["weights"] is None
                else (f"  [weights {Path(p['weights']).name}{'' if p['weights_available'] else ' not shipped'}]")
            )
            print(f"{p['name']:<11} {p['description']}{weights}")
        print(
            "your own: --planner FILE.py:FACTORY or MODULE:FACTORY, FACTORY(size) -> torch.nn.Module with "
            "forward(obstacles (B,N,N) float 0/1, goals (B,2) int64) -> (B,8,N,N) logits (docs/own-planner.md)"
        )
        print(
            f"symmetric:  any of these but optimal with {SUFFIX} (gppn{SUFFIX}): averaged over the 8 rotations and "
            "flips of the map, 8 forwards"
        )

    return emit(args, listing, text)


def cmd_eval(args: argparse.Namespace) -> int:
    from vinadv.interop.protocols import gppn_protocol
    from vinadv.planners.evaluation import evaluate_planner
    from vinadv.planners.registry import load_planner

    maps, source = start_eval(args)
    planner = load_planner(
        args.planner, maps.size, weights=args.weights, corner_cutting=maps.corner_cutting, moves=maps.moves
    )
    t0 = time.perf_counter()
    ours = evaluate_planner(planner, maps, progress=shows_progress(args))
    t1 = time.perf_counter()
    theirs = gppn_protocol(planner, maps)
    metrics = {
        "planner": planner.spec(),
        "weights": args.weights or "shipped",
        **source,
        "vinadv": ours,
        "gppn": theirs,
        "seconds": {"vinadv": round(t1 - t0, 2), "gppn": round(time.perf_counter() - t1, 2)},
        "command": command_line(),
    }
    write_figures(args, metrics)

    def text() -> None:
        print(f"planner {planner.name}: {ours['maps']} maps of {ours['size']}x{ours['size']}")
        print(
            f"  vinadv: rollout success {ours['success_rate']:.2%} of {ours['rollouts']} rollouts, optimal paths "
            f"{ours['optimal_rate']:.2%}, action accuracy {ours['action_accuracy']:.2%}"
        )
        print(
            f"  gppn:   %Suc {theirs['percent_success']:.2%}, %Opt {theirs['percent_optimal']:.2%} over "
            f"{theirs['cells']} free cells (every {'NEWS' if maps.moves == 'news' else 'Moore'} move costs 1)"
        )
        print(by_length_text(ours))

    return emit(args, metrics, text)
