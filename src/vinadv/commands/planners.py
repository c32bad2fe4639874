"""`vinadv planners` (the registry), `vinadv eval` (any planner, both conventions) and `vinadv gppn train|eval`."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from vinadv.commands import add_planner_arguments, emit
from vinadv.commands.vin import (
    _command_line,
    add_eval_arguments,
    add_train_arguments,
    by_length_text,
    emit_metrics,
    run_training,
    start_eval,
)

#: GPPN defaults at 28x28, chosen by benchmarks/gppn_training.py on the 2-core CPU (README, "Planners"): a 5x5
#: recurrent kernel reaches two cells per iteration, so 20 iterations cross a 28x28 map.
GPPN_DEFAULTS = {"l_h": 32, "k": 20, "kernel": 5, "lr": 0.001}


def register(subparsers) -> None:
    p = subparsers.add_parser("planners", help="list the planners (--planner NAME) and how to bring your own")
    p.add_argument("--size", type=int, default=28, help="map side whose shipped weights to look for (default 28)")
    p.add_argument("--json", action="store_true", help="print the list as JSON")
    p.set_defaults(func=cmd_planners)

    ev = subparsers.add_parser(
        "eval",
        help="any planner's figures in both conventions: vinadv's rollouts and GPPN's %%Opt/%%Suc over every free cell",
    )
    add_planner_arguments(ev)
    add_eval_arguments(ev)
    ev.set_defaults(func=cmd_eval)

    gppn = subparsers.add_parser("gppn", help="train and evaluate the GPPN planner")
    sub = gppn.add_subparsers(dest="gppn_command", metavar="ACTION")
    sub.required = True
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
    train.add_argument(
        "--compile",
        action="store_true",
        help="run training through torch.compile: the same function in fused kernels, about 1.4x faster on the CPU "
        "(needs a C++ compiler; the first steps compile, about a minute)",
    )
    train.set_defaults(func=cmd_gppn_train, k=GPPN_DEFAULTS["k"])

    ev = sub.add_parser("eval", help="action accuracy and rollout figures of a GPPN")
    ev.add_argument("--weights", default=None, help="GPPN weights file (default: the shipped weights for the size)")
    add_eval_arguments(ev)
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
    widen.add_argument("--json", action="store_true", help="print what was written as JSON")
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
    imp.add_argument("--out", required=True, help="output weights (.pt) for --planner gppn --weights")
    imp.add_argument("--json", action="store_true", help="print what was written as JSON")
    imp.set_defaults(func=cmd_gppn_import_weights)


def cmd_planners(args: argparse.Namespace) -> int:
    from vinadv.planners.registry import SUFFIX, list_planners

    planners = list_planners(args.size)
    if args.json:
        print(
            json.dumps(
                {
                    "planners": planners,
                    "bring_your_own": "FILE.py:FACTORY or MODULE:FACTORY",
                    "symmetric": f"NAME{SUFFIX} or SPEC{SUFFIX}: the planner averaged over the 8 rotations and flips",
                }
            )
        )
        return 0
    for p in planners:
        weights = (
            ""
            if p["weights"] is None
            else (f"  [weights {Path(p['weights']).name}{'' if p['weights_available'] else ' not shipped'}]")
        )
        print(f"{p['name']:<11} {p['description']}{weights}")
    print(
        "your own: --planner FILE.py:FACTORY or MODULE:FACTORY, FACTORY(size) -> torch.nn.Module with "
        "forward(obstacles (B,N,N) float 0/1, goals (B,2) int64) -> (B,8,N,N) logits (README, 'Planners')"
    )
    print(
        f"symmetric:  any of these but optimal with {SUFFIX} (gppn{SUFFIX}): averaged over the 8 rotations and flips "
        "of the map, 8 forwards"
    )
    return 0


def cmd_eval(args: argparse.Namespace) -> int:
    from vinadv.interop.protocols import gppn_protocol
    from vinadv.outfile import atomic_output
    from vinadv.planners.evaluation import evaluate_planner
    from vinadv.planners.registry import load_planner

    maps, source = start_eval(args)
    planner = load_planner(args.planner, maps.size, weights=args.weights, corner_cutting=maps.corner_cutting)
    t0 = time.perf_counter()
    ours = evaluate_planner(planner, maps, progress=not (args.quiet or args.json))
    t1 = time.perf_counter()
    theirs = gppn_protocol(planner, maps)
    metrics = {
        "planner": planner.spec(),
        "weights": args.weights or "shipped",
        **source,
        "vinadv": ours,
        "gppn": theirs,
        "seconds": {"vinadv": round(t1 - t0, 2), "gppn": round(time.perf_counter() - t1, 2)},
        "command": _command_line(),
    }
    if args.out:
        with atomic_output(args.out, "w") as fh:
            fh.write(json.dumps(metrics, indent=2) + "\n")
    if args.json:
        print(json.dumps(metrics))
    elif not args.quiet:
        print(f"planner {planner.name}: {ours['maps']} maps of {ours['size']}x{ours['size']}")
        print(
            f"  vinadv: rollout success {ours['success_rate']:.2%} of {ours['rollouts']} rollouts, optimal paths "
            f"{ours['optimal_rate']:.2%}, action accuracy {ours['action_accuracy']:.2%}"
        )
        print(
            f"  gppn:   %Suc {theirs['percent_success']:.2%}, %Opt {theirs['percent_optimal']:.2%} over "
            f"{theirs['cells']} free cells (every Moore move costs 1)"
        )
        print(by_length_text(ours))
    return 0


def cmd_gppn_train(args: argparse.Namespace) -> int:
    from vinadv.commands.vin import train_config
    from vinadv.planners.gppn import save_gppn
    from vinadv.planners.training import train_gppn

    config = train_config(args, planner="gppn", l_h=args.l_h, kernel=args.kernel, compile=args.compile)
    return run_training(args, config, train_gppn, save_gppn)


def cmd_gppn_widen(args: argparse.Namespace) -> int:
    from vinadv.outfile import check_output_path
    from vinadv.planners.gppn import load_gppn, save_gppn, widen_gppn
    from vinadv.planners.weights import weights_checksum

    check_output_path(args.out, mkdir=True)
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
        "command": _command_line(),
    }
    save_gppn(wide, args.out, record)
    summary = {"out": args.out, "config": wide.config.to_dict(), "from": args.weights, "noise": args.noise}
    return emit(
        args,
        summary,
        f"wrote {args.out}: GPPN {wide.config.to_dict()} widened from {args.weights} (l_h {model.config.l_h}); "
        f"continue with `vinadv gppn train --init {args.out} --l-h {args.l_h}`",
    )


def cmd_gppn_import_weights(args: argparse.Namespace) -> int:
    from vinadv.interop.checkpoints import gppn_from_checkpoint
    from vinadv.outfile import check_output_path
    from vinadv.planners.gppn import save_gppn
    from vinadv.planners.weights import weights_checksum

    check_output_path(args.out, mkdir=True)
    model = gppn_from_checkpoint(args.checkpoint, args.k, args.entry)
    record = {
        "imported_from": {**model.source, "sha256": weights_checksum(args.checkpoint)},
        "command": _command_line(),
        "action_order": "reordered from GPPN's N,E,W,S,NE,NW,SE,SW",
    }
    if args.size is not None:
        record["size"] = args.size
    save_gppn(model, args.out, record)
    summary = {"out": args.out, "config": model.config.to_dict(), **record}
    return emit(
        args,
        summary,
        f"wrote {args.out}: GPPN {model.config.to_dict()} from {args.checkpoint} "
        f"({model.source['entry']}); use --planner gppn --weights {args.out}",
    )


def cmd_gppn_eval(args: argparse.Namespace) -> int:
    from vinadv.planners.evaluation import evaluate_planner
    from vinadv.planners.registry import load_planner

    maps, source = start_eval(args)
    planner = load_planner("gppn", maps.size, weights=args.weights, corner_cutting=maps.corner_cutting)
    t0 = time.perf_counter()
    metrics = evaluate_planner(planner, maps, progress=not (args.quiet or args.json))
    return emit_metrics(args, {"planner": planner.spec(), "weights": args.weights or "shipped"}, source, metrics, t0)
