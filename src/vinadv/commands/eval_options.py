"""The options every `eval` command shares (`vin eval`, `gppn eval`, `vinadv eval`: the maps, torch threads, where
the figures go), and how the rollout figures are recorded and printed."""

from __future__ import annotations

import argparse
import json
import math
import textwrap
import time
from typing import TYPE_CHECKING

from vinadv.commands import add_moves_argument, add_threads_argument, command_line, planner_inputs, set_threads
from vinadv.commands.output import add_output_options, emit
from vinadv.errors import InputError, OutputError
from vinadv.outfile import atomic_output, check_output_path, same_file
from vinadv.planners.records import RolloutMetrics

if TYPE_CHECKING:  # NumPy and Numba behind it: imported by the command that evaluates
    from vinadv.grid.mapset import MapSet


def add_eval_arguments(ev: argparse.ArgumentParser, weights: str | None = None) -> None:
    """The options of every `eval` command: the maps (a maps file, or N maps generated on the fly: `start_eval`),
    torch threads and where the figures go; first, for the `eval` of one planner (`vin eval`, `gppn eval`: `weights`
    names it, "VIN"), that planner's `--weights` (`vinadv eval` has `add_planner_arguments`' own)."""
    if weights is not None:
        ev.add_argument(
            "--weights",
            default=None,
            help=f"{weights} weights file or model zoo name (default: the shipped weights for the map size)",
        )
    src = ev.add_mutually_exclusive_group(required=True)
    src.add_argument("--data", help="maps file (.npz)")
    src.add_argument("--n", type=int, help="generate N maps on the fly (with --seed and --size)")
    ev.add_argument("--seed", type=int, default=1000, help="seed of the generated maps (default 1000)")
    ev.add_argument("--size", type=int, default=28, help="side of the generated maps (default 28)")
    ev.add_argument("--starts", type=int, default=7, help="starts per generated map (default 7)")
    add_moves_argument(ev, default=None, what="with --n: movement model of the generated maps")
    add_threads_argument(ev)
    ev.add_argument("--out", default=None, help="also write the figures as JSON to this file")
    ev.add_argument(
        "--figure",
        default=None,
        metavar="FILE",
        help="also draw rollout success against the optimal path's length (buckets of 5 moves, 95%% Wilson band, "
        "rollouts per bucket) to FILE (.png, .svg or .pdf); needs the vinadv protocol",
    )
    add_output_options(ev, json="the figures", quiet=True)


def add_prior_argument(ev: argparse.ArgumentParser) -> None:
    """`--prior`: the goal-channel value of the kentsommer protocol (`vinadv eval`, `vin eval`)."""
    ev.add_argument(
        "--prior",
        type=float,
        default=None,
        help="kentsommer protocol: goal-channel value off the goal (default -1, as the port's test.py)",
    )


def start_eval(args: argparse.Namespace) -> tuple[MapSet, dict]:
    """Start an `eval` command from `add_eval_arguments`' options: set the torch threads (`--threads`), then
    return `(MapSet, source)`, the maps and a record of where they came from."""
    from vinadv.grid.generator import generate_maps
    from vinadv.grid.mapset import MapSet

    check_figure_option(args)
    check_eval_outputs(args)
    set_threads(args.threads)
    if args.data is not None:
        if args.moves is not None:
            raise InputError("--moves: only with --n (a maps file has its own movement model)")
        return MapSet.load(args.data), {"data": args.data}
    if args.n < 1:
        raise InputError(f"--n must be >= 1, got {args.n}")
    moves = args.moves or "octile"
    maps = generate_maps(args.n, args.size, args.seed, args.starts, moves=moves)
    generated = {"n": args.n, "seed": args.seed, "size": args.size}
    if moves != "octile":  # the record names the movement model only off octile maps
        generated["moves"] = moves
    return maps, {"generated": generated}


def check_eval_outputs(args: argparse.Namespace) -> None:
    """`--out` and `--figure` checked before the work (`check_output_path`): writable, not one another, and neither
    the maps file nor a file the planner reads."""
    inputs = {"--data": args.data, **planner_inputs(args)}
    if args.out:
        check_output_path(args.out, inputs=inputs)
    if getattr(args, "figure", None):
        check_output_path(args.figure, inputs=inputs)
        if args.out and same_file(args.out, args.figure):
            raise OutputError(f"--figure and --out name one file ({args.figure}): give each its own")


def check_figure_option(args: argparse.Namespace) -> None:
    """Refuse `--figure` before any work: a file name matplotlib cannot write, or protocols without the vinadv
    one (only it records rollouts by path length). `args.protocol` is one name (`vin eval`, `gppn eval`) or the
    comma-joined list of `vinadv eval` (None: the planner's default, which holds vinadv)."""
    if getattr(args, "figure", None) is None:
        return
    from vinadv.plot.files import figure_format

    try:
        figure_format(args.figure)
    except InputError as exc:
        raise InputError(str(exc).replace("out:", "--figure:", 1)) from None
    protocol = getattr(args, "protocol", None)
    names = [] if protocol is None else [p.strip() for p in str(protocol).split(",")]
    if names and "vinadv" not in names and names != ["all"]:
        raise InputError(f"--figure: needs the vinadv protocol (rollouts by path length), not {protocol}")


def emit_metrics(args: argparse.Namespace, measured: dict, source: dict, figures: dict, started: float) -> int:
    """Write an `eval` command's record to `--out`, and print it as JSON (`--json`) or as text. The record: what
    was measured (`measured`), where the maps came from (`source`), the `figures`, the seconds since `started`
    (a `time.perf_counter()` reading) and the command line."""
    seconds = round(time.perf_counter() - started, 2)
    metrics = {**measured, **source, **figures, "seconds": seconds, "command": command_line()}
    write_figures(args, metrics)
    protocol = getattr(args, "protocol", "vinadv")
    return emit(
        args, metrics, lambda: _print_metrics(metrics) if protocol == "vinadv" else _print_protocol_metrics(metrics)
    )


def write_figures(args: argparse.Namespace, figures: dict) -> None:
    """Write an `eval` command's record `figures` as indented JSON to `--out`, and its success-by-path-length
    curve to `--figure` (`vinadv.evaluation.length_curve`), where they are given."""
    if args.out:
        with atomic_output(args.out, "w") as fh:
            fh.write(json.dumps(figures, indent=2) + "\n")
    if getattr(args, "figure", None):
        from vinadv.evaluation.length_curve import by_length_rows, save_success_by_length

        ours = figures.get("vinadv", figures)  # `vinadv eval` nests each protocol's figures, `vin eval` is flat
        title = f"{ours['maps']:,} maps of {ours['size']}x{ours['size']}, {ours['rollouts']:,} rollouts"
        save_success_by_length([(figure_label(figures), by_length_rows(figures))], args.figure, title)


def figure_label(figures: dict) -> str:
    """The legend entry of an `eval` record: the planner (`vinadv eval`'s spec name) and the weights file's name."""
    planner = figures.get("planner")
    name = planner.get("name") if isinstance(planner, dict) else None
    weights = str(figures.get("weights") or "")
    weights = weights.removeprefix("shipped:").rsplit("/", 1)[-1]
    return " ".join(part for part in (name, f"({weights})" if weights and name else weights) if part) or "planner"


def _pct(x: float) -> str:
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{100 * x:.2f}%"


def _print_protocol_metrics(m: dict) -> None:
    print(f"{m['maps']} maps of {m['size']}x{m['size']}, measured as {m['protocol']} ({m['weights']})")
    if m["protocol"] == "kentsommer":
        print(f"  rollout success   {_pct(m['success_rate'])} of {m['rollouts']} (goal prior {m['prior']:g})")
        print(
            f"  action accuracy   {_pct(m['action_accuracy_single_label'])} single-label, "
            f"{m['trajectory_states']} trajectory states"
        )
    else:
        print(f"  %Opt              {_pct(m['percent_optimal'])} of {m['cells']} free cells (diagonal cost 1)")
        print(f"  %Suc              {_pct(m['percent_success'])}")


def _print_metrics(m: dict) -> None:
    terms = ", ".join(f"{k} {v}" for k, v in m["terminations"].items())
    print(f"{m['maps']} maps of {m['size']}x{m['size']}, {m['rollouts']} rollouts ({m['weights']})")
    print(f"  action accuracy   {_pct(m['action_accuracy'])} of {m['action_cells']} cells")
    print(f"  rollout success   {_pct(m['success_rate'])}")
    print(f"  optimal paths     {_pct(m['optimal_rate'])} (of reached: {_pct(m['optimal_rate_of_reached'])})")
    print(f"  mean extra cost   {m['mean_extra_cost']:.4f} (relative {_pct(m['mean_extra_cost_relative'])})")
    print(f"  terminations      {terms}")
    print(by_length_text(m))


def by_length_text(m: RolloutMetrics) -> str:
    """Rollout metrics `m`'s success by the optimal path's move count (`by_length`), wrapped lines."""
    rows = [f"{r['moves'][0]}-{r['moves'][1]}: {_pct(r['success_rate'])} of {r['rollouts']}" for r in m["by_length"]]
    # non-breaking spaces inside a row, so the lines break between rows only
    text = textwrap.fill(
        ", ".join(r.replace(" ", "\xa0") for r in rows),
        118,
        initial_indent="  by optimal moves  ",
        subsequent_indent=" " * 20,
        break_on_hyphens=False,
    )
    return text.replace("\xa0", " ")
