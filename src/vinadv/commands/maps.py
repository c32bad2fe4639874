"""`vinadv maps generate`, `vinadv maps show`, `vinadv maps concat`, `vinadv maps import` and `vinadv maps export`."""

from __future__ import annotations

import argparse
import time

from vinadv.commands import add_actions, add_corner_cutting_argument, add_moves_argument
from vinadv.commands.output import add_output_options, emit, progress_bar
from vinadv.errors import InputError
from vinadv.outfile import check_output_path


def register(subparsers) -> None:
    sub = add_actions(subparsers, "maps", help="generate and look at grid-world maps")

    gen = sub.add_parser("generate", help="generate random maps with starts, goal and expert paths")
    gen.add_argument("--n", type=int, required=True, help="number of maps")
    gen.add_argument("--size", type=int, default=28, help="map side N (>= 8; default 28)")
    gen.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    gen.add_argument("--starts", type=int, default=7, help="starts per map (default 7)")
    add_corner_cutting_argument(gen)
    add_moves_argument(gen)
    add_maps_out_argument(gen)
    add_output_options(gen, json="the summary", quiet=True)
    gen.set_defaults(func=cmd_generate)

    show = sub.add_parser(
        "show",
        help="draw a map (with its expert paths), a pair of a pairs file or a planned path to an image",
        description="Draw one map of a maps file with its starts, goal and expert paths; one pair of a pairs file "
        "(vinadv attack: both maps, both paths, the edited cells); or one map of a paths file (vinadv plan: the "
        "planned paths, on the maps of --maps). The file's kind is read from it. Colours: vinadv.plot's palette.",
    )
    show.add_argument("maps", metavar="FILE", help="maps, pairs or paths file (.npz)")
    show.add_argument("--index", type=int, default=0, help="map index, or pair index of a pairs file (default 0)")
    show.add_argument("--out", required=True, help="output image (.png, .svg or .pdf)")
    show.add_argument("--all-starts", action="store_true", help="draw the paths of every start (maps, paths files)")
    show.add_argument("--maps", dest="maps_file", metavar="MAPS", help="the maps file a paths file was planned on")
    show.set_defaults(func=cmd_show)

    cat = sub.add_parser(
        "concat",
        help="write the maps of several maps files as one (same size, starts per map, corner cutting and moves)",
    )
    cat.add_argument("maps", nargs="+", metavar="MAPS", help="maps files (.npz), in order")
    add_maps_out_argument(cat)
    add_output_options(cat, json="the summary", quiet=True)
    cat.set_defaults(func=cmd_concat)
    _register_interop(sub)


def add_maps_out_argument(parser) -> None:
    """`--out`: the maps file a command writes (`maps generate`, `maps concat`, `maps import`)."""
    parser.add_argument("--out", required=True, help="output maps file (.npz)")


def cmd_concat(args: argparse.Namespace) -> int:
    from vinadv.grid.mapset import MapSet

    check_output_path(args.out, inputs={"MAPS": args.maps})
    maps = MapSet.concat([MapSet.load(path) for path in args.maps], [str(path) for path in args.maps])
    maps.save(args.out)
    summary = {
        "out": args.out,
        "inputs": [str(path) for path in args.maps],
        "maps": len(maps),
        "size": maps.size,
        "starts": maps.n_starts,
        "corner_cutting": maps.corner_cutting,
        "moves": maps.moves,
        "seed": int(maps.seed),
    }
    return emit(
        args,
        summary,
        f"wrote {len(maps)} maps of {maps.size}x{maps.size} ({maps.moves} moves) from {len(args.maps)} files to "
        f"{args.out}",
    )


def cmd_generate(args: argparse.Namespace) -> int:
    from vinadv.grid import generate_maps, obstacle_fraction

    if args.n < 1:  # a maps file holds at least one map
        raise InputError(f"--n must be >= 1, got {args.n}")
    check_output_path(args.out)  # before the work: a folder in the way or a missing folder
    t0 = time.perf_counter()
    with progress_bar(args, total=args.n, unit="map", desc="maps") as bar:
        maps = generate_maps(
            args.n,
            args.size,
            args.seed,
            args.starts,
            corner_cutting=not args.no_corner_cutting,
            progress=bar.update,
            moves=args.moves,
        )
    elapsed = time.perf_counter() - t0
    maps.save(args.out)
    summary = {
        "out": args.out,
        "maps": len(maps),
        "size": maps.size,
        "starts": maps.n_starts,
        "seed": args.seed,
        "corner_cutting": maps.corner_cutting,
        "moves": maps.moves,
        "obstacle_fraction": round(obstacle_fraction(maps.obstacles), 4),
        "mean_expert_moves": round(float(maps.expert.lengths.mean() - 1), 3) if len(maps) else None,
        "seconds": round(elapsed, 3),
    }
    return emit(
        args,
        summary,
        f"wrote {len(maps)} maps of {maps.size}x{maps.size} ({maps.n_starts} starts each, {maps.moves} moves) to "
        f"{args.out} in {elapsed:.2f} s; obstacles {summary['obstacle_fraction']:.1%}",
    )


def _file_format(path: str) -> str:
    """The `format` entry of a vinadv .npz file ('' where it has none or is no .npz file: the loader then says
    what is wrong)."""
    import numpy as np

    try:
        with np.load(path, allow_pickle=False) as data:
            return str(data["format"]) if "format" in data.files else ""
    except (OSError, ValueError):
        return ""


def cmd_show(args: argparse.Namespace) -> int:
    import matplotlib

    matplotlib.use("Agg")  # no display: the image goes to a file
    import matplotlib.pyplot as plt

    from vinadv.plot.files import figure_format, save_figure
    from vinadv.plot.maps import draw_map, map_legend, pair

    figure_format(args.out)  # before the work: an extension matplotlib cannot write
    inputs = {"FILE": args.maps, **({"--maps": args.maps_file} if args.maps_file else {})}
    check_output_path(args.out, inputs=inputs)
    kind = _file_format(args.maps).partition("/")[0]
    if kind == "vinadv.pairs":
        from vinadv.attacks.pairs import PairSet

        if args.maps_file or args.all_starts:
            raise InputError(f"{args.maps} is a pairs file: --maps and --all-starts are for maps and paths files")
        pairs = PairSet.load(args.maps)
        if not 0 <= args.index < len(pairs):
            raise InputError(f"--index {args.index} is out of range: {args.maps} has {len(pairs)} pairs")
        fig = pair(pairs, args.index, title=f"pair {args.index} ({pairs.strategy}, {pairs.moves})")
        save_figure(fig, args.out)
        print(f"wrote {args.out}")
        return 0
    from vinadv.grid import MapSet

    planned = None
    if kind == "vinadv.paths":
        from vinadv.planners.pathset import PathSet

        if not args.maps_file:
            raise InputError(
                f"{args.maps} is a paths file, which holds no maps: give the maps it was planned on (--maps)"
            )
        planned, maps = PathSet.load(args.maps), MapSet.load(args.maps_file)
        if (len(planned), planned.size) != (len(maps) * maps.n_starts, maps.size):
            raise InputError(
                f"{args.maps} holds {len(planned)} paths on {planned.size}x{planned.size} maps, not one per start of "
                f"the {len(maps)} maps of {args.maps_file} ({maps.n_starts} starts, {maps.size}x{maps.size})"
            )
        source = args.maps_file
    else:
        if args.maps_file:
            raise InputError(f"--maps is for a paths file; {args.maps} is read as a maps file")
        maps, source = MapSet.load(args.maps), args.maps
    if not 0 <= args.index < len(maps):
        raise InputError(f"--index {args.index} is out of range: {source} has {len(maps)} maps")
    starts = list(range(maps.n_starts)) if args.all_starts else [0]
    paths = [("expert", maps.expert_path(args.index, s)) for s in starts]
    costs = maps.expert_costs[args.index, starts]
    if planned is not None:
        paths += [("planned", planned.path(args.index, s)) for s in starts]
        reached = int(planned.reached[[args.index * planned.n_starts + s for s in starts]].sum())
        title = f"map {args.index}: planned paths reaching the goal {reached}/{len(starts)} ({maps.moves})"
    elif len(starts) == 1:
        title = f"map {args.index}: expert cost {costs[0]:.2f} ({maps.moves})"
    else:
        spread = f"{costs.min():.2f}-{costs.max():.2f}"
        title = f"map {args.index}: {len(starts)} starts, expert costs {spread} ({maps.moves})"
    fig, ax = plt.subplots(figsize=(4, 4.4))
    draw_map(
        ax, maps.obstacles[args.index], maps.goals[args.index], maps.starts[args.index, starts], paths, title=title
    )
    map_legend(fig, ax)
    save_figure(fig, args.out)
    print(f"wrote {args.out}")
    return 0


FOREIGN_FORMATS = ("kentsommer", "avivt", "gppn", "mpd", "movingai", "ascii", "png", "transpath")


def _register_interop(sub) -> None:
    imp = sub.add_parser(
        "import",
        help="read maps of the kentsommer PyTorch port, avivt's .mat files, GPPN, the MP dataset (mpd), the Moving "
        "AI benchmarks (movingai), a map drawn in text (ascii) or an image (png), or TransPath's XML tasks (transpath)",
        description="Regroup another codebase's samples into maps and trajectories; expert costs "
        "are vinadv's under the maps' movement model (kentsommer, avivt: octile; gppn: the file's moore or news; "
        "mpd: moore; movingai: octile without corner cutting; ascii, png: --moves, corner cutting unless "
        "--no-corner-cutting; transpath: octile, corner cutting unless --no-corner-cutting). See "
        "docs/guide/interop.md and docs/formats.md.",
    )
    imp.add_argument(
        "input",
        nargs="+",
        metavar="IN",
        help="the file to read (.npz for kentsommer, gppn and mpd, .mat for avivt, .map for movingai, a text file for "
        "ascii, an image for png); transpath: one or more .xml tasks, a task in several files counted once",
    )
    imp.add_argument("--format", required=True, choices=FOREIGN_FORMATS, help="the file's layout")
    add_maps_out_argument(imp)
    imp.add_argument(
        "--split",
        default=None,
        help="kentsommer: train|test|all (default test); gppn: train|valid|test|all (default test); "
        "mpd: train|valid|test (default test); avivt: test|train layout (default: the one the file has)",
    )
    imp.add_argument(
        "--starts",
        type=int,
        default=None,
        help="starts drawn per map where the file has none (gppn: default 7; mpd: default 1, by Neural A*'s rule)",
    )
    imp.add_argument("--seed", type=int, default=0, help="seed of the drawn starts and crops (default 0)")
    imp.add_argument(
        "--scen",
        default=None,
        metavar="FILE",
        help="movingai: the .scen problems (each a map of its own; optimal lengths checked against vinadv's)",
    )
    imp.add_argument(
        "--bucket", default=None, metavar="LIST", help="movingai: keep the .scen problems of these buckets (0-4,7)"
    )
    imp.add_argument(
        "--crop",
        type=int,
        default=None,
        metavar="N",
        help="movingai: cut windows of N x N out of the map, goal and starts drawn in each (docs/formats.md)",
    )
    imp.add_argument("--crops", type=int, default=None, metavar="K", help="movingai: windows drawn (default 1)")
    imp.add_argument(
        "--min-free",
        type=float,
        default=None,
        metavar="F",
        help="movingai: the least share of free cells of a window (default 0.5)",
    )
    imp.add_argument("--start", default=None, metavar="ROW,COL", help="png: the start cell (an image draws none)")
    imp.add_argument("--goal", default=None, metavar="ROW,COL", help="png: the goal cell")
    imp.add_argument(
        "--pad-to",
        type=int,
        default=None,
        metavar="N",
        help="ascii, png, transpath: pad the map with obstacles into an N x N map (default: a square of its larger "
        "side)",
    )
    add_corner_cutting_argument(imp)
    add_moves_argument(
        imp,
        default=None,
        what="movement model of the maps (default: the file's; gppn: moore for 8 actions, news for 4, or octile "
        "for an 8-action file to get sqrt 2 expert costs)",
    )
    add_output_options(imp, json="the summary", quiet=True)
    imp.set_defaults(func=cmd_import)

    exp = sub.add_parser(
        "export",
        help="write a maps file in the kentsommer, avivt, GPPN, MP dataset (mpd) or Moving AI (movingai) layout",
    )
    exp.add_argument("maps", help="maps file (.npz)")
    exp.add_argument("--format", required=True, choices=FOREIGN_FORMATS, help="the layout to write")
    exp.add_argument(
        "--out",
        required=True,
        help="output file (.npz for kentsommer, gppn and mpd, .mat for avivt; movingai: the .scen, its .map beside)",
    )
    exp.add_argument(
        "--split",
        default=None,
        help="kentsommer: train|test; gppn, mpd: train|valid|test; avivt: test|train layout (default test); movingai: "
        "none",
    )
    add_output_options(exp, json="the summary")
    exp.set_defaults(func=cmd_export)


def cmd_import(args: argparse.Namespace) -> int:
    from vinadv.interop.formats import read_maps

    if args.starts is not None and args.starts < 1:
        raise InputError(f"--starts must be >= 1, got {args.starts}")
    if len(args.input) > 1 and args.format != "transpath":
        raise InputError(f"format {args.format} reads one file, got {len(args.input)} (IN): give one")
    inputs = {f"IN {i}" if i else "IN": p for i, p in enumerate(args.input)}
    check_output_path(args.out, inputs={**inputs, "--scen": args.scen})  # before the work
    options = {
        "scen": args.scen,
        "bucket": args.bucket,
        "crop": args.crop,
        "crops": args.crops,
        "min_free": args.min_free,
        "corner_cutting": False if args.no_corner_cutting else None,
        "start": args.start,
        "goal": args.goal,
        "pad_to": args.pad_to,
    }
    source = args.input if args.format == "transpath" else args.input[0]
    maps, info = read_maps(
        source, args.format, split=args.split, starts=args.starts, seed=args.seed, moves=args.moves, **options
    )
    if len(maps) == 0:  # a maps file holds at least one map (`MapSet.save`): say so of the file read
        split = args.split or info.get("split")
        raise InputError(f"{args.input[0]}: no maps to import{f' (split {split})' if split else ''}")
    maps.save(args.out)
    info = {"out": args.out, **info}

    def text() -> None:
        padded = f", {info['maps_padded']} with fewer starts (padded, see start_counts)" if info["maps_padded"] else ""
        print(
            f"wrote {info['maps']} maps of {info['size']}x{info['size']} (up to {info['starts_per_map']} starts"
            f"{padded}) to {args.out}; expert paths: {info['expert_paths']}"
        )
        for key in (
            "moves",
            "file_paths_optimal",
            "movement",
            "starts_rule",
            "maps_left_out_no_start",
            "lengths_checked",
            "tasks_counted_once",
        ):
            if info.get(key):
                print(f"  {key.replace('_', ' ')}: {info[key]}")
        if any(info.get("padding", {}).values()):
            pad = info["padding"]
            print(f"  padded with obstacles: {pad['rows']} rows below, {pad['cols']} columns to the right")

    return emit(args, info, text)


def cmd_export(args: argparse.Namespace) -> int:
    from vinadv.grid import MapSet
    from vinadv.interop.formats import export_maps

    check_output_path(args.out, mkdir=True, inputs={"MAPS": args.maps})  # before the maps are read
    maps = MapSet.load(args.maps)
    summary = export_maps(maps, args.out, args.format, split=args.split)
    return emit(args, summary, f"wrote {summary['maps']} maps to {args.out} ({args.format}, {summary['split']})")
