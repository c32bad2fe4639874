"""The `vinadv` command: one entry point, one subcommand module per pipeline stage.

Each module in `vinadv.commands` exposes `register(subparsers)`, which adds its subcommands and sets
`func(args) -> int | None` on each parser. Bad input (`InputError`, a missing file) exits with status 2.
"""

from __future__ import annotations

import argparse
import gc
import importlib
import os
import sys

from vinadv import __version__
from vinadv.commands import cli_message
from vinadv.errors import InputError, os_error_message

# Order is the order of `vinadv --help`; one module per stage of the pipeline.
COMMAND_MODULES = [
    "vinadv.commands.maps",
    "vinadv.commands.vin",
    "vinadv.commands.plan",
    "vinadv.commands.planners",
    "vinadv.commands.gppn",
    "vinadv.commands.attack",
    "vinadv.commands.classify",
    "vinadv.commands.run",
    "vinadv.commands.robustness",
    "vinadv.commands.store",
    "vinadv.commands.report",
    "vinadv.commands.serve",
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="vinadv",
        description="Find and identify adversarial maps for Value Iteration Network path planning.",
    )
    parser.add_argument("--version", action="version", version=f"vinadv {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code = args.func(args)
    except InputError as exc:
        print(f"vinadv: error: {cli_message(exc)}", file=sys.stderr)
        return 2
    except FileNotFoundError as exc:
        print(f"vinadv: error: no such file: {exc.filename}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # the reader went away (`vinadv export | head`): stop quietly, as a program killed by SIGPIPE would;
        # stdout goes to /dev/null so the interpreter's final flush cannot raise again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except OSError as exc:  # a file the command reads or writes: permissions, full disk, a folder in the way
        print(f"vinadv: error: {os_error_message(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("vinadv: interrupted", file=sys.stderr)
        return 130
    if argv is None:
        # Run as the program, which exits next. The interpreter's shutdown runs the garbage collector over every
        # object PyTorch and the rest created (hundreds of thousands): after a command that imported PyTorch, exit
        # took ~0.5 s on a quiet machine and 8 s beside busy ones; 2 s with them frozen (left to reference counting).
        gc.freeze()
    return int(code or 0)


if __name__ == "__main__":
    sys.exit(main())
