"""`vinadv plan`: plan a path from every start of every map with a planner (default: the VIN and its fast engine)."""

from __future__ import annotations

import argparse
import time

from vinadv.commands import add_planner_arguments, load_args_planner, planner_device, planner_inputs
from vinadv.commands.output import add_output_options, emit, shows_progress
from vinadv.errors import InputError
from vinadv.outfile import check_output_path
from vinadv.planners.batching import DEFAULT_CHUNK


def register(subparsers) -> None:
    p = subparsers.add_parser("plan", help="plan paths from every start of every map (VIN or another planner)")
    p.add_argument("--maps", required=True, help="maps file (.npz, from `vinadv maps generate`)")
    p.add_argument("--out", required=True, help="output paths file (.npz, format vinadv.paths/2)")
    add_planner_arguments(p)
    p.add_argument(
        "--chunk-size", type=int, default=DEFAULT_CHUNK, help=f"maps per batch; bounds memory (default {DEFAULT_CHUNK})"
    )
    add_output_options(p, json="the summary", quiet=True)
    p.set_defaults(func=cmd_plan)


def cmd_plan(args: argparse.Namespace) -> int:
    import numpy as np

    from vinadv.grid import MapSet
    from vinadv.planners.interface import plan_every_start
    from vinadv.planners.pathset import PathSet
    from vinadv.vocabulary import TERMINATIONS

    if args.chunk_size < 1:
        raise InputError(f"--chunk-size must be >= 1, got {args.chunk_size}")
    device = planner_device(args)
    # before the work: a folder in the way, a missing folder, an input (the maps, the planner's files)
    check_output_path(args.out, inputs={"--maps": args.maps, **planner_inputs(args)})
    maps = MapSet.load(args.maps)
    planner = load_args_planner(args, maps, device)
    t0 = time.perf_counter()
    result = plan_every_start(planner, maps, chunk_size=args.chunk_size, progress=shows_progress(args))
    elapsed = time.perf_counter() - t0
    k = planner.config.get("k")
    label = " ".join(
        [planner.name]
        + ([f"k={k}"] if k is not None else [])
        + ([f"sha256={planner.checksum}"] if planner.checksum else [])
    )
    PathSet.from_result(result, maps.n_starts, maps.size, maps.corner_cutting, model=label, moves=maps.moves).save(
        args.out
    )
    counts = np.bincount(result.termination, minlength=4)
    summary = {
        "out": args.out,
        "planner": planner.spec(),
        "maps": len(maps),
        "starts": maps.n_starts,
        "paths": len(result),
        "reached": round(float(result.reached.mean()), 4) if len(result) else None,
        "terminations": dict(zip(TERMINATIONS, counts.tolist())),
        "seconds": round(elapsed, 3),
        "plans_per_s": round(len(result) / elapsed, 1) if elapsed > 0 else None,
    }
    return emit(
        args,
        summary,
        f"planned {len(result)} paths on {len(maps)} maps in {elapsed:.2f} s "
        f"({summary['plans_per_s']} plans/s); reached {summary['reached']:.1%}; wrote {args.out}",
    )
