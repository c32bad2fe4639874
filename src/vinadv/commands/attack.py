"""`vinadv attack`: adversarial maps (one added obstacle, or K added greedily) from a maps file."""

from __future__ import annotations

import argparse

from vinadv.commands import (
    LazyChoices,
    add_cluster_arguments,
    add_planner_arguments,
    open_args_executor,
    option_values,
    planner_device,
    planner_inputs,
)
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
    add_strategy_arguments(parser)
    parser.add_argument(
        "--obstacles",
        type=int,
        default=1,
        metavar="K",
        help="obstacles added per pair (default 1, the paper's setting); K > 1: greedily, the "
        "strategy run again on the map with the cells chosen so far, keeping the strongest cell "
        "against the original map's path each time; the search stops when no map has a valid cell left",
    )
    add_edit_argument(parser)


def add_strategy_arguments(parser) -> None:
    """`--budget` and `--radius`: the parameters of the strategies that take one (`make_attack`'s), which `attack`,
    `run` and `robustness` share."""
    parser.add_argument(
        "--budget", type=int, default=8, help="key-points and saliency: candidates evaluated per map (default 8)"
    )
    parser.add_argument("--radius", type=int, default=2, help="near-path: Chebyshev distance to the path (default 2)")


def attack_options(args: argparse.Namespace) -> dict:
    """The options of `add_attack_arguments` as `make_attack`'s (and `RunConfig`'s) keyword arguments."""
    return option_values(args, "per_map", "seed", "budget", "radius", "obstacles", "edit")


def add_edit_argument(parser, several: str = "--obstacles K frees K greedily") -> None:
    """`--edit add|remove`: whether the attack adds obstacles or frees them (DESIGN.md "Obstacle removal"); `several`
    says what the command's own flag for more than one edited cell does with `remove`."""
    parser.add_argument(
        "--edit",
        choices=("add", "remove"),  # vinadv.vocabulary.EDITS
        default="add",
        help="add obstacles (default, the paper's setting) or remove them: free obstacle cells, never a border wall "
        "(the world gets easier, so any harm is the planner's own failure); " + several,
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


def add_objective_argument(parser, default: str = "paper") -> None:
    """`--objective paper|harm|effort`: what the ranking attacks keep as the strongest candidates of a map."""
    parser.add_argument(
        "--objective",
        choices=("paper", "harm", "effort"),
        default=default,
        help="what the ranking strategies (key-points, saliency, exhaustive unless it keeps every cell) keep per "
        "map: the strongest by the paper's label (UrP > FP > DP > UcP), by harm (UrP, then the largest regret_a) or "
        f"by search effort (the most cells expanded: a planner that reports expansions); default {default}",
    )


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
    from vinadv.jobs.attack import AttackConfig, run  # scikit-learn behind it: for this command only

    config = AttackConfig(
        maps=args.maps,
        strategy=args.strategy,
        **attack_options(args),
        **option_values(args, "objective", "planner", "weights", "harm_tolerance", "harm_rtol", "shard_size"),
    )
    device = planner_device(args)
    # before the work: a folder in the way, a missing folder, an input (the maps, the planner's files)
    check_output_path(args.out, inputs={"--maps": args.maps, **planner_inputs(args)})
    with open_args_executor(args) as executor:
        outcome = run(config, executor, device=device, progress=shows_progress(args))
    outcome.pairs.save(args.out)
    summary = {**outcome.to_dict(), "out": args.out}
    elapsed, name, fallback = outcome.seconds, outcome.planner_name, outcome.ranked_as
    no_valid = outcome.result.no_valid_cell

    def report() -> None:
        removing = " (obstacles removed)" if args.edit == "remove" else ""
        print(
            f"{args.strategy}{removing} on planner {name}: {summary['pairs']:,} pairs from {outcome.n_maps:,} maps "
            f"in {elapsed:.1f} s -> {args.out}"
        )
        if fallback:
            print(f"planner {name} has no gradients: {args.strategy} ranked the cells as {fallback}")
        if no_valid.size:
            what = "an obstacle to remove" if args.edit == "remove" else "an added obstacle"
            print(f"{len(no_valid)} maps had no valid cell for {what}; no pair was made for them")
        print_counts(summary)
        per = summary["planner_calls_per_success"]
        per_text = "n/a" if per is None else f"{per:.1f}"
        print(f"planner calls: {outcome.result.planner_calls:,} ({per_text} per successful attack)")

    return emit(args, summary, report)
