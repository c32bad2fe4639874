"""`vinadv planners` (the registry) and `vinadv eval` (any planner, any protocol: the one eval command)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from vinadv.bench.index import entries_of, read_index
from vinadv.commands import add_planner_arguments, command_line, load_args_planner, planner_device
from vinadv.commands.eval_options import (
    add_eval_arguments,
    add_prior_argument,
    by_length_text,
    start_eval,
    write_figures,
)
from vinadv.commands.output import add_output_options, emit, shows_progress
from vinadv.errors import InputError

#: `vinadv.evaluation.protocols.PROTOCOLS`, not imported: building the parser loads no PyTorch
PROTOCOLS = ("vinadv", "gppn", "kentsommer", "search")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "planners", help="list the planners (`vinadv plan --planner NAME`) and how to bring your own"
    )
    p.add_argument("--size", type=int, default=28, help="map side whose shipped weights to look for (default 28)")
    add_output_options(p, json="the list")
    p.set_defaults(func=cmd_planners)

    ev = subparsers.add_parser(
        "eval",
        help="any planner's figures, by any protocol: vinadv's rollouts, GPPN's %%Opt/%%Suc over every free cell, "
        "the kentsommer port's, the Neural A* authors' Opt/Exp/Hmean",
        description="Measure a planner on a maps file or on generated maps. By default a policy planner gets vinadv's "
        "figures (action accuracy, rollouts from every start), GPPN's (%%Opt/%%Suc from every free cell) and the "
        "search figures (the Neural A* authors' Opt/Exp/Hmean, success, cost ratio to optimal); a search planner "
        "vinadv's rollout figures of its paths and the search figures. `vin eval` and `gppn eval` are this command "
        "for one planner and one protocol, with a flat record.",
    )
    add_planner_arguments(ev)
    add_eval_arguments(ev)
    ev.add_argument(
        "--protocol",
        default=None,
        metavar="P[,P]",
        help=f"protocols, joined by commas, from {', '.join(PROTOCOLS)} or all (default vinadv,gppn,search for a "
        "policy planner, vinadv,search for a search planner; kentsommer measures a VIN, gppn and kentsommer need a "
        "policy; docs/guide/planners.md)",
    )
    add_prior_argument(ev)
    ev.set_defaults(func=cmd_eval)


def zoo_listing(planners: list[dict]) -> list[dict]:
    """The model zoo (`vinadv.planners.registry.models`), each model with its bench entries (the shipped index,
    `vinadv.bench.index`); and, in place, each of `planners` (`list_planners`) with its zoo model (the shipped
    weights it loads by default, or None), weights sha256, training record, licence and bench entries."""
    from vinadv.planners.registry.models import model_of_file, read_zoo  # noqa: PLC0415 (light, read when listed)

    index = read_index()
    models = []
    for model in read_zoo().values():
        models.append({**model.to_dict(), "bench_entries": entries_of(index, model.planner, model.sha256)})
    by_name = {m["name"]: m for m in models}
    for p in planners:
        model = None if p["weights"] is None else model_of_file(p["weights"])
        m = None if model is None or not p["weights_available"] else by_name[model.name]
        p["zoo"] = None if m is None else m["name"]
        p["weights_sha256"] = None if m is None else m["sha256"]
        p["training"] = None if m is None else m["training"]
        p["licence"] = "MIT (vinadv's own licence)" if p["weights"] is None else (None if m is None else m["licence"])
        p["bench_entries"] = (
            entries_of(index, p["name"], None)
            if p["weights"] is None
            else ([] if m is None else entries_of(index, p["name"], m["sha256"]))
        )
    return models


def cmd_planners(args: argparse.Namespace) -> int:
    from vinadv.planners.registry.loading import SUFFIX, list_planners

    planners = list_planners(args.size)
    models = zoo_listing(planners)
    listing = {
        "planners": planners,
        "zoo": models,
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
        print("model zoo (--weights NAME; checked against its sha256 when loaded):")
        zoo_width = max(len(m["name"]) for m in models)
        for m in models:
            entries = ", ".join(e["suite"] for e in m["bench_entries"]) or "none"
            print(
                f"  {m['name']:<{zoo_width}} planner {m['planner']}, sha256 {m['sha256'][:12]}, {m['licence']}; "
                f"bench entries: {entries}"
            )
        print(
            "your own: --planner FILE.py:FACTORY or MODULE:FACTORY, FACTORY(size) -> torch.nn.Module with "
            "forward(obstacles (B,N,N) float 0/1, goals (B,2) int64) -> (B,8,N,N) logits (docs/own-planner.md)"
        )
        print(
            "           or an object with plan_paths(obstacles (B,N,N) bool, starts (B,2), goals (B,2), "
            "corner_cutting) -> SearchResult or B (L,2) paths: a search planner, every path checked"
        )
        print(
            f"symmetric:  any of these but optimal with {SUFFIX} (gppn{SUFFIX}): averaged over the 8 rotations and "
            "flips of the map, 8 forwards"
        )

    return emit(args, listing, text)


def check_protocols(text: str | None) -> tuple[str, ...] | None:
    """`--protocol`: names from `PROTOCOLS` joined by commas ('all': every one), none twice; None: the planner's
    default. InputError naming the option otherwise."""
    if text is None:
        return None
    names = [p.strip() for p in str(text).split(",")]
    if names == ["all"]:
        return PROTOCOLS
    for name in names:
        if name not in PROTOCOLS:
            raise InputError(f"protocol {name!r}: choose from {', '.join(PROTOCOLS)} or all", "protocol")
    if len(set(names)) != len(names):
        raise InputError(f"protocol: a protocol named twice in {text}", "protocol")
    return tuple(names)


def cmd_eval(args: argparse.Namespace) -> int:
    from vinadv.evaluation.planner_metrics import evaluate_planner
    from vinadv.evaluation.protocols import (
        PORT_TEST_PRIOR,
        gppn_protocol,
        kentsommer_protocol,
        planner_vin,
        require_policy,
    )
    from vinadv.evaluation.search_metrics import evaluate_search

    protocols = check_protocols(args.protocol)  # every option checked before the maps are read or made
    if args.prior is not None and "kentsommer" not in (protocols or ()):
        raise InputError("--prior applies to --protocol kentsommer only")
    device = planner_device(args)
    maps, source = start_eval(args)
    planner = load_args_planner(args, maps, device)
    if protocols is None:
        protocols = ("vinadv", "gppn", "search") if planner.capabilities.policy else ("vinadv", "search")
    for protocol in protocols:
        if protocol in ("gppn", "kentsommer"):
            require_policy(planner, f"the {protocol} protocol")
    vin = planner_vin(planner) if "kentsommer" in protocols else None
    figures, seconds = {}, {}
    for protocol in protocols:
        t0 = time.perf_counter()
        if protocol == "vinadv":
            figures[protocol] = evaluate_planner(planner, maps, progress=shows_progress(args))
        elif protocol == "gppn":
            figures[protocol] = gppn_protocol(planner, maps)
        elif protocol == "search":
            theirs = planner.vanilla_ratios and maps.moves == "octile"  # TransPath's ratios beside
            figures[protocol] = evaluate_search(planner, maps, progress=shows_progress(args), theirs=theirs)
        else:
            prior = PORT_TEST_PRIOR if args.prior is None else args.prior
            figures[protocol] = kentsommer_protocol(vin, maps, prior)
        seconds[protocol] = round(time.perf_counter() - t0, 2)
    metrics = {
        "planner": planner.spec(),
        "weights": args.weights or "shipped",
        **source,
        **figures,
        "seconds": seconds,
        "command": command_line(),
    }
    write_figures(args, metrics)
    return emit(args, metrics, lambda: print_eval(planner.name, maps, figures))


def _pct(x) -> str:
    return "n/a" if x is None or x != x else f"{x:.2%}"  # x != x: NaN


def print_eval(name: str, maps, figures: dict) -> None:
    """`vinadv eval`'s text: the planner and maps, one line per protocol, then vinadv's by optimal moves."""
    print(f"planner {name}: {len(maps)} maps of {maps.size}x{maps.size}")
    ours = figures.get("vinadv")
    if ours is not None:
        head = (
            f"  vinadv: rollout success {_pct(ours['success_rate'])} of {ours['rollouts']} rollouts, optimal paths "
            f"{_pct(ours['optimal_rate'])}"
        )
        accuracy = ours["action_accuracy"]
        print(head if accuracy is None else f"{head}, action accuracy {_pct(accuracy)}")
    theirs = figures.get("gppn")
    if theirs is not None:
        print(
            f"  gppn:   %Suc {_pct(theirs['percent_success'])}, %Opt {_pct(theirs['percent_optimal'])} over "
            f"{theirs['cells']} free cells (every {'NEWS' if maps.moves == 'news' else 'Moore'} move costs 1)"
        )
    port = figures.get("kentsommer")
    if port is not None:
        print(
            f"  kentsommer: rollout success {_pct(port['success_rate'])} of {port['rollouts']} (goal prior "
            f"{port['prior']:g}), action accuracy {_pct(port['action_accuracy_single_label'])} single-label over "
            f"{port['trajectory_states']} trajectory states"
        )
    found = figures.get("search")
    if found is not None:
        print(f"  search: {search_text(found)}")
        if found.get("transpath") is not None:
            print(f"  transpath: {transpath_text(found['transpath'])}")
    if ours is not None:
        print(by_length_text(ours))


def search_text(m: dict) -> str:
    """The search metrics (`vinadv.evaluation.search_metrics`) in one line; n/a where undefined."""
    ratio = "n/a" if m["cost_ratio"] is None else f"{m['cost_ratio']:.4f}"
    expanded = "" if m["expansions"] is None else f", {m['expansions']:.1f} cells expanded per search"
    reference = "" if m["expansions"] is None else " (against vinadv's exact A*)"
    return (
        f"Opt {_pct(m['opt'])}, Exp {_pct(m['exp'])}, Hmean {_pct(m['hmean'])}, success {_pct(m['success'])}, "
        f"cost ratio {ratio} over {m['rows']} (map, start) rows{expanded}{reference}"
    )


def transpath_text(t: dict) -> str:
    """TransPath's ratios (`vinadv.evaluation.search_metrics.transpath_ratios`) in one line; n/a where undefined."""

    def num(x) -> str:
        return "n/a" if x is None else f"{x:.4f}"

    unreached = f", {t['unreached']} not reached (left out of the cost ratio)" if t["unreached"] else ""
    return (
        f"expansions ratio {num(t['expansions_ratio'])}, cost ratio {num(t['cost_ratio'])} against their vanilla A* "
        f"(f = 0.5 g + 0.501 h, h octile) on the {t['kept']} of {t['rows']} rows whose vanilla cost is at least "
        f"{t['hardness']:g} x the octile heuristic at the start{unreached}"
    )
