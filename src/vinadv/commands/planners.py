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
        "parameters": "NAME:KEY=VALUE[,KEY=VALUE...] for a planner that lists parameters (wastar:w=3)",
        "symmetric": f"NAME{SUFFIX} or SPEC{SUFFIX}: the planner averaged over the 8 rotations and flips",
    }

    def text() -> None:
        width = max([11, *(len(p["name"]) for p in planners)])  # the names in one column
        for p in planners:
            weights = (
                ""
                if p["weights"] is None
                else (f"  [weights {Path(p['weights']).name}{'' if p['weights_available'] else ' not shipped'}]")
            )
            params = ", ".join(f"{q['name']}={q['default']:g}" for q in p["params"])
            print(f"{p['name']:<{width}} {p['description']}{weights}{f'  [parameters {params}]' if params else ''}")
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
    from vinadv.planners.search import SearchPlanner
    from vinadv.planners.search_metrics import evaluate_search

    maps, source = start_eval(args)
    planner = load_planner(
        args.planner, maps.size, weights=args.weights, corner_cutting=maps.corner_cutting, moves=maps.moves
    )
    # a search planner has no policy: the action accuracy and GPPN's per-cell protocol need one
    policy = not isinstance(planner, SearchPlanner)
    t0 = time.perf_counter()
    ours = evaluate_planner(planner, maps, progress=shows_progress(args)) if policy else None
    t1 = time.perf_counter()
    theirs = gppn_protocol(planner, maps) if policy else None
    t2 = time.perf_counter()
    search = evaluate_search(planner, maps, progress=shows_progress(args))
    metrics = {
        "planner": planner.spec(),
        "weights": args.weights or "shipped",
        **source,
        "vinadv": ours,
        "gppn": theirs,
        "search": search,
        "seconds": {
            "vinadv": round(t1 - t0, 2),
            "gppn": round(t2 - t1, 2),
            "search": round(time.perf_counter() - t2, 2),
        },
        "command": command_line(),
    }
    write_figures(args, metrics)

    def text() -> None:
        if ours is not None:
            print(f"planner {planner.name}: {ours['maps']} maps of {ours['size']}x{ours['size']}")
            print(
                f"  vinadv: rollout success {ours['success_rate']:.2%} of {ours['rollouts']} rollouts, optimal paths "
                f"{ours['optimal_rate']:.2%}, action accuracy {ours['action_accuracy']:.2%}"
            )
            print(
                f"  gppn:   %Suc {theirs['percent_success']:.2%}, %Opt {theirs['percent_optimal']:.2%} over "
                f"{theirs['cells']} free cells (every Moore move costs 1)"
            )
        else:
            print(f"planner {planner.name}: {len(maps)} maps of {maps.size}x{maps.size} ({maps.moves} moves)")
        print(f"  search: {search_text(search)}")
        if ours is not None:
            print(by_length_text(ours))

    return emit(args, metrics, text)


def search_text(m: dict) -> str:
    """The search metrics (`vinadv.planners.search_metrics`) in one line; n/a where undefined."""

    def pct(x):
        return "n/a" if x is None else f"{x:.2%}"

    ratio = "n/a" if m["cost_ratio"] is None else f"{m['cost_ratio']:.4f}"
    return (
        f"Opt {pct(m['opt'])}, Exp {pct(m['exp'])}, Hmean {pct(m['hmean'])}, success {pct(m['success'])}, "
        f"cost ratio {ratio} over {m['rows']} (map, start) rows"
    )
