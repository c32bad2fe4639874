"""The `vinadv` command: one entry point, one subcommand module per pipeline stage.

Each module in `vinadv.commands` exposes `register(subparsers)`, which adds its subcommands and sets
`func(args) -> int | None` on each parser. Bad input (`InputError`, a missing file) exits with status 2.
"""

from __future__ import annotations

import argparse
import gc
import hashlib
import importlib
import os
import signal
import sys
import threading
from pathlib import Path

from vinadv import __version__
from vinadv.commands import cli_message
from vinadv.commands.output import reserve_stdout
from vinadv.errors import InputError, one_line, os_error_message
from vinadv.seeds import check_seed

# Order is the order of `vinadv --help`; one module per stage of the pipeline.
COMMAND_MODULES = [
    "vinadv.commands.maps",
    "vinadv.commands.vin",
    "vinadv.commands.plan",
    "vinadv.commands.planners",
    "vinadv.commands.gppn",
    "vinadv.commands.neural_astar",
    "vinadv.commands.transpath",
    "vinadv.commands.attack",
    "vinadv.commands.classify",
    "vinadv.commands.run",
    "vinadv.commands.robustness",
    "vinadv.commands.bench",
    "vinadv.commands.store",
    "vinadv.commands.report",
    "vinadv.commands.serve",
]


# the trained weights shipped in the package (package data); `vinadv --version` names each with its checksum
SHIPPED_WEIGHTS_DIR = Path(__file__).resolve().parent / "weights"


def shipped_weights_checksums(folder: Path = SHIPPED_WEIGHTS_DIR) -> dict[str, str]:
    """SHA-256 (hex) of every weights file `*.pt` in `folder`, by file name, in name order.

    The same checksum runs record (`weights_sha256`), so a figure can be traced to the weights that made it. Reads
    the files with hashlib alone: `vinadv --version` must not import NumPy or PyTorch.
    """
    sums = {}
    for path in sorted(folder.glob("*.pt")):
        digest = hashlib.sha256()
        with path.open("rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
        sums[path.name] = digest.hexdigest()
    return sums


def version_text() -> str:
    """What `vinadv --version` prints: the version, then one `name  sha256` line per shipped weights file."""
    sums = shipped_weights_checksums()
    width = max((len(name) for name in sums), default=0)
    lines = [f"vinadv {__version__}", "shipped weights (sha256):" if sums else "shipped weights: none"]
    lines += [f"  {name:<{width}}  {digest}" for name, digest in sums.items()]
    return "\n".join(lines)


class VersionAction(argparse.Action):
    """`--version`: print `version_text()` and exit 0 (argparse's own version action prints one fixed string)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(version_text())
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="vinadv",
        description="Find and identify adversarial maps for learned path planners (VIN, GPPN, Neural A*, your own).",
    )
    parser.add_argument(
        "--version", action=VersionAction, help="show the version and the shipped weights' SHA-256 checksums, and exit"
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(subparsers)
    return parser


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is (as Ctrl-C raises KeyboardInterrupt), so that a command stopped either
    way cleans up the same: a run records that it was interrupted and says how to resume it."""


def _raise_terminated(_signum, _frame) -> None:
    raise Terminated()


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    on_main_thread = threading.current_thread() is threading.main_thread()  # where Python runs signal handlers
    previous = signal.signal(signal.SIGTERM, _raise_terminated) if on_main_thread else None
    try:
        return _run(args, argv)
    finally:
        if on_main_thread:
            signal.signal(signal.SIGTERM, previous)


def _run(args: argparse.Namespace, argv: list[str] | None) -> int:
    """Run the parsed command; every bad input, fault of the environment or interruption as one line and a status."""
    try:
        if getattr(args, "seed", None) is not None:
            check_seed(args.seed)  # every command's --seed, by one rule, before the command does anything
        with reserve_stdout(args):  # --json: standard output holds the result alone
            code = args.func(args)
    except InputError as exc:
        print(f"vinadv: error: {one_line(cli_message(exc))}", file=sys.stderr)
        return 2
    except FileNotFoundError as exc:
        print(f"vinadv: error: no such file: {one_line(str(exc.filename))}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # the reader went away (`vinadv export | head`): stop quietly, as a program killed by SIGPIPE would;
        # stdout goes to /dev/null so the interpreter's final flush cannot raise again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except OSError as exc:  # a file the command reads or writes: permissions, full disk, a folder in the way
        print(f"vinadv: error: {one_line(os_error_message(exc))}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:  # Ctrl-C (status 128 + SIGINT) or SIGTERM (128 + SIGTERM), as a shell reports
        terminated = isinstance(exc, Terminated)
        print(
            f"vinadv: {'terminated' if terminated else 'interrupted'}{f': {exc}' if str(exc) else ''}", file=sys.stderr
        )
        return 128 + int(signal.SIGTERM if terminated else signal.SIGINT)
    if argv is None:
        # Run as the program, which exits next. The interpreter's shutdown runs the garbage collector over every
        # object PyTorch and the rest created (hundreds of thousands): after a command that imported PyTorch, exit
        # took ~0.5 s on a quiet machine and 8 s beside busy ones; 2 s with them frozen (left to reference counting).
        gc.freeze()
    return int(code or 0)


if __name__ == "__main__":
    sys.exit(main())
