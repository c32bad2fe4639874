"""Subcommands of `vinadv`; each module has `register(subparsers)`.

Building the parser must stay light (`vinadv --help` and `--version` import no PyTorch, Numba, scikit-learn or
SQLAlchemy): a command module imports the vinadv modules that pull those (and NumPy) inside the command's function,
and reads names that live in them through `LazyChoices`. `output` holds `--json`, `--quiet` and how a command prints
its result; `training` and `evaluation` the options every `train` and every `eval` command shares. An option that
several commands share is added by one `add_..._argument(s)` function (here, or in the module of the command it
belongs to), so that its type, default and help are written once.
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import shlex
import sys
from collections.abc import Iterator
from typing import Any

from vinadv.cluster import open_executor
from vinadv.errors import InputError
from vinadv.planners.batching import set_torch_threads
from vinadv.planners.device import resolve_device
from vinadv.planners.registry.base import DEFAULT_PLANNER, REGISTRY  # names, loaders as text: no NumPy


class LazyChoices:
    """argparse `choices` taken from `module.attribute` (any iterable of names) only when argparse needs them: to
    check a value given on the command line, or for the command's own `--help`."""

    def __init__(self, module: str, attribute: str) -> None:
        self.module, self.attribute = module, attribute
        self._names: tuple[str, ...] | None = None

    def _load(self) -> tuple[str, ...]:
        if self._names is None:
            self._names = tuple(getattr(importlib.import_module(self.module), self.attribute))
        return self._names

    def __contains__(self, value: object) -> bool:
        return value in self._load()

    def __iter__(self) -> Iterator[str]:
        return iter(self._load())


def add_actions(subparsers, name: str, help: str) -> argparse._SubParsersAction:
    """The command `vinadv NAME ACTION` (`help` its line in `vinadv --help`): its actions' subparsers, one of which
    must be given; the action's name goes to `NAME_command`."""
    parser = subparsers.add_parser(name, help=help)
    actions = parser.add_subparsers(dest=name.replace("-", "_") + "_command", metavar="ACTION")
    actions.required = True
    return actions


def add_planner_arguments(parser, weights_help: str | None = None) -> None:
    """`--planner NAME|SPEC`, `--weights FILE` and `--device` (`add_device_argument`): the planner a command plans
    with (`vinadv.planners.registry`) and where its forward runs."""
    parser.add_argument(
        "--planner",
        default=None,
        metavar="NAME|SPEC",
        help=planner_help(),
    )
    parser.add_argument(
        "--weights",
        default=None,
        help=weights_help
        or "weights file of the vin, gppn or neural-astar planner, or a model zoo name (vin28-robust: `vinadv "
        "planners`) (default: the shipped weights for the map size)",
    )
    add_device_argument(parser)


def planner_help() -> str:
    """`--planner`'s help: the registered planners by name, read from the registry (a light import: no NumPy), so a
    planner registered in `vinadv.planners.registry.declarations` is listed without editing this text."""
    names = ", ".join(f"{name} (default)" if name == DEFAULT_PLANNER else name for name in REGISTRY)
    return (
        f"a registered planner: {names}; NAME:key=value sets its parameters (wastar:w=3); or your own FILE.py:FACTORY "
        "/ MODULE:FACTORY; +d4 after one averages it over the 8 rotations and flips (see `vinadv planners`)"
    )


def add_device_argument(parser) -> None:
    """`--device cpu|cuda|cuda:N|auto`: where a torch planner's forward runs (read it with `planner_device`)."""
    parser.add_argument(
        "--device",
        default=None,
        metavar="cpu|cuda|cuda:N|auto",
        help="torch device of the planner's forward; auto: cuda where available, else cpu. Default: the CPU, and for "
        "the VIN its exact CPU engine (with --device the VIN plans with its PyTorch forward there). Recorded by type "
        "in the planner's record (docs/guide/gpu.md)",
    )


def load_args_planner(args, maps, device: str | None):
    """The planner of `--planner`/`--weights` for the maps `maps` (a `MapSet`: its size, move rule and movement
    model), its forward on `device` (`planner_device(args)`, checked before the command wrote anything)."""
    from vinadv.planners.registry.loading import load_planner

    size, corner_cutting, moves = maps.size, maps.corner_cutting, maps.moves
    return load_planner(
        args.planner, size, weights=args.weights, corner_cutting=corner_cutting, moves=moves, device=device
    )


def planner_inputs(args) -> dict[str, str | None]:
    """The files `--planner` and `--weights` read (for `vinadv.outfile.check_output_path`'s `inputs`): the planner's
    own FILE.py of a FILE.py:FACTORY spec, and the weights file (a zoo name matches no output)."""
    spec = getattr(args, "planner", None)
    found = re.match(r"(.+?\.py):", spec) if spec else None
    return {"--planner": found.group(1) if found else None, "--weights": getattr(args, "weights", None)}


def db_file(db: str | None) -> str | None:
    """The SQLite file a `--db` value names (its default included: $VINADV_DB, else vinadv.db), or None for a server
    URL or an in-memory database: for `check_output_path`'s `inputs`, without loading SQLAlchemy."""
    db = db or os.environ.get("VINADV_DB") or "vinadv.db"
    if "://" not in db:
        return os.path.expanduser(db)
    if not db.startswith("sqlite:///"):
        return None
    path = db.removeprefix("sqlite:///").split("?", 1)[0]
    return None if path in ("", ":memory:") or path.startswith("file:") else path


def check_db_and_report(db: str | None, inputs: dict, report: str | None = None) -> None:
    """Before a job's work: the SQLite file it stores in, `db` (`db_file(args.db)`; None: none), is none of its
    `inputs` (`{"--maps": args.maps, ...}`), and its report folder `report` (`--report DIR`) is neither an input nor
    the database (`vinadv.outfile`)."""
    from vinadv.outfile import check_not_input, check_output_folder  # noqa: PLC0415 (light, but only for jobs)

    if db is not None:
        check_not_input(db, inputs)
    if report is not None:
        check_output_folder(report, inputs={**inputs, "--db": db})


def planner_device(args) -> str | None:
    """`--device` checked and made concrete (`auto` -> `cuda` or `cpu`), for `load_planner(..., device=)`; None when
    not given. Call it before the command writes anything: a device this machine lacks is one line, exit status 2."""
    name = getattr(args, "device", None)
    if name is None:
        return None
    return str(resolve_device(name))


def add_cluster_arguments(parser, shard_size: bool = False) -> None:
    """`--cluster`, `--workers` (read by `open_args_executor`; and with `shard_size`, `--shard-size` for commands
    that have none yet): where a job's chunks are computed (`vinadv.cluster.DaskExecutor`)."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--cluster", metavar="tcp://HOST:PORT", help="compute on this Dask scheduler's workers")
    group.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="compute on a local Dask cluster of N single-threaded worker processes (at most 4 per core of this "
        "machine; for more, --cluster)",
    )
    if shard_size:
        parser.add_argument(
            "--shard-size", type=int, default=1000, help="with --cluster/--workers: items per task (default 1000)"
        )


def open_args_executor(args):
    """The executor of `--cluster`/`--workers` (`vinadv.cluster.open_executor`, a context manager): in this process
    without either. Open it after the options are checked: a local cluster spawns processes."""
    return open_executor(args.cluster, args.workers)


def add_corner_cutting_argument(parser) -> None:
    """`--no-corner-cutting`: the generated maps forbid a diagonal move between two obstacles."""
    parser.add_argument(
        "--no-corner-cutting",
        action="store_true",
        help="forbid diagonal moves between two obstacles (default: allowed, as in the original data)",
    )


def add_moves_argument(parser, default: str | None = "octile", what: str = "") -> None:
    """`--moves MODEL`: the movement model of the maps a command makes or imports (`vinadv.grid.moves`)."""
    parser.add_argument(
        "--moves",
        default=default,
        metavar="MOVES",  # checked by the library (`vinadv.grid.moves`): argparse choices would load it for --help
        help=(what or "movement model")
        + ": octile (default: 8 moves, diagonal sqrt 2, the original data's), moore (8 moves, all "
        "cost 1: GPPN's and the MP dataset's) or news (4 moves N, S, E, W, cost 1; no diagonal, so refused on maps "
        "that forbid corner cutting)",
    )


def add_db_argument(parser, when: str = "") -> None:
    """`--db`: the results database a command reads or writes (`vinadv.store.Store.open`); `when` begins the help of
    a command that reads it only with some option ("with --labels human: ")."""
    parser.add_argument(
        "--db", default=None, help=f"{when}database URL or SQLite file (default $VINADV_DB or vinadv.db)"
    )


#: library parameters whose flag is not `--` plus the name with dashes
FLAG_NAMES = {
    "n_starts": "--starts",
    "run_id": "--run",
    "harm_tol": "--harm-tolerance",
    "warmup_steps": "--warmup",
    "authors": "--author",
}


def flag(parameter: str) -> str:
    """The command-line flag of a library parameter: `shard_size` -> `--shard-size`."""
    return FLAG_NAMES.get(parameter, "--" + parameter.replace("_", "-"))


def option_values(args: argparse.Namespace, *names: str) -> dict[str, Any]:
    """The options `names` (their `args` attributes) as keyword arguments of the same names, for a library call that
    takes them as given: `option_values(args, "seed", "budget")` is `{"seed": args.seed, "budget": args.budget}`."""
    return {name: getattr(args, name) for name in names}


def cli_message(exc: InputError) -> str:
    """`exc`'s message for the command line: the first mention of each parameter it names becomes its flag. A word
    that is part of a path (`/tmp/data/x.npz`: next to a `/`, `\\` or `.`) is the path's, and stays."""
    message = str(exc)
    for parameter in getattr(exc, "parameters", ()):
        pattern = rf"(?<![\w/\\.-]){re.escape(parameter)}(?![\w/\\-]|\.\w)"
        message = re.sub(pattern, flag(parameter).replace("\\", "\\\\"), message, count=1)
    return message


def command_line() -> str:
    """The command line this process was started with, as a shell would take it back (recorded in outputs)."""
    return "vinadv " + shlex.join(sys.argv[1:])


def add_threads_argument(parser) -> None:
    """`--threads N`: PyTorch's CPU threads, applied by `set_threads`."""
    parser.add_argument("--threads", type=int, default=None, help="torch CPU threads (default: torch's choice)")


def set_threads(threads: int | None) -> None:
    """Apply `--threads`: PyTorch's CPU threads (None: PyTorch's own choice)."""
    if threads is not None:
        if threads < 1:
            raise InputError(f"--threads must be >= 1, got {threads}")
        set_torch_threads(threads)
