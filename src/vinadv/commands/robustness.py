"""`vinadv robustness`: a planner's robustness benchmark (the attack suite, worst case per map; `vinadv.robustness`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from vinadv import display
from vinadv.commands import (
    add_moves_argument,
    add_planner_arguments,
    check_db_and_report,
    db_file,
    option_values,
    planner_device,
    planner_inputs,
)
from vinadv.commands.attack import (
    add_edit_argument,
    add_harm_arguments,
    add_objective_argument,
    add_strategy_arguments,
)
from vinadv.commands.output import add_output_options, emit, shows_progress
from vinadv.commands.run import add_maps_arguments, maps_settings
from vinadv.errors import InputError, OutputError

#: `vinadv.robustness.DEFAULT_STRATEGIES`, not imported: building the parser stays light
_DEFAULTS = "key-points, saliency, near-path, random"


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "robustness",
        help="benchmark a planner's robustness: every attack strategy on fixed held-out maps, worst "
        "case per map, 1..K added obstacles",
        description="Attack a fixed, seeded set of held-out maps with every strategy (one pair per map, 1..K "
        "obstacles added greedily), and print per strategy and worst case per map (broken if any strategy breaks "
        "it): clean success, the paper's success rate (UrP + FP), the harmful rate, the mean regret, and the harmful "
        "rate against the number of added obstacles.",
    )
    add_planner_arguments(p)
    add_maps_arguments(p, n=1000, instead="the generator's held-out maps", record="the settings record")
    p.add_argument(
        "--seed",
        type=int,
        default=1000,
        help="seed of the maps and of the randomised strategies (default 1000: the held-out maps of the "
        "evaluation tables)",
    )
    add_moves_argument(
        p, default=None, what="movement model of the benchmark maps (the planner must plan it; with --maps, the file's)"
    )
    p.add_argument(
        "--strategies",
        default="all",
        metavar="all|A,B",
        help=f"strategies, joined by commas (default all: {_DEFAULTS})",
    )
    p.add_argument(
        "--exhaustive",
        action="store_true",
        help="also run the exhaustive search (every valid cell of every map at every step: slow)",
    )
    p.add_argument(
        "--max-obstacles",
        type=int,
        default=3,
        metavar="K",
        help="the curve's largest number of added obstacles (default 3; at most a map's N*N cells)",
    )
    add_objective_argument(p, default="harm")
    add_strategy_arguments(p)
    add_edit_argument(p, several="the curve frees 1 to --max-obstacles cells")
    p.add_argument(
        "--exact-k2",
        choices=("harmful", "regret"),
        help="after the benchmark, the exact k = 2 diagnostic: the exhaustive one-cell search, then every pair of "
        "addable cells on the valid maps no cell harms, stopping at a map's first harmful pair (harmful) or planning "
        "all pairs for the largest regret (regret: about 165,000 planner calls per 28x28 map), and the gap of the "
        "greedy worst case at k <= 2 to it; printed and in --json, not stored (adding only; --max-obstacles >= 2)",
    )
    add_harm_arguments(p)
    p.add_argument("--db", help="store the benchmark in this database (URL or SQLite file)")
    p.add_argument(
        "--name",
        help="a name for this benchmark, stored and shown with it (tells runs of one planner apart)",
    )
    p.add_argument(
        "--report",
        metavar="DIR",
        help="write a page with the benchmark (and, with --db, every one stored there) as a table and curves to DIR",
    )
    add_output_options(p, json="every figure", quiet=True)
    p.set_defaults(func=cmd_robustness)


def cmd_robustness(args: argparse.Namespace) -> int:
    from vinadv.robustness import RobustnessConfig, check_strategies, run

    # every option checked before the maps are made and the planner loaded
    strategies = check_strategies(args.strategies, exhaustive=args.exhaustive)
    if args.n is not None and args.n < 1:  # before a maps file is read
        raise InputError(f"n must be >= 1, got {args.n}", "n")
    device = planner_device(args)
    inputs = {"--maps": args.maps, **planner_inputs(args)}
    check_db_and_report(db_file(args.db) if args.db else None, inputs, args.report)  # no input overwritten
    if args.report and Path(args.report).exists() and not Path(args.report).is_dir():
        raise OutputError(f"cannot write the report to {args.report}: exists and is not a folder")
    if args.exact_k2 and (args.edit == "remove" or args.max_obstacles < 2):
        raise InputError(
            "--exact-k2 compares pairs of added cells with the greedy k = 2: it needs --edit add and --max-obstacles "
            ">= 2",
            "exact_k2",
        )
    settings = maps_settings(args, n=1000)  # a maps file is read and checked here, before anything is written
    config = RobustnessConfig(
        **settings,
        **option_values(args, "planner", "weights", "seed", "max_obstacles", "objective", "budget", "radius", "edit"),
        **option_values(args, "harm_tolerance", "harm_rtol", "name"),
        strategies=strategies,
    )
    result = run(config, db=args.db, device=device, progress=shows_progress(args))
    out = result.to_dict()
    if result.id is not None:
        out["id"] = result.id
    if args.exact_k2:
        from vinadv import exact_k2

        diagnostic = exact_k2.run(config, result, args.exact_k2, device=device, progress=shows_progress(args))
        out["exact_k2"] = diagnostic.to_dict()
    if args.report:
        from vinadv.report.build import robustness_report

        unsaved = (
            []
            if args.db is not None
            else [
                {
                    "id": None,
                    "planner": result.settings["planner"],
                    "run_name": result.settings["name"],
                    "weights_checksum": result.planner.get("weights_sha256"),
                    "settings": result.settings,
                    "result": result.to_dict(),
                }
            ]
        )
        out["report"] = str(robustness_report(args.report, args.db, unsaved))
    return emit(args, out, lambda: print_robustness(out))


def _pct(value) -> str:
    return display.percent(value)


def _regret(figures: dict) -> str:
    """The mean regret with its bootstrap 95% interval where there is one: `0.412 [0.301, 0.530]` (rounded: float
    noise shows as 0.000)."""
    low, high = figures.get("mean_regret_low"), figures.get("mean_regret_high")
    interval = "" if low is None or high is None else f" [{display.number(low)}, {display.number(high)}]"
    return display.number(figures["mean_regret"]) + interval


def _pct_ci(figures: dict, rate: str) -> str:
    """The rate with its Wilson 95% interval (`{rate}_low`, `{rate}_high`), in percent: `10.0% [2.8, 30.1]`."""
    low, high = figures.get(f"{rate}_low"), figures.get(f"{rate}_high")
    interval = "" if low is None or high is None else f" {display.points(low, high)}"
    return _pct(figures[rate]) + interval


def print_robustness(out: dict) -> None:
    """The benchmark as text: the figures at one obstacle per strategy and worst case, then the k curve."""
    s, clean = out["settings"], out["clean"]
    planner = out["planner"]
    weights = (planner.get("weights_sha256") or "")[:12]
    origin = f"from {s['maps']}" if s.get("maps") else f"seed {s['maps_seed']}"  # every record names `maps`
    if s.get("maps_sha256"):
        origin += f", sha256 {s['maps_sha256'][:12]}"
    named = f"{s['name']!r}: " if s.get("name") else ""
    print(
        f"{named}robustness of planner {s.get('planner') or planner['name']}"
        f"{f' (weights {weights})' if weights else ''} on {s['n']:,} maps "
        f"{s['size']}x{s['size']} ({origin}), kept by {s['objective']}, in {out['seconds']:.1f} s"
        + (", obstacles removed" if s["edit"] == "remove" else "")
    )
    print(
        f"clean success: {_pct(clean['success_rate'])} ({clean['reached']:,} of {clean['maps']:,} maps), mean "
        f"regret of the reached paths {_regret(clean)}"
    )
    rows = [(name, st["by_obstacles"], st["seconds"]) for name, st in out["strategies"].items()]
    rows.append(("worst case", out["overall"], out["seconds"]))
    print("rates with their Wilson 95% intervals, in percent; mean regrets with their bootstrap 95% intervals")
    print(f"{'one obstacle':<12}{'valid':>8}{'paper success':>22}{'harmful':>22}{'mean regret':>26}{'seconds':>9}")
    for name, by_k, sec in rows:
        f = by_k[0]
        print(
            f"{name:<12}{f['valid']:>8,}{_pct_ci(f, 'paper_success_rate'):>22}{_pct_ci(f, 'harmful_rate'):>22}"
            f"{_regret(f):>26}{sec:>9.1f}"
        )
    if "effort_harmful" in out["overall"][0]:  # a planner that reports expansions
        print(f"effort-harmful at one obstacle (search grown over {s['effort_tolerance']:g} times A*'s growth)")
        for name, by_k, _ in rows:
            print(f"{name:<12}{_pct_ci(by_k[0], 'effort_harmful_rate'):>30}")
    ks = [f["k"] for f in out["overall"]]
    print("harmful rate by obstacles added: " + "".join(f"{f'k = {k}':>9}" for k in ks))
    for name, by_k, _ in rows:
        print(f"{name:<33}" + "".join(f"{_pct(f['harmful_rate']):>9}" for f in by_k))
    if "exact_k2" in out:
        print_exact_k2(out["exact_k2"])
    if "id" in out:
        print(f"stored as robustness benchmark {out['id']}")
    if "report" in out:
        print(f"report: {out['report']}")


def print_exact_k2(d: dict) -> None:
    """The exact k = 2 diagnostic as text: the exact harmful rate at k <= 2, the search's cost, the greedy's gap."""
    what = "first harmful pair" if d["mode"] == "harmful" else "all pairs"
    print(
        f"exact k <= 2 ({what}): {d['harmful_k1']:,} of {d['valid']:,} valid maps harmed by one cell; "
        f"{d['searched']:,} searched, {d['planned_pairs']:,} of {d['candidate_pairs']:,} pairs planned in "
        f"{d['seconds']:.1f} s; harmed by a pair: {d['harmful_pair']:,}"
    )
    print(f"exact harmful rate at k <= 2: {_pct_ci(d, 'harmful_rate')} ({d['harmful']:,} maps)")
    greedy = d.get("greedy")
    if greedy:
        print(
            f"greedy worst case at k <= 2: {_pct_ci(greedy, 'harmful_rate')} ({greedy['harmful']:,} maps); gap "
            f"{greedy['gap']:,} maps ({_pct(greedy['gap_rate'])})"
            + (f"; {greedy['greedy_only']} harmed by the greedy only (should be 0)" if greedy["greedy_only"] else "")
        )
    if "regret" in d:
        r = d["regret"]
        mean = "—" if r["mean"] is None else f"{r['mean']:.3f}"
        line = f"largest regret over the pairs of {r['maps']:,} maps: {r['unreached']:,} unreached, mean {mean}"
        if greedy and "regret" in greedy:
            g = greedy["regret"]
            gap = "—" if g["mean_gap"] is None else f"{g['mean_gap']:.3f}"
            line += f"; worse than the greedy's on {g['exact_worse']:,}, by {gap} on average where both reach"
        print(line)
