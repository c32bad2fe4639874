"""`vinadv plan`: plan a path from every start of every map with the VIN (the fast batched engine)."""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from vinadv.errors import InputError
from vinadv.grid import MapSet
from vinadv.planners.engine import DEFAULT_CHUNK, plan_maps
from vinadv.planners.pathset import PathSet


def register(subparsers) -> None:
    p = subparsers.add_parser("plan", help="plan VIN paths from every start of every map")
    p.add_argument("--maps", required=True, help="maps file (.npz, from `vinadv maps generate`)")
    p.add_argument("--out", required=True, help="output paths file (.npz, format vinadv.paths/1)")
    p.add_argument("--weights", default=None, help="VIN weights file (default: the shipped weights for the map size)")
    p.add_argument("--chunk-size", type=int, default=DEFAULT_CHUNK,
                   help=f"maps per batch; bounds memory (default {DEFAULT_CHUNK})")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.add_argument("--quiet", action="store_true", help="print nothing, no progress bar")
    p.set_defaults(func=cmd_plan)


def cmd_plan(args: argparse.Namespace) -> int:
    from vinadv.planners.weights import load_vin, weights_checksum, default_weights_path
    from vinadv.vocabulary import TERMINATIONS

    if args.chunk_size < 1:
        raise InputError(f"--chunk-size must be >= 1, got {args.chunk_size}")
    maps = MapSet.load(args.maps)
    model = load_vin(args.weights, size=maps.size)
    weights_file = args.weights if args.weights is not None else default_weights_path(maps.size)
    t0 = time.perf_counter()
    result = plan_maps(maps.obstacles, maps.goals, maps.starts, model, maps.corner_cutting, args.chunk_size,
                       progress=not (args.quiet or args.json))
    elapsed = time.perf_counter() - t0
    PathSet.from_result(result, maps.n_starts, maps.size, maps.corner_cutting,
                        model=f"vin k={model.config.k} sha256={weights_checksum(weights_file)}").save(args.out)
    counts = np.bincount(result.termination, minlength=4)
    summary = {
        "out": args.out, "maps": len(maps), "starts": maps.n_starts, "paths": len(result),
        "reached": round(float(result.reached.mean()), 4) if len(result) else None,
        "terminations": dict(zip(TERMINATIONS, counts.tolist())),
        "seconds": round(elapsed, 3), "plans_per_s": round(len(result) / elapsed, 1) if elapsed > 0 else None,
    }
    if args.json:
        print(json.dumps(summary))
    elif not args.quiet:
        print(f"planned {len(result)} paths on {len(maps)} maps in {elapsed:.2f} s "
              f"({summary['plans_per_s']} plans/s); reached {summary['reached']:.1%}; wrote {args.out}")
    return 0
