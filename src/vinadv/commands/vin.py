"""`vinadv vin train`, `vinadv vin eval` and `vinadv vin export-weights` (the GPPN's are in `commands.gppn`)."""

from __future__ import annotations

import argparse
import time

from vinadv.commands import LazyChoices, add_actions
from vinadv.commands.eval_options import add_eval_arguments, add_prior_argument, emit_metrics, start_eval
from vinadv.commands.output import add_output_options, emit, note, shows_progress
from vinadv.commands.train_options import add_train_arguments, run_training, train_config
from vinadv.errors import InputError
from vinadv.outfile import check_output_path
from vinadv.planners.weights import check_trained_size, weights_checksum


def register(subparsers) -> None:
    sub = add_actions(subparsers, "vin", help="train and evaluate the VIN planner")

    train = sub.add_parser("train", help="train a VIN on a maps file (every free cell is supervised)")
    add_train_arguments(train, lr=0.005, k_help="value-iteration steps (default: 10/20/36 at 8/16/28)")
    train.add_argument(
        "--vi-init",
        choices=LazyChoices("vinadv.planners.vin", "VI_INITS"),
        default="default",
        metavar="INIT",
        help="how a fresh VIN's value iteration starts: default (PyTorch's initialisation, the paper's VIN) or shift "
        "(each q channel reads one neighbour's value, fc the identity: learns the shortest-path recursion itself; "
        "docs/guide/planners.md)",
    )
    train.set_defaults(func=cmd_train)

    ev = sub.add_parser(
        "eval",
        help="action accuracy and rollout figures of a VIN: an alias of `vinadv eval --planner vin --protocol P`, "
        "with a flat record (and --k for port-style weights)",
    )
    add_eval_arguments(ev, weights="VIN")
    ev.add_argument("--k", type=int, default=None, help="value-iteration steps for a port-style weights file")
    ev.add_argument(
        "--protocol",
        choices=("vinadv", "kentsommer", "gppn"),
        default="vinadv",
        help="measure as vinadv (default), the kentsommer port's test.py, or GPPN (%%Opt/%%Suc over every "
        "free cell); see docs/guide/interop.md",
    )
    add_prior_argument(ev)
    ev.set_defaults(func=cmd_eval)

    exw = sub.add_parser("export-weights", help="write VIN weights as a plain state dict for the PyTorch ports")
    exw.add_argument("weights", metavar="W", help="weights file (.pt)")
    exw.add_argument(
        "--format",
        required=True,
        choices=("state-dict",),
        help="state-dict: exactly the keys h.weight h.bias r.weight q.weight w fc.weight",
    )
    exw.add_argument("--out", required=True, help="output file (.pth)")
    add_output_options(exw, json="the keys and shapes")
    exw.set_defaults(func=cmd_export_weights)


def cmd_train(args: argparse.Namespace) -> int:
    from vinadv.planners.vin.training import train_vin
    from vinadv.planners.vin.weights import save_vin

    return run_training(args, train_config(args, vi_init=args.vi_init), train_vin, save_vin)


def cmd_eval(args: argparse.Namespace) -> int:
    from vinadv.evaluation.protocols import evaluate_protocol
    from vinadv.planners.vin.planner import as_planner
    from vinadv.planners.vin.weights import default_weights_path, load_vin

    maps, source = start_eval(args)
    model = load_vin(args.weights, size=maps.size, k=args.k)
    check_trained_size(model.weights_path, model.record, maps.size, "VIN")
    as_planner(model, maps.size).for_moves(maps.moves)  # a VIN trained on another movement model: one line
    data_seed = model.record.get("data", {}).get("seed")
    if data_seed is not None and data_seed == maps.seed:
        note(args, f"vinadv: warning: these maps use seed {maps.seed}, the seed of the training data")
    t0 = time.perf_counter()
    if args.prior is not None and args.protocol != "kentsommer":
        raise InputError("--prior applies to --protocol kentsommer only")
    metrics = evaluate_protocol(model, maps, args.protocol, args.prior, progress=shows_progress(args))
    weights_path = args.weights or f"shipped:{default_weights_path(maps.size).name}"
    measured = {"weights": weights_path, "weights_sha256": weights_checksum(model.weights_path)}
    return emit_metrics(args, measured, source, metrics, t0)


def cmd_export_weights(args: argparse.Namespace) -> int:
    import torch

    from vinadv.interop.checkpoints import export_state_dict, gppn_vin_gaps, read_checkpoint
    from vinadv.planners.vin.weights import load_vin

    check_output_path(args.out, inputs={"W": args.weights})  # before the weights are read
    try:
        model = load_vin(args.weights)
    except InputError:
        try:  # a GPPN checkpoint: say what vinadv's VIN cannot represent
            state, _ = read_checkpoint(args.weights)
        except InputError:
            state = None
        if state is None:
            raise
        raise InputError(
            f"{args.weights}: a GPPN-style checkpoint; vinadv's VIN cannot represent it: "
            + "; ".join(gppn_vin_gaps(state))
        ) from None
    shapes = export_state_dict(model, args.out)
    summary = {
        "out": args.out,
        "format": args.format,
        "k": model.config.k,
        "keys": {k: list(v) for k, v in shapes.items()},
        "torch": torch.__version__,
    }
    return emit(
        args,
        summary,
        f"wrote {args.out}: plain state dict {', '.join(shapes)} (k = {model.config.k} is not stored: "
        f"the ports take it as an option)",
    )
