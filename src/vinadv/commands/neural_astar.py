"""`vinadv neural-astar import-weights`, `vinadv neural-astar compare-modes` and `vinadv neural-astar train`."""

from __future__ import annotations

import argparse
import hashlib
import time

from vinadv.commands import add_actions, add_device_argument, command_line, option_values, planner_device, set_threads
from vinadv.commands.output import add_output_options, emit, progress_bar
from vinadv.commands.train_options import (
    add_import_arguments,
    add_run_arguments,
    add_weights_out_argument,
    check_weights_out,
    file_beside,
    save_import,
    start_import,
    train_and_save,
    training_checkpoint,
    training_record,
)
from vinadv.errors import InputError
from vinadv.planners.weights import weights_checksum

#: the format of the record of an import, in the weights file and beside it
IMPORT_RECORD_FORMAT = "vinadv.neural-astar-import/1"


def register(subparsers) -> None:
    sub = add_actions(
        subparsers, "neural-astar", help="the Neural A* planner: train it, import the authors' weights, check it"
    )

    imp = sub.add_parser(
        "import-weights",
        help="the Neural A* authors' Lightning checkpoint (CNN encoder) as vinadv weights, with its record",
    )
    imp.add_argument("checkpoint", metavar="CKPT", help="the authors' checkpoint (epoch=..-step=...ckpt)")
    imp.add_argument(
        "--train-config",
        default=None,
        help="the authors' train.yaml the model was trained with, recorded (default: train.yaml beside CKPT, if "
        "there; its encoder must be the checkpoint's)",
    )
    add_import_arguments(imp, "CKPT", "checkpoint")
    imp.set_defaults(func=cmd_import_weights)

    cmp = sub.add_parser(
        "compare-modes",
        help="plan a maps file with the exact and the differentiable search; count the searches that part",
    )
    cmp.add_argument("--data", required=True, help="a maps file of moore maps (vinadv.maps), every start planned")
    cmp.add_argument(
        "--weights", default=None, help="Neural A* weights file or model zoo name (default: the shipped mazes model)"
    )
    cmp.add_argument("--device", default="cpu", help="torch device: cpu, cuda, cuda:1 ... (default cpu)")
    add_output_options(cmp, json="the counts", quiet=True)
    cmp.set_defaults(func=cmd_compare_modes)

    tr = sub.add_parser(
        "train",
        help="train Neural A* as its authors do (L1 between the search history and the optimal path; train.yaml's "
        "settings), selected by validation Hmean",
    )
    tr.add_argument(
        "--data",
        required=True,
        action="append",
        metavar="MAPS",
        help="moore maps file(s) to train on (repeat for several: joined as `vinadv maps concat` joins them, "
        "so of one size and starts per map), e.g. from `vinadv maps import "
        "--format mpd FILE --split train`",
    )
    tr.add_argument(
        "--val-data",
        action="append",
        metavar="MAPS",
        help="maps file(s) to validate on, each map's first start (repeatable; default: the last --val-fraction "
        "of the training maps after a seeded shuffle)",
    )
    tr.add_argument("--val-fraction", type=float, default=0.1, help="held out without --val-data (default 0.1)")
    add_weights_out_argument(tr)
    tr.add_argument("--epochs", type=int, default=50, help="epochs (default 50, as train.yaml)")
    tr.add_argument("--lr", type=float, default=0.001, help="RMSprop learning rate (default 0.001)")
    tr.add_argument("--batch-size", type=int, default=100, help="maps per step and per validation batch (default 100)")
    tr.add_argument("--tmax", type=float, default=0.25, help="share of cells the search may select (default 0.25)")
    tr.add_argument("--seed", type=int, default=1234, help="initialisation, shuffles and starts (default 1234)")
    tr.add_argument("--depth", type=int, default=4, help="encoder blocks, 1..4 (default 4)")
    add_run_arguments(tr)
    add_device_argument(tr)
    add_output_options(tr, json="the training record", quiet=True)
    tr.set_defaults(func=cmd_train)


def cmd_import_weights(args: argparse.Namespace) -> int:
    from vinadv.planners.neural_astar.checkpoint import (
        check_train_config,
        from_lightning_checkpoint,
        read_train_config,
    )
    from vinadv.planners.neural_astar.model import save_neural_astar
    from vinadv.planners.neural_astar.planner import MOVES

    inputs = {"CKPT": args.checkpoint, "--train-config": args.train_config}
    out, license_path = start_import(args, args.checkpoint, "checkpoint", inputs)
    config_path = file_beside(args.checkpoint, args.train_config, "train.yaml")
    model, source = from_lightning_checkpoint(args.checkpoint)
    train_config = None
    if config_path is not None:
        train_config = read_train_config(config_path)
        check_train_config(train_config, model.config.depth, str(config_path))
    record = {
        "format": IMPORT_RECORD_FORMAT,
        "planner": "neural-astar",
        "imported_from": {
            **source,
            "sha256": weights_checksum(args.checkpoint),
            "source": args.source,
        },
        "train_config": train_config,
        "train_config_file": None
        if config_path is None
        else {"path": str(config_path), "sha256": weights_checksum(config_path)},
        "model": model.config.to_dict(),
        "moves": MOVES,
        "corner_cutting": True,
    }
    return save_import(
        args,
        model,
        out,
        record,
        save_neural_astar,
        f"Neural A* (CNN encoder, depth {model.config.depth}) from {args.checkpoint} (epoch {source['epoch']}); "
        f"use --planner neural-astar --weights {out}",
        license_path,
    )


def cmd_compare_modes(args: argparse.Namespace) -> int:
    import numpy as np

    from vinadv.grid.mapset import MapSet
    from vinadv.planners.registry.loading import load_planner

    maps = MapSet.load(args.data)
    planner = load_planner(
        "neural-astar",
        maps.size,
        weights=args.weights,
        corner_cutting=maps.corner_cutting,
        device=args.device,
        moves=maps.moves,
    )
    rows = maps.start_mask.reshape(-1)
    starts = maps.starts.reshape(-1, 2)[rows]
    map_of_row = np.repeat(np.arange(len(maps)), maps.n_starts)[rows]
    obstacles, goals = maps.obstacles[map_of_row], maps.goals[map_of_row]
    chunk = 256
    same_path = np.zeros(len(starts), dtype=bool)
    same_expanded = np.zeros(len(starts), dtype=bool)
    seconds = {"exact": 0.0, "differentiable": 0.0}
    with progress_bar(args, total=len(starts), unit="search", desc="comparing modes") as bar:
        for i in range(0, len(starts), chunk):
            sl = slice(i, i + chunk)
            t0 = time.perf_counter()
            exact = planner.plan(obstacles[sl], starts[sl], goals[sl], maps.corner_cutting, maps.moves)
            t1 = time.perf_counter()
            diff = planner.plan_paths_differentiable(obstacles[sl], starts[sl], goals[sl], maps.corner_cutting)
            seconds["exact"] += t1 - t0
            seconds["differentiable"] += time.perf_counter() - t1
            same_path[sl] = exact.paths.same_as(diff.paths) & (exact.termination == diff.termination)
            same_expanded[sl] = (exact.expanded == diff.expanded).all(axis=(1, 2))
            bar.update(len(exact.termination))
    n = len(starts)
    differing = np.flatnonzero(~(same_path & same_expanded))
    result = {
        "data": args.data,
        "weights": args.weights or "shipped",
        "searches": n,
        "identical_paths": int(same_path.sum()),
        "identical_expansions": int(same_expanded.sum()),
        "share_identical_paths": float(same_path.mean()) if n else float("nan"),
        "share_identical_expansions": float(same_expanded.mean()) if n else float("nan"),
        "differing": [{"map": int(map_of_row[r]), "start": [int(v) for v in starts[r]]} for r in differing[:20]],
        "seconds": {k: round(v, 2) for k, v in seconds.items()},
        "command": command_line(),
    }
    return emit(
        args,
        result,
        f"{n} searches on {len(maps)} maps: identical paths {result['identical_paths']} "
        f"({result['share_identical_paths']:.2%}), identical expanded cells {result['identical_expansions']} "
        f"({result['share_identical_expansions']:.2%}); exact {seconds['exact']:.1f} s, differentiable "
        f"{seconds['differentiable']:.1f} s",
    )


def _joined_maps(paths: list[str]):
    """The maps files `paths` loaded and joined by `MapSet.concat` (one size, starts per map, movement model and
    corner-cutting rule), and what the record says of them."""
    from vinadv.grid.mapset import MapSet

    parts = [MapSet.load(p) for p in paths]
    records = [
        {"path": str(p), "sha256": weights_checksum(p), "maps": len(m), "seed": int(m.seed)}
        for p, m in zip(paths, parts, strict=True)
    ]
    return MapSet.concat(parts, names=[str(p) for p in paths]), records


def cmd_train(args: argparse.Namespace) -> int:

    from vinadv.planners.harness import split_indices
    from vinadv.planners.neural_astar.model import save_neural_astar
    from vinadv.planners.neural_astar.training import NeuralAstarTrainConfig, train_neural_astar

    set_threads(args.threads)
    device = planner_device(args) or "cpu"
    config = NeuralAstarTrainConfig(
        **option_values(args, "epochs", "lr", "batch_size", "tmax", "seed", "depth"),
        device=device,
        time_limit_min=args.time_limit,
    )
    config.validate()
    if not args.val_data and not 0 < args.val_fraction < 1:
        raise InputError(f"--val-fraction must be in (0, 1), got {args.val_fraction}")
    out = check_weights_out(args.out, {"--data": args.data, "--val-data": args.val_data})
    checkpoint = training_checkpoint(args, out)
    maps, data = _joined_maps(args.data)
    if args.val_data:
        val_maps, val_data = _joined_maps(args.val_data)
        train_maps = maps
    else:
        try:  # the held-out maps as `vin train` and `gppn train` draw them
            train_rows, val_rows = split_indices(len(maps), args.val_fraction, args.seed)
        except InputError as exc:
            raise InputError(f"{args.data[0]}: {exc}") from None
        train_maps, val_maps = maps.take(train_rows), maps.take(val_rows)
        val_data = None
    digest = hashlib.sha256(
        "".join(d["sha256"] for d in data + (val_data or [])).encode() + str(args.val_fraction).encode()
    ).hexdigest()
    record = training_record(
        data=data,
        val_data=val_data if val_data is not None else f"{args.val_fraction} of the training maps held out",
    )
    record, record_path = train_and_save(
        args,
        train_neural_astar,
        train_maps,
        val_maps,
        config,
        out=out,
        checkpoint=checkpoint,
        record=record,
        save=save_neural_astar,
        data_sha256=digest,
    )
    best = record["best"]
    return emit(
        args,
        record,
        f"wrote {out} and {record_path}: {record['epochs_done']} epochs in {record['wall_time_s']:.0f} s; best epoch "
        f"{best['epoch']}: val Opt {best['val_p_opt']:.3f} Exp {best['val_p_exp']:.3f} Hmean {best['val_h_mean']:.3f}; "
        f"use --planner neural-astar --weights {out}",
    )
