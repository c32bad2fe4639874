"""The options every planner's `train` command shares (`vin train`, `gppn train`; `neural-astar train` those of the
training run, `add_run_arguments`), and the body of those commands: the options' `TrainConfig`, the training run
with its checkpoint, the weights and the training record written."""

from __future__ import annotations

import argparse
import datetime
import json
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from vinadv import __version__
from vinadv.commands import LazyChoices, add_threads_argument, command_line, option_values, set_threads
from vinadv.commands.output import add_output_options, emit, progress_lines, shows_progress
from vinadv.errors import InputError
from vinadv.outfile import Inputs, atomic_output, check_output_path
from vinadv.planners.records import TrainingRecord
from vinadv.planners.weights import weights_checksum
from vinadv.records import RECORD_VERSIONS, TRAINING, VERSION_KEY

if TYPE_CHECKING:  # PyTorch behind it: imported by the command that trains
    from vinadv.planners.imitation import TrainConfig


def add_train_arguments(train: argparse.ArgumentParser, lr: float, k_help: str) -> None:
    """The options every planner's `train` command shares (`vin train`, `gppn train`)."""
    train.add_argument("--data", required=True, help="maps file (.npz, from `vinadv maps generate`)")
    add_weights_out_argument(train)
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
    train.add_argument(
        "--device", default="cpu", help="torch device: cpu, cuda, cuda:N, auto (cuda where available) (default cpu)"
    )
    train.add_argument("--k", type=int, default=None, help=k_help)
    train.add_argument(
        "--init",
        metavar="WEIGHTS",
        help="start from these weights (continue a training) instead of a fresh initialisation",
    )
    add_run_arguments(train)
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
    add_output_options(train, json="the training record", quiet=True)


def add_weights_out_argument(parser: argparse.ArgumentParser) -> None:
    """`--out`: the weights a command writes, with its record beside them (`write_record`)."""
    parser.add_argument("--out", required=True, help="output weights (.pt); the record goes to the same name .json")


def add_run_arguments(train: argparse.ArgumentParser) -> None:
    """The options of the training run that every `train` command shares (`vin`, `gppn`, `neural-astar`): torch CPU
    threads, a time limit, and `--resume` from the checkpoint a killed run left (`training_checkpoint`)."""
    add_threads_argument(train)
    train.add_argument(
        "--time-limit",
        type=float,
        default=None,
        metavar="MIN",
        help="stop after the first epoch that ends past MIN minutes (recorded as stopped early)",
    )
    train.add_argument("--resume", action="store_true", help="continue from OUT.ckpt if a killed run left one")


def add_compile_argument(train: argparse.ArgumentParser) -> None:
    """`--compile`: train through torch.compile (torch planners; the VIN's value iteration is compiled already)."""
    train.add_argument(
        "--compile",
        action="store_true",
        help="run training through torch.compile: the same function in fused kernels, about 1.4x faster on the CPU "
        "(needs a C++ compiler; the first steps compile, about a minute)",
    )


def train_config(args: argparse.Namespace, **extra: Any) -> TrainConfig:
    """The `TrainConfig` of a `train` command's shared options (`add_train_arguments`), plus `extra` fields."""
    from vinadv.planners.imitation import TrainConfig

    config = TrainConfig(
        **option_values(args, "epochs", "lr", "batch_size", "val_fraction", "seed", "device", "k", "init"),
        time_limit_min=args.time_limit,
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


def training_checkpoint(args: argparse.Namespace, out: Path) -> Path:
    """OUT.ckpt, the resumable checkpoint of a training that writes `out`; refused where a killed run left one and
    `--resume` was not given."""
    checkpoint = out.with_name(out.name + ".ckpt")
    if checkpoint.exists() and not args.resume:
        raise InputError(
            f"{checkpoint} exists (a killed or time-limited training?): pass --resume to continue it, or remove it"
        )
    return checkpoint


def training_record(**fields: Any) -> dict:
    """The head of a training record: its record version (`vinadv.records.TRAINING`), the command line, vinadv's
    version and the time it started; then `fields`."""
    return {
        VERSION_KEY: RECORD_VERSIONS[TRAINING],
        "command": command_line(),
        "vinadv": __version__,
        "started": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        **fields,
    }


def check_weights_out(out: str, inputs: Inputs) -> Path:
    """`--out` of a command that writes weights and their record beside them (`write_record`), checked before the
    work (`check_output_path`: created folder, writable, none of the command's `inputs`), the record's file too."""
    path = check_output_path(out, mkdir=True, inputs=inputs)
    check_output_path(path.with_suffix(".json"), inputs=inputs)
    return path


def write_record(out: Path, record: dict) -> Path:
    """Write `record` as indented JSON beside the weights `out` (`out` with `.json`, returned)."""
    record_path = out.with_suffix(".json")
    with atomic_output(record_path, "w") as fh:
        fh.write(json.dumps(record, indent=2) + "\n")
    return record_path


def add_import_arguments(imp: argparse.ArgumentParser, file: str, what: str) -> None:
    """The options every `import-weights` command of an authors' file shares (`neural-astar`, `transpath`): the
    licence and origin recorded, `--out` (`add_weights_out_argument`) and `--json`. `file` is the metavar of the
    authors' file, `what` what it is ("checkpoint", "file")."""
    imp.add_argument(
        "--license",
        default=None,
        help=f"the licence of the authors' code and weights, copied into the record (default: LICENSE beside {file}, "
        "if there)",
    )
    imp.add_argument(
        "--source",
        default=None,
        help=f"where the {what} comes from, recorded (say the repository, commit and path in it)",
    )
    add_weights_out_argument(imp)
    add_output_options(imp, json="the record")


def start_import(args: argparse.Namespace, path: str, what: str, inputs: Inputs) -> tuple[Path, Path | None]:
    """Start an `import-weights` command (`add_import_arguments`) of the authors' file `path` (`what` it is, for the
    error): `--out` checked before the work (`check_weights_out`: none of `inputs` nor `--license`), `path` there,
    and the licence file to record (`--license`, else LICENSE beside `path`). Returns `(out, licence or None)`."""
    out = check_weights_out(args.out, {**inputs, "--license": args.license})
    if not Path(path).is_file():
        raise InputError(f"{path}: no such {what} file")
    return out, file_beside(path, args.license, "LICENSE")


def file_beside(weights: str, given: str | None, name: str) -> Path | None:
    """`given` (an input of an import: it must be a file), or the file `name` in the folder of the imported
    `weights` when there (None if not)."""
    if given is not None:
        path = Path(given)
        if not path.is_file():
            raise InputError(f"{given}: no such file")
        return path
    path = Path(weights).parent / name
    return path if path.is_file() else None


def read_licence(path: Path | None) -> str | None:
    """The text of the licence file `path` an import copies into its record (None without one)."""
    if path is None:
        return None
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read the licence ({exc})") from None


def import_stamp() -> dict:
    """The tail of an import's record: the command line, vinadv's version and the time of the import."""
    return {
        "command": command_line(),
        "vinadv": __version__,
        "imported": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    }


def save_import(
    args: argparse.Namespace,
    model: Any,
    out: Path,
    record: dict,
    save: Callable[..., None],
    summary: str,
    licence: Path | None,
) -> int:
    """Complete an import's `record` with the text of the licence file `licence` (`read_licence`) and the import's
    stamp (`import_stamp`), write the imported weights with `save(model, out, record)` and the record beside them,
    then report: `wrote OUT and RECORD: summary`, or the record with `--json`."""
    record = {**record, "license": read_licence(licence), **import_stamp()}
    save(model, out, record)
    record_path = write_record(out, record)
    return emit(args, record, f"wrote {out} and {record_path}: {summary}")


def train_and_save(
    args: argparse.Namespace,
    train: Callable[..., tuple],
    *data: Any,
    out: Path,
    checkpoint: Path,
    record: dict,
    save: Callable[..., None],
    **options: Any,
) -> tuple[dict, Path]:
    """Train with `train(*data, ...)` (the checkpoint `checkpoint`, `--resume`, progress bars and lines as `--quiet`
    and `--json` say, `record` to fill, and `options`), then write the weights with `save(model, out, record)` and the
    record, stamped finished, beside them. The checkpoint goes when the training ran to its last epoch, and stays when
    it stopped early (`--time-limit`): `--resume` continues from it. Returns the record and the record file's
    path."""
    model, record = train(
        *data,
        checkpoint=checkpoint,
        resume=args.resume,
        progress=shows_progress(args),
        record=record,
        log=progress_lines(args),
        **options,
    )
    record["finished"] = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    save(model, out, record)
    record_path = write_record(out, record)
    if not record.get("stopped_early"):
        checkpoint.unlink(missing_ok=True)
    return record, record_path


def run_training(
    args: argparse.Namespace, config: TrainConfig, train: Callable[..., tuple], save: Callable[..., None]
) -> int:
    """Load the data, train with `train(maps, config, ...)` (checkpoint OUT.ckpt, `--resume`), write the weights
    with `save(model, out, record)` and the record next to them; the body of the `vin train` and `gppn train`
    commands."""
    from vinadv.grid.mapset import MapSet

    set_threads(args.threads)
    check_weights_out(args.out, {"--data": args.data, "--init": args.init})  # before hours of training
    maps = MapSet.load(args.data)
    if len(maps) < 2:
        raise InputError(f"{args.data}: {len(maps)} maps; training needs at least 2")
    out = Path(args.out)
    checkpoint = training_checkpoint(args, out)
    record: TrainingRecord = training_record(
        data={
            "path": str(args.data),
            "sha256": weights_checksum(args.data),
            "maps": len(maps),
            "size": maps.size,
            "seed": int(maps.seed),
            "corner_cutting": bool(maps.corner_cutting),
            "moves": maps.moves,
        }
    )
    augment = None
    if config.adversarial is not None:
        from vinadv.grid.moves import require_moves
        from vinadv.hardening import AdversarialConfig, AdversarialMaps

        # its attacks judge harm on octile costs: refused on other maps rather than mislabelled
        require_moves(maps.moves, ("octile",), "adversarial training (--adversarial)")

        augment = AdversarialMaps(maps, AdversarialConfig(**config.adversarial), seed=config.seed)
    record, record_path = train_and_save(
        args, train, maps, config, out=out, checkpoint=checkpoint, record=record, save=save, augment=augment
    )
    return emit(
        args,
        record,
        f"wrote {out} and {record_path}: {record['epochs_done']} epochs in "
        f"{record['wall_time_s']:.0f} s, val action accuracy {record['epochs'][-1]['val_action_accuracy']}",
    )
