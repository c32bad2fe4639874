"""`vinadv vin train` and `vinadv vin eval`."""

from __future__ import annotations

import argparse
import datetime
import json
import math
import shlex
import sys
import textwrap
import time
from pathlib import Path

from vinadv.commands import LazyChoices, emit
from vinadv.errors import InputError
from vinadv.outfile import atomic_output, check_output_path
from vinadv.planners.records import RolloutMetrics, TrainingRecord


def register(subparsers) -> None:
    vin = subparsers.add_parser("vin", help="train and evaluate the VIN planner")
    sub = vin.add_subparsers(dest="vin_command", metavar="ACTION")
    sub.required = True

    train = sub.add_parser("train", help="train a VIN on a maps file (every free cell is supervised)")
    add_train_arguments(train, lr=0.005, k_help="value-iteration steps (default: 10/20/36 at 8/16/28)")
    train.add_argument(
        "--vi-init",
        choices=LazyChoices("vinadv.planners.vin", "VI_INITS"),
        default="default",
        metavar="INIT",
        help="how a fresh VIN's value iteration starts: default (PyTorch's initialisation, the paper's VIN) or shift "
        "(each q channel reads one neighbour's value, fc the identity: learns the shortest-path recursion itself; "
        "README, 'Adversarial training')",
    )
    train.set_defaults(func=cmd_train)

    ev = sub.add_parser("eval", help="action accuracy and rollout figures of a VIN")
    ev.add_argument("--weights", default=None, help="weights file (default: the shipped weights for the map size)")
    add_eval_arguments(ev)
    ev.add_argument("--k", type=int, default=None, help="value-iteration steps for a port-style weights file")
    ev.add_argument(
        "--protocol",
        choices=("vinadv", "kentsommer", "gppn"),
        default="vinadv",
        help="measure as vinadv (default), the kentsommer port's test.py, or GPPN (%%Opt/%%Suc over every "
        "free cell); see README, 'Using data and models from other VIN/GPPN code'",
    )
    ev.add_argument(
        "--prior",
        type=float,
        default=None,
        help="kentsommer protocol: goal-channel value off the goal (default -1, as the port's test.py)",
    )
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
    exw.add_argument("--json", action="store_true", help="print the keys and shapes as JSON")
    exw.set_defaults(func=cmd_export_weights)


def add_train_arguments(train: argparse.ArgumentParser, lr: float, k_help: str) -> None:
    """The options every planner's `train` command shares (`vin train`, `gppn train`)."""
    train.add_argument("--data", required=True, help="maps file (.npz, from `vinadv maps generate`)")
    train.add_argument("--out", required=True, help="output weights (.pt); the record goes to the same name .json")
    train.add_argument("--epochs", type=int, default=30, help="epochs (default 30)")
    train.add_argument(
        "--lr", type=float, default=lr, help=f"peak RMSprop learning rate, cosine-decayed (default {lr})"
    )
    train.add_argument("--batch-size", type=int, default=32, help="maps per batch (default 32)")
    train.add_argument(
        "--warmup",
        type=int,
        default=None,
        metavar="STEPS",
        help="linear learning-rate warm-up over the first STEPS optimizer steps "
        "(default: 5%% of all steps, at most 200)",
    )
    train.add_argument("--val-fraction", type=float, default=0.05, help="maps held out for validation (default 0.05)")
    train.add_argument("--seed", type=int, default=0, help="seed for initialisation, split and shuffling (default 0)")
    train.add_argument("--device", default="cpu", help="torch device: cpu, cuda, cuda:1 ... (default cpu)")
    train.add_argument("--k", type=int, default=None, help=k_help)
    train.add_argument("--threads", type=int, default=None, help="torch CPU threads (default: torch's choice)")
    train.add_argument(
        "--time-limit",
        type=float,
        default=None,
        metavar="MIN",
        help="stop after the first epoch that ends past MIN minutes (recorded as stopped early)",
    )
    train.add_argument(
        "--init",
        metavar="WEIGHTS",
        help="start from these weights (continue a training) instead of a fresh initialisation",
    )
    train.add_argument("--resume", action="store_true", help="continue from OUT.ckpt if a killed run left one")
    adv = train.add_argument_group("adversarial training (vinadv.hardening)")
    adv.add_argument(
        "--adversarial",
        action="store_true",
        help="before each epoch, attack training maps with the current model and add the adversarial "
        "maps of the harmful pairs to the training maps",
    )
    adv.add_argument(
        "--adv-maps",
        type=int,
        default=1000,
        metavar="M",
        help="training maps attacked before each epoch (default 1000)",
    )
    adv.add_argument(
        "--adv-strategy",
        choices=LazyChoices("vinadv.attacks.strategies", "STRATEGIES"),
        default="exhaustive",
        metavar="STRATEGY",
        help="attack strategy: %(choices)s (default exhaustive: each map's worst single obstacle)",
    )
    adv.add_argument("--adv-budget", type=int, default=8, help="key-points/saliency: candidates per map (default 8)")
    adv.add_argument(
        "--adv-objective",
        choices=("harm", "paper"),
        default="harm",
        help="what the attack keeps as a map's strongest pair (default harm)",
    )
    adv.add_argument(
        "--adv-start",
        type=int,
        default=None,
        metavar="EPOCH",
        help="first epoch (1-based) before which maps are attacked (default 1 with --init, else 2)",
    )
    train.add_argument("--quiet", action="store_true", help="no progress bar or per-epoch lines")
    train.add_argument("--json", action="store_true", help="print the training record as JSON")


def add_eval_arguments(ev: argparse.ArgumentParser) -> None:
    """The options of every `eval` command: the maps (a maps file, or N maps generated on the fly: `start_eval`),
    torch threads and where the figures go."""
    src = ev.add_mutually_exclusive_group(required=True)
    src.add_argument("--data", help="maps file (.npz)")
    src.add_argument("--n", type=int, help="generate N maps on the fly (with --seed and --size)")
    ev.add_argument("--seed", type=int, default=1000, help="seed of the generated maps (default 1000)")
    ev.add_argument("--size", type=int, default=28, help="side of the generated maps (default 28)")
    ev.add_argument("--starts", type=int, default=7, help="starts per generated map (default 7)")
    ev.add_argument("--threads", type=int, default=None, help="torch CPU threads")
    ev.add_argument("--out", default=None, help="also write the figures as JSON to this file")
    ev.add_argument("--quiet", action="store_true", help="no progress bar")
    ev.add_argument("--json", action="store_true", help="print the figures as JSON")


def start_eval(args: argparse.Namespace):
    """Start an `eval` command from `add_eval_arguments`' options: set the torch threads (`--threads`), then
    return `(MapSet, source)`, the maps and a record of where they came from."""
    from vinadv.grid.generator import generate_maps
    from vinadv.grid.mapset import MapSet

    _set_threads(args.threads)
    if args.data is not None:
        return MapSet.load(args.data), {"data": args.data}
    if args.n < 1:
        raise InputError(f"--n must be >= 1, got {args.n}")
    maps = generate_maps(args.n, args.size, args.seed, args.starts)
    return maps, {"generated": {"n": args.n, "seed": args.seed, "size": args.size}}


def _command_line() -> str:
    return "vinadv " + shlex.join(sys.argv[1:])


def _set_threads(n: int | None) -> None:
    from vinadv.planners.batching import set_torch_threads

    if n is not None:
        if n < 1:
            raise InputError(f"--threads must be >= 1, got {n}")
        set_torch_threads(n)


def train_config(args: argparse.Namespace, **extra):
    """The `TrainConfig` of a `train` command's shared options (`add_train_arguments`), plus `extra` fields."""
    from vinadv.planners.training import TrainConfig

    config = TrainConfig(
        epochs=args.epochs,
        lr=args.lr,
        batch_size=args.batch_size,
        val_fraction=args.val_fraction,
        seed=args.seed,
        device=args.device,
        k=args.k,
        time_limit_min=args.time_limit,
        init=args.init,
        warmup_steps=args.warmup,
        adversarial=adversarial_config(args),
        **extra,
    )
    config.validate()
    return config


def adversarial_config(args: argparse.Namespace) -> dict | None:
    """The `AdversarialConfig` of `--adversarial` and its options, as a dict (None without `--adversarial`)."""
    if not args.adversarial:
        return None
    from vinadv.hardening import AdversarialConfig

    start = args.adv_start if args.adv_start is not None else (1 if args.init else 2)
    for flag, value in (("--adv-maps", args.adv_maps), ("--adv-budget", args.adv_budget), ("--adv-start", start)):
        if value < 1:  # checked here, in flags (strategy and objective are argparse choices)
            raise InputError(f"{flag} must be >= 1, got {value}")
    config = AdversarialConfig(
        maps_per_epoch=args.adv_maps,
        strategy=args.adv_strategy,
        budget=args.adv_budget,
        objective=args.adv_objective,
        start_epoch=start - 1,
    )
    config.validate()
    return config.to_dict()


def cmd_train(args: argparse.Namespace) -> int:
    from vinadv.planners.training import train_vin
    from vinadv.planners.vin.weights import save_vin

    return run_training(args, train_config(args, vi_init=args.vi_init), train_vin, save_vin)


def run_training(args: argparse.Namespace, config, train, save) -> int:
    """Load the data, train with `train(maps, config, ...)` (checkpoint OUT.ckpt, `--resume`), write the weights
    with `save(model, out, record)` and the record next to them; the body of every `train` command."""
    from vinadv import __version__
    from vinadv.grid.mapset import MapSet
    from vinadv.planners.weights import weights_checksum

    _set_threads(args.threads)
    check_output_path(args.out, mkdir=True)  # before hours of training: a folder in the way
    maps = MapSet.load(args.data)
    if len(maps) < 2:
        raise InputError(f"{args.data}: {len(maps)} maps; training needs at least 2")
    out = Path(args.out)
    checkpoint = out.with_name(out.name + ".ckpt")
    if checkpoint.exists() and not args.resume:
        raise InputError(f"{checkpoint} exists (a killed training?): pass --resume to continue it, or remove it")
    record: TrainingRecord = {
        "command": _command_line(),
        "vinadv": __version__,
        "started": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "data": {
            "path": str(args.data),
            "sha256": weights_checksum(args.data),
            "maps": len(maps),
            "size": maps.size,
            "seed": int(maps.seed),
            "corner_cutting": bool(maps.corner_cutting),
        },
    }
    log = None if args.quiet or args.json else (lambda line: print(line, flush=True))
    augment = None
    if config.adversarial is not None:
        from vinadv.hardening import AdversarialConfig, AdversarialMaps

        augment = AdversarialMaps(maps, AdversarialConfig(**config.adversarial), seed=config.seed)
    model, record = train(
        maps,
        config,
        checkpoint=checkpoint,
        resume=args.resume,
        progress=not (args.quiet or args.json),
        record=record,
        log=log,
        augment=augment,
    )
    record["finished"] = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    save(model, out, record)
    record_path = out.with_suffix(".json")
    with atomic_output(record_path, "w") as fh:
        fh.write(json.dumps(record, indent=2) + "\n")
    checkpoint.unlink(missing_ok=True)
    return emit(
        args,
        record,
        f"wrote {out} and {record_path}: {record['epochs_done']} epochs in "
        f"{record['wall_time_s']:.0f} s, val action accuracy {record['epochs'][-1]['val_action_accuracy']}",
    )


def cmd_eval(args: argparse.Namespace) -> int:
    from vinadv.interop.protocols import evaluate_protocol
    from vinadv.planners.vin.weights import default_weights_path, load_vin
    from vinadv.planners.weights import weights_checksum

    maps, source = start_eval(args)
    model = load_vin(args.weights, size=maps.size, k=args.k)
    trained = model.record.get("size")
    if trained is not None and trained != maps.size:
        raise InputError(
            f"{model.weights_path}: weights were trained on {trained}x{trained} maps, "
            f"the maps are {maps.size}x{maps.size}"
        )
    data_seed = model.record.get("data", {}).get("seed")
    if data_seed is not None and data_seed == maps.seed and not args.quiet:
        print(f"vinadv: warning: these maps use seed {maps.seed}, the seed of the training data", file=sys.stderr)
    t0 = time.perf_counter()
    if args.prior is not None and args.protocol != "kentsommer":
        raise InputError("--prior applies to --protocol kentsommer only")
    metrics = evaluate_protocol(model, maps, args.protocol, args.prior, progress=not (args.quiet or args.json))
    weights_path = args.weights or f"shipped:{default_weights_path(maps.size).name}"
    measured = {"weights": weights_path, "weights_sha256": weights_checksum(model.weights_path)}
    return emit_metrics(args, measured, source, metrics, t0)


def emit_metrics(args: argparse.Namespace, measured: dict, source: dict, figures: dict, started: float) -> int:
    """Write an `eval` command's record to `--out`, and print it as JSON (`--json`) or as text. The record: what
    was measured (`measured`), where the maps came from (`source`), the `figures`, the seconds since `started`
    (a `time.perf_counter()` reading) and the command line."""
    seconds = round(time.perf_counter() - started, 2)
    metrics = {**measured, **source, **figures, "seconds": seconds, "command": _command_line()}
    if args.out:
        with atomic_output(args.out, "w") as fh:
            fh.write(json.dumps(metrics, indent=2) + "\n")
    if args.json:
        print(json.dumps(metrics))
    elif getattr(args, "protocol", "vinadv") == "vinadv":
        _print_metrics(metrics)
    else:
        _print_protocol_metrics(metrics)
    return 0


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


def cmd_export_weights(args: argparse.Namespace) -> int:
    import torch

    from vinadv.interop.checkpoints import export_state_dict, gppn_vin_gaps, read_checkpoint
    from vinadv.planners.vin.weights import load_vin

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
