"""`vinadv maps generate` and `vinadv maps show`."""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from vinadv.errors import InputError


def register(subparsers) -> None:
    maps = subparsers.add_parser("maps", help="generate and look at grid-world maps")
    sub = maps.add_subparsers(dest="maps_command", metavar="ACTION")
    sub.required = True

    gen = sub.add_parser("generate", help="generate random maps with starts, goal and expert paths")
    gen.add_argument("--n", type=int, required=True, help="number of maps")
    gen.add_argument("--size", type=int, default=28, help="map side N (>= 8; default 28)")
    gen.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    gen.add_argument("--starts", type=int, default=7, help="starts per map (default 7)")
    gen.add_argument("--no-corner-cutting", action="store_true",
                     help="forbid diagonal moves between two obstacles (default: allowed, as in the original data)")
    gen.add_argument("--out", required=True, help="output maps file (.npz)")
    gen.add_argument("--json", action="store_true", help="print a JSON summary")
    gen.add_argument("--quiet", action="store_true", help="print nothing")
    gen.set_defaults(func=cmd_generate)

    show = sub.add_parser("show", help="draw one map with its starts, goal and expert paths to an image")
    show.add_argument("maps", help="maps file (.npz)")
    show.add_argument("--index", type=int, default=0, help="map index (default 0)")
    show.add_argument("--out", required=True, help="output image (.png, .svg or .pdf)")
    show.add_argument("--all-starts", action="store_true", help="draw the expert paths of every start")
    show.set_defaults(func=cmd_show)


def cmd_generate(args: argparse.Namespace) -> int:
    from vinadv.grid import generate_maps, obstacle_fraction

    t0 = time.perf_counter()
    maps = generate_maps(args.n, args.size, args.seed, args.starts, corner_cutting=not args.no_corner_cutting)
    elapsed = time.perf_counter() - t0
    maps.save(args.out)
    summary = {
        "out": args.out, "maps": len(maps), "size": maps.size, "starts": maps.n_starts, "seed": args.seed,
        "corner_cutting": maps.corner_cutting, "obstacle_fraction": round(obstacle_fraction(maps.obstacles), 4),
        "mean_expert_moves": round(float(np.diff(maps.expert_offsets).mean() - 1), 3) if len(maps) else None,
        "seconds": round(elapsed, 3),
    }
    if args.json:
        print(json.dumps(summary))
    elif not args.quiet:
        print(f"wrote {len(maps)} maps of {maps.size}x{maps.size} ({maps.n_starts} starts each) to {args.out} "
              f"in {elapsed:.2f} s; obstacles {summary['obstacle_fraction']:.1%}")
    return 0


def cmd_show(args: argparse.Namespace) -> int:
    import matplotlib.pyplot as plt

    from vinadv.grid import MapSet
    from vinadv.grid.draw import draw_map, save_figure

    maps = MapSet.load(args.maps)
    if not 0 <= args.index < len(maps):
        raise InputError(f"--index {args.index} is out of range: {args.maps} has {len(maps)} maps")
    starts = range(maps.n_starts) if args.all_starts else [0]
    paths = [("expert", maps.expert_path(args.index, s)) for s in starts]
    fig, ax = plt.subplots(figsize=(4, 4))
    cost = maps.expert_costs[args.index, 0]
    draw_map(ax, maps.obstacles[args.index], maps.goals[args.index], maps.starts[args.index, 0], paths,
             title=f"map {args.index}: expert cost {cost:.2f}")
    save_figure(fig, args.out)
    print(f"wrote {args.out}")
    return 0
