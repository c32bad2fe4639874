"""The `vinadv` command: one entry point, one subcommand module per pipeline stage.

Each module in `vinadv.commands` exposes `register(subparsers)`, which adds its subcommands and sets
`func(args) -> int | None` on each parser. Bad input (`InputError`, a missing file) exits with status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from vinadv import __version__
from vinadv.errors import InputError

# Order is the order of `vinadv --help`; one module per stage of the pipeline.
COMMAND_MODULES = [
    "vinadv.commands.maps",
    "vinadv.commands.vin",
    "vinadv.commands.plan",
    "vinadv.commands.planners",
    "vinadv.commands.attack",
    "vinadv.commands.classify",
    "vinadv.commands.run",
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
        print(f"vinadv: error: {exc}", file=sys.stderr)
        return 2
    except FileNotFoundError as exc:
        print(f"vinadv: error: no such file: {exc.filename}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("vinadv: interrupted", file=sys.stderr)
        return 130
    return int(code or 0)


if __name__ == "__main__":
    sys.exit(main())
