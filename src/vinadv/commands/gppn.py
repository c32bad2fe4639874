"""`vinadv gppn train`, `vinadv gppn eval`, `vinadv gppn widen` and `vinadv gppn import-weights`."""

from __future__ import annotations

import argparse
import time
from typing import Any

from vinadv.commands import add_actions, command_line
from vinadv.commands.eval_options import add_eval_arguments, emit_metrics, start_eval
from vinadv.commands.output import add_output_options, emit, shows_progress
from vinadv.commands.train_options import add_compile_argument, add_train_arguments, run_training, train_config
from vinadv.outfile import check_output_path
from vinadv.planners.weights import weights_checksum

#: GPPN defaults at 28x28, chosen by perf/gppn_training.py on the 2-core CPU (docs/results/history.md): a 5x5
#: recurrent kernel reaches two cells per iteration, so 20 iterations cross a 28x28 map.
GPPN_DEFAULTS = {"l_h": 32, "k": 20, "kernel": 5, "lr": 0.001}


def register(subparsers) -> None:
    sub = add_actions(subparsers, "gppn", help="train and evaluate the GPPN planner")
    train = sub.add_parser("train", help="train a GPPN on a maps file (every free cell is supervised)")
    add_train_arguments(train, lr=GPPN_DEFAULTS["lr"], k_help=f"iterations (default {GPPN_DEFAULTS['k']})")
    train.add_argument(
        "--l-h", type=int, default=GPPN_DEFAULTS["l_h"], help=f"hidden (LSTM) channels (default {GPPN_DEFAULTS['l_h']})"
    )
    train.add_argument(
        "--kernel",
        type=int,
        default=GPPN_DEFAULTS["kernel"],
        help=f"odd kernel of the recurrent convolution (default {GPPN_DEFAULTS['kernel']})",
    )
    add_compile_argument(train)
    train.set_defaults(func=cmd_gppn_train, k=GPPN_DEFAULTS["k"])

    ev = sub.add_parser(
        "eval",
        help="action accuracy and rollout figures of a GPPN: an alias of `vinadv eval --planner gppn --protocol "
        "vinadv`, with a flat record",
    )
    add_eval_arguments(ev, weights="GPPN")
    ev.set_defaults(func=cmd_gppn_eval)

    widen = sub.add_parser(
        "widen",
        help="a wider GPPN computing the same function (Net2WiderNet), to continue training with more channels",
    )
    widen.add_argument("weights", metavar="WEIGHTS", help="the GPPN weights to widen (.pt)")
    widen.add_argument("--l-h", type=int, required=True, help="hidden (LSTM) channels of the wide model")
    widen.add_argument(
        "--noise",
        type=float,
        default=1e-3,
        help="noise on the added channels' incoming weights, relative to each weight's std, so training can tell "
        "the copies apart (default 0.001; 0 keeps the logits equal)",
    )
    widen.add_argument("--seed", type=int, default=0, help="seed for the channels copied and the noise (default 0)")
    widen.add_argument("--out", required=True, help="output weights (.pt); continue with `gppn train --init OUT`")
    add_output_options(widen, json="what was written")
    widen.set_defaults(func=cmd_gppn_widen)

    imp = sub.add_parser("import-weights", help="a checkpoint of the GPPN authors' code as vinadv GPPN weights")
    imp.add_argument(
        "checkpoint", metavar="CKPT", help="the GPPN code's checkpoint (.pth: {'model', 'best_model', ...})"
    )
    imp.add_argument(
        "--k",
        type=int,
        required=True,
        help="iterations the model was trained with (the GPPN code's --k; not in its checkpoints)",
    )
    imp.add_argument(
        "--entry",
        choices=("best_model", "model"),
        default=None,
        help="which state dict of the checkpoint (default best_model when present)",
    )
    imp.add_argument(
        "--size",
        type=int,
        default=None,
        help="map side the model is for (recorded; default: any, the GPPN is fully convolutional)",
    )
    imp.add_argument(
        "--out", required=True, help="output weights (.pt), for `vinadv plan --planner gppn --weights OUT`"
    )
    add_output_options(imp, json="what was written")
    imp.set_defaults(func=cmd_gppn_import_weights)


def cmd_gppn_train(args: argparse.Namespace) -> int:
    from vinadv.planners.gppn import save_gppn
    from vinadv.planners.gppn.training import train_gppn

    config = train_config(args, planner="gppn", l_h=args.l_h, kernel=args.kernel, compile=args.compile)
    return run_training(args, config, train_gppn, save_gppn)


def cmd_gppn_widen(args: argparse.Namespace) -> int:
    from vinadv.planners.gppn import load_gppn, widen_gppn

    check_output_path(args.out, mkdir=True, inputs={"WEIGHTS": args.weights})
    model = load_gppn(args.weights)
    wide = widen_gppn(model, args.l_h, noise=args.noise, seed=args.seed)
    record = {
        "widened_from": {
            "path": str(args.weights),
            "sha256": weights_checksum(args.weights),
            "config": model.config.to_dict(),
            "record": model.record,
        },
        "noise": args.noise,
        "seed": args.seed,
        "command": command_line(),
    }
    return _write_gppn(
        args,
        wide,
        record,
        {"from": args.weights, "noise": args.noise},
        f"widened from {args.weights} (l_h {model.config.l_h}); continue with `vinadv gppn train --init {args.out} "
        f"--l-h {args.l_h}`",
    )


def cmd_gppn_import_weights(args: argparse.Namespace) -> int:
    from vinadv.interop.checkpoints import gppn_from_checkpoint

    check_output_path(args.out, mkdir=True, inputs={"CKPT": args.checkpoint})
    model = gppn_from_checkpoint(args.checkpoint, args.k, args.entry)
    record = {
        "imported_from": {**model.source, "sha256": weights_checksum(args.checkpoint)},
        "command": command_line(),
        "action_order": "reordered from GPPN's N,E,W,S,NE,NW,SE,SW",
    }
    if args.size is not None:
        record["size"] = args.size
    return _write_gppn(
        args,
        model,
        record,
        record,
        f"from {args.checkpoint} ({model.source['entry']}); use --planner gppn --weights {args.out}",
    )


def _write_gppn(args: argparse.Namespace, model: Any, record: dict, summary: dict, made: str) -> int:
    """Save the GPPN `model` with `record` to `--out` (`gppn widen`, `gppn import-weights`), then report it: with
    `--json` the file, the model's config and `summary`, else `wrote OUT: GPPN CONFIG made`."""
    from vinadv.planners.gppn import save_gppn

    save_gppn(model, args.out, record)
    config = model.config.to_dict()
    return emit(args, {"out": args.out, "config": config, **summary}, f"wrote {args.out}: GPPN {config} {made}")


def cmd_gppn_eval(args: argparse.Namespace) -> int:
    from vinadv.evaluation.planner_metrics import evaluate_planner
    from vinadv.planners.registry.loading import load_planner

    maps, source = start_eval(args)
    planner = load_planner(
        "gppn", maps.size, weights=args.weights, corner_cutting=maps.corner_cutting, moves=maps.moves
    )
    t0 = time.perf_counter()
    metrics = evaluate_planner(planner, maps, progress=shows_progress(args))
    return emit_metrics(args, {"planner": planner.spec(), "weights": args.weights or "shipped"}, source, metrics, t0)
