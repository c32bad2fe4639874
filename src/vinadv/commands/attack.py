"""`vinadv attack`: adversarial maps (one added obstacle, or K added greedily) from a maps file."""

from __future__ import annotations

import argparse
import time

from vinadv.cluster import add_cluster_arguments, attack_on_cluster, open_cluster
from vinadv.commands import LazyChoices, add_planner_arguments, load_args_planner, option_values, planner_device
from vinadv.commands.output import add_output_options, emit, shows_progress
from vinadv.outfile import check_output_path


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "attack",
        help="make adversarial maps (one obstacle added or removed, or --obstacles K) from a maps file, on any planner",
    )
    p.add_argument("--maps", required=True, help="maps file (.npz from `vinadv maps generate`)")
    p.add_argument(
        "--strategy",
        required=True,
        choices=LazyChoices("vinadv.attacks.strategies", "STRATEGIES"),
        metavar="STRATEGY",
        help="attack strategy: %(choices)s",
    )
    p.add_argument("--out", required=True, help="output pairs file (.npz)")
    add_attack_arguments(p)
    add_planner_arguments(p)
    add_harm_arguments(p)
    add_objective_argument(p)
    add_output_options(p, json="the summary", quiet=True)
    add_cluster_arguments(p, shard_size=True)
    p.set_defaults(func=cmd_attack)


def add_attack_arguments(parser) -> None:
    """The options of the attack itself (`make_attack`'s, read by `attack_options`) that `attack` and `run` share:
    `--per-map`, `--seed`, `--budget`, `--radius`, `--obstacles K` (added greedily: DESIGN.md "Several obstacles")
    and `--edit`."""
    parser.add_argument(
        "--per-map", type=int, default=1, help="pairs per map (default 1; 0 with exhaustive: every valid cell)"
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument(
        "--budget", type=int, default=8, help="key-points and saliency: candidates evaluated per map (default 8)"
    )
    parser.add_argument("--radius", type=int, default=2, help="near-path: Chebyshev distance to the path (default 2)")
    parser.add_argument(
        "--obstacles",
        type=int,
        default=1,
        metavar="K",
        help="obstacles added per pair (default 1, the paper's setting); K > 1: greedily, the "
        "strategy run again on the map with the cells chosen so far, keeping the strongest cell "
        "against the original map's path each time",
    )
    add_edit_argument(parser)


def attack_options(args: argparse.Namespace) -> dict:
    """The options of `add_attack_arguments` as `make_attack`'s (and `RunConfig`'s) keyword arguments."""
    return option_values(args, "per_map", "seed", "budget", "radius", "obstacles", "edit")


def add_edit_argument(parser) -> None:
    """`--edit add|remove`: whether the attack adds obstacles or frees them (DESIGN.md "Obstacle removal")."""
    parser.add_argument(
        "--edit",
        choices=("add", "remove"),  # vinadv.vocabulary.EDITS
        default="add",
        help="add obstacles (default, the paper's setting) or remove them: free obstacle cells, never a border wall "
        "(the world gets easier, so any harm is the planner's own failure); --obstacles K frees K greedily",
    )


def add_harm_arguments(parser) -> None:
    """`--harm-tolerance`, `--harm-rtol`: the tolerances of the harm test (DESIGN.md "Harm")."""
    # 1e-6 is vinadv.classify.harm.DEFAULT_TOL, not imported: building the parser stays light (no scikit-learn)
    parser.add_argument(
        "--harm-tolerance",
        type=float,
        default=1e-6,
        metavar="ABS",
        help="harmful when regret_a > regret_o + ABS + REL * opt_cost_a (default 1e-6, cost units)",
    )
    parser.add_argument(
        "--harm-rtol",
        type=float,
        default=0.0,
        metavar="REL",
        help="relative harm tolerance, times the adversarial map's optimal cost (default 0)",
    )


def harm_tolerances(args: argparse.Namespace) -> dict:
    """The options of `add_harm_arguments` as the library's keyword arguments `harm_tol` and `harm_rtol`."""
    return {"harm_tol": args.harm_tolerance, "harm_rtol": args.harm_rtol}


def add_objective_argument(parser) -> None:
    """`--objective paper|harm`: what the ranking attacks keep as the strongest candidates of a map."""
    parser.add_argument(
        "--objective",
        choices=("paper", "harm"),
        default="paper",
        help="ranking strategies (key-points, saliency, exhaustive with --per-map >= 1): keep the "
        "strongest by the paper's label (UrP > FP > DP > UcP, default) or by harm (UrP, then "
        "the largest regret_a)",
    )


def attack_summary(
    labels, n_maps: int, no_valid: int, planner_calls: int, seconds: float, harm_table: dict | None = None
) -> dict:
    """The summary of labelled pairs: counts, the paper's success rate, and with `harm_table` (a
    `vinadv.classify.harm.cross_table`) the harm counts, the harmful rate and the label x harm table."""
    from vinadv.classify.harm import harm_summary
    from vinadv.vocabulary import label_counts, success_count

    counts = label_counts(labels)
    valid = len(labels) - counts["invalid"]
    success = success_count(counts)
    return {
        "maps": n_maps,
        "pairs": len(labels),
        "maps_without_valid_cell": no_valid,
        "counts": counts,
        "success_rate": success / valid if valid else None,
        "planner_calls": planner_calls,
        "planner_calls_per_success": planner_calls / success if success else None,
        "seconds": round(seconds, 3),
        **({} if harm_table is None else harm_summary(harm_table)),
    }


def print_counts(summary: dict) -> None:
    counts = summary["counts"]
    total = max(1, sum(counts.values()))
    print(f"{'category':<10}{'pairs':>9}{'share':>9}")
    for label, count in counts.items():
        print(f"{label:<10}{count:>9,}{count / total:>9.1%}")
    rate = summary["success_rate"]
    print(f"attack success rate (UrP + FP over valid pairs): {'n/a' if rate is None else f'{rate:.1%}'}")
    if "label_x_harm" in summary:
        table = summary["label_x_harm"]
        values = list(summary["harm_counts"])
        print(f"{'label x harm':<14}" + "".join(f"{v:>10}" for v in values))
        for label, row in table.items():
            print(f"{label:<14}" + "".join(f"{row[v]:>10,}" for v in values))
        rate = summary["harmful_rate"]
        print(
            f"harmful rate (UrP, or a path that got worse than optimal by more than on the original map, over valid "
            f"pairs): {'n/a' if rate is None else f'{rate:.1%}'}"
        )


def cmd_attack(args: argparse.Namespace) -> int:
    from vinadv.attacks.strategies import make_attack
    from vinadv.classify.harm import check_tolerances
    from vinadv.grid.mapset import MapSet
    from vinadv.identify import identify, objective_strength  # scikit-learn behind it: for this command only
    from vinadv.planners.registry.loading import PlannerRef

    check_tolerances(args.harm_tolerance, args.harm_rtol)
    device = planner_device(args)
    check_output_path(args.out)  # before the work: a folder in the way or a missing folder
    maps = MapSet.load(args.maps)
    planner = load_args_planner(args, maps, device)
    # `make_attack`'s options, kept: on a cluster every worker builds its own attack from them
    options = attack_options(args)
    attack = make_attack(args.strategy, **options)
    t0 = time.perf_counter()
    if args.cluster is None and args.workers is None:
        result = attack.attack(
            maps.obstacles,
            maps.starts[:, 0],
            maps.goals,
            planner,
            maps.corner_cutting,
            strength=objective_strength(args.objective),
            progress=shows_progress(args),
        )
    else:
        with open_cluster(args.cluster, args.workers) as client:
            ref = PlannerRef.of(planner, args.planner, args.weights, maps.corner_cutting)
            result = attack_on_cluster(
                client,
                args.strategy,
                options,
                maps,
                ref,
                shard_size=args.shard_size,
                progress=shows_progress(args),
                objective=args.objective,
            )
    elapsed = time.perf_counter() - t0
    result.pairs.save(args.out)
    ident = identify(result.pairs, **harm_tolerances(args))
    summary = attack_summary(
        ident.labels, len(maps), len(result.no_valid_cell), result.planner_calls, elapsed, harm_table=ident.harm_table()
    )
    summary.update(
        strategy=args.strategy,
        params=attack.params(),
        planner=planner.spec(),
        out=args.out,
        objective=args.objective,
        edit=args.edit,
    )
    fallback = attack.ranked_as(planner)
    if fallback:  # saliency without gradients (optimal, most search planners): ranked as key-points
        summary["ranked_as"] = fallback

    def report() -> None:
        removing = " (obstacles removed)" if args.edit == "remove" else ""
        print(
            f"{args.strategy}{removing} on planner {planner.name}: {summary['pairs']:,} pairs from {len(maps):,} maps "
            f"in {elapsed:.1f} s -> {args.out}"
        )
        if fallback:
            print(f"planner {planner.name} has no gradients: {args.strategy} ranked the cells as {fallback}")
        if result.no_valid_cell.size:
            what = "an obstacle to remove" if args.edit == "remove" else "an added obstacle"
            print(f"{len(result.no_valid_cell)} maps had no valid cell for {what}; no pair was made for them")
        print_counts(summary)
        per = summary["planner_calls_per_success"]
        per_text = "n/a" if per is None else f"{per:.1f}"
        print(f"planner calls: {result.planner_calls:,} ({per_text} per successful attack)")

    return emit(args, summary, report)
