"""`vinadv run` (the main job) and `vinadv identify` (label a pairs file and store it)."""

from __future__ import annotations

import argparse
import time

from vinadv.commands import (
    LazyChoices,
    add_cluster_arguments,
    add_corner_cutting_argument,
    add_db_argument,
    add_moves_argument,
    add_planner_arguments,
    check_db_and_report,
    db_file,
    open_args_executor,
    option_values,
    planner_device,
    planner_inputs,
)
from vinadv.commands.attack import (
    add_attack_arguments,
    add_harm_arguments,
    add_objective_argument,
    print_counts,
)
from vinadv.commands.output import add_output_options, emit, shows_progress
from vinadv.errors import InputError


def register(subparsers) -> None:
    run = subparsers.add_parser("run", help="the main job: maps -> attack -> identify -> store (-> report)")
    add_maps_arguments(run, n=5000, instead="generating them", record="the run records")
    run.add_argument(
        "--attack",
        default="near-path",
        choices=LazyChoices("vinadv.attacks.strategies", "STRATEGIES"),
        metavar="STRATEGY",
        help="attack strategy: %(choices)s (default near-path)",
    )
    add_attack_arguments(run)
    add_corner_cutting_argument(run)
    add_moves_argument(
        run, default=None, what="movement model of the generated maps (the planner plans it; with --maps, the file's)"
    )
    run.add_argument("--shard-size", type=int, default=1000, help="maps per shard (default 1000)")
    add_classifier_argument(run)
    add_planner_arguments(run)
    add_harm_arguments(run)
    add_objective_argument(run)
    add_db_argument(run)
    run.add_argument("--name", help="run name (needed to --resume)")
    run.add_argument(
        "--resume",
        action="store_true",
        help="continue the latest run called --name, with the settings it was made with (options given must agree)",
    )
    run.add_argument(
        "--report",
        metavar="DIR",
        help="also write the HTML report of the run to DIR, with the "
        "classifier comparison (tables 5, 6, figs. 8, 9; both settings, a quick profile) run first",
    )
    run.add_argument(
        "--no-evaluate",
        action="store_true",
        help="with --report: skip the classifier comparison (a shorter report, without tables 5, 6 and figs. 8, 9)",
    )
    add_output_options(run, json="the summary", quiet=True)
    add_cluster_arguments(run)
    # the run's settings are None unless given (`RunConfig` holds their defaults, as the help says): --resume takes
    # the stored ones for the options not given
    run.set_defaults(func=cmd_run, **dict.fromkeys(RUN_OPTIONS))

    ident = subparsers.add_parser("identify", help="label the pairs of a pairs file and store them as a run")
    ident.add_argument("--pairs", required=True, help="pairs file (.npz from `vinadv attack`)")
    add_db_argument(ident)
    add_classifier_argument(ident)
    add_planner_arguments(ident, weights_help="weights file of the vin or gppn planner, or a model zoo name")
    ident.epilog = (
        "With --planner or --weights, both maps of every pair are planned again by that planner (the "
        "attacks of the file, tried on another planner: transfer); without, the file's paths are kept."
    )
    add_harm_arguments(ident)
    ident.add_argument("--name", help="run name")
    add_output_options(ident, json="the summary", quiet=True)
    add_cluster_arguments(ident, shard_size=True)
    ident.set_defaults(func=cmd_identify)


#: the options of `vinadv run` that are settings of `RunConfig` under their own name, besides the maps' and planner's
RUN_OPTIONS = (
    "attack",
    "per_map",
    "seed",
    "budget",
    "radius",
    "obstacles",
    "edit",
    "shard_size",
    "classifier",
    "weights",
    "harm_tolerance",
    "harm_rtol",
    "objective",
    "no_corner_cutting",
)


def add_classifier_argument(parser) -> None:
    """`--classifier`: what labels the pairs of `run` and `identify` (`vinadv.identify`)."""
    parser.add_argument("--classifier", help="'rule' (default) or a model file from `vinadv classify train`")


def cmd_run(args: argparse.Namespace) -> int:
    from vinadv.pipeline import RunConfig, resumed_config, run  # scikit-learn behind it: for this command only

    if args.no_evaluate and not args.report:
        raise InputError("--no-evaluate: only with --report DIR")
    inputs = {"--maps": args.maps, "--classifier": args.classifier, **planner_inputs(args)}
    check_db_and_report(db_file(args.db), inputs, args.report)  # before the work: no input overwritten
    device = planner_device(args)
    settings = run_settings(args)
    if args.resume and args.name:  # the stored settings, with the options given (the run refuses any that differs)
        config = resumed_config(args.db, args.name, **settings)
    else:  # RunConfig's defaults for the options not given (without --name, --resume is refused by `run`)
        config = RunConfig(**settings)
    with open_args_executor(args) as executor:
        summary = run(
            config,
            executor,
            **option_values(args, "db", "name", "resume"),
            progress=shows_progress(args),
            device=device,
        )
    result = summary.to_dict()
    if args.report:
        from vinadv.evaluation import evaluate_for_report  # noqa: PLC0415 (its stage is heavy: only with --report)
        from vinadv.report import build_report
        from vinadv.store import Store

        t0 = time.perf_counter()
        # the evaluation stage (the quick classifier comparison unless --no-evaluate, the planner's quality, the
        # processing times), stored; then the report, which reads them
        with Store.open(args.db, create=False) as store:
            reason = evaluate_for_report(
                store, summary.run_id, compare=not args.no_evaluate, progress=shows_progress(args)
            )
        build_report(args.db, args.report, run_id=summary.run_id)
        result["report"] = args.report
        result["comparison"] = reason or "stored"
        result["seconds"]["report"] = round(time.perf_counter() - t0, 3)
    return emit(args, result, lambda: _print_run(result))


def run_settings(args: argparse.Namespace) -> dict:
    """The `RunConfig` settings of the options of `vinadv run` that were given (`RUN_OPTIONS`, `--planner` and the
    maps': with `--maps FILE`, the file's, its `n` only with `--n` when resuming a named run)."""
    given = {name: value for name, value in option_values(args, *RUN_OPTIONS, "planner").items() if value is not None}
    if given.pop("no_corner_cutting", False):
        given["corner_cutting"] = False
    if args.maps is not None:
        maps = maps_settings(args)  # the file's size, corner cutting and moves (refuses those options), all its maps
        if args.n is None and args.resume and args.name:
            del maps["n"]  # the run's
        return {**given, **maps}
    maps = {"n": args.n, "size": args.size, "moves": args.moves}
    return {**given, **{name: value for name, value in maps.items() if value is not None}}


def add_maps_arguments(parser, n: int, instead: str, record: str) -> None:
    """`--n`, `--size` and `--maps FILE` (a maps file's maps `instead` of the generated ones; what `record`s its path
    and SHA-256): the maps of `run` and `robustness`, read by `maps_settings`."""
    parser.add_argument("--n", type=int, default=None, help=f"maps (default {n}; with --maps, the file's first N: all)")
    parser.add_argument("--size", type=int, default=None, help="map side N (default 28; with --maps, the file's)")
    parser.add_argument(
        "--maps",
        metavar="FILE",
        help=f"the maps of this maps file (first start of each; an import, say) instead of {instead}: its size and "
        f"corner cutting are used, and {record} its path and SHA-256",
    )


def maps_settings(args: argparse.Namespace, n: int = 5000, size: int = 28) -> dict:
    """The maps of `run` or `robustness` as `RunConfig` settings: `--n`, `--size`, the corner-cutting rule and the
    movement model (`--moves`, default octile) of generated maps (defaults `n`, `size`), or with `--maps FILE` the
    file's (`pipeline.maps_file_config`, which reads and checks it): then `--size`, `--no-corner-cutting` and
    `--moves` are the file's to say, and refused."""
    if args.maps is None:
        return {
            "n": n if args.n is None else args.n,
            "size": size if args.size is None else args.size,
            "corner_cutting": not getattr(args, "no_corner_cutting", False),
            "moves": args.moves or "octile",
        }
    from vinadv.pipeline import maps_file_config

    for flag_name, given in (
        ("--size", args.size is not None),
        ("--no-corner-cutting", getattr(args, "no_corner_cutting", False)),
        ("--moves", args.moves is not None),
    ):
        if given:
            raise InputError(f"{flag_name}: with --maps the maps file says it ({args.maps})")
    return maps_file_config(args.maps, args.n)


def _print_run(result: dict) -> None:
    from vinadv.pipeline import STAGES

    print(
        f"run {result['run_id']} ({result['name'] or 'unnamed'}) in {result['db']}: {result['pairs']:,} pairs from "
        f"{result['maps']:,} maps on planner {result['planner']['name']}, {result['stored']:,} stored"
    )
    if result["skipped_shards"]:
        print(f"resumed: {result['skipped_shards']} complete shards skipped")
    if result["maps_without_valid_cell"]:
        print(f"{result['maps_without_valid_cell']} maps had no valid cell for an added obstacle")
    print_counts(result)
    seconds = result["seconds"]
    print(
        "time per stage: "
        + ", ".join(f"{s} {seconds[s]:.2f} s" for s in (*STAGES, "report") if s in seconds)
        + f"; wall {result['wall_seconds']:.2f} s"
    )
    if "report" in result:
        print(
            f"report: {result['report']}/index.html"
            + (
                ""
                if result["comparison"] in ("stored", "skipped")
                else f" (no classifier comparison: {result['comparison']})"
            )
        )


def cmd_identify(args: argparse.Namespace) -> int:
    from vinadv.identify import IdentifyConfig, run  # scikit-learn behind it: imported for this command only

    inputs = {"--pairs": args.pairs, "--classifier": args.classifier, **planner_inputs(args)}
    check_db_and_report(db_file(args.db), inputs)  # before the work: the database is no input
    config = IdentifyConfig(
        **option_values(args, "pairs", "classifier", "planner", "weights", "harm_tolerance", "harm_rtol", "shard_size")
    )
    device = planner_device(args)
    with open_args_executor(args) as executor:
        done = run(config, executor, db=args.db, name=args.name, device=device)
    summary = done.to_dict()

    def report() -> None:
        print(
            f"run {done.run_id}: {summary['pairs']:,} pairs identified in {done.seconds:.2f} s; "
            f"{summary['adversarial']:,} successful attacks (D_adversarial)"
        )
        print_counts(summary)

    return emit(args, summary, report)
