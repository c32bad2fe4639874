"""Subcommands of `vinadv`; each module has `register(subparsers)`."""

from __future__ import annotations

import re

from vinadv.errors import InputError

#: library parameters whose flag is not `--` plus the name with dashes
FLAG_NAMES = {"n_starts": "--starts", "run_id": "--run", "harm_tol": "--harm-tolerance"}


def flag(parameter: str) -> str:
    """The command-line flag of a library parameter: `shard_size` -> `--shard-size`."""
    return FLAG_NAMES.get(parameter, "--" + parameter.replace("_", "-"))


def cli_message(exc: InputError) -> str:
    """`exc`'s message for the command line: the first mention of each parameter it names becomes its flag."""
    message = str(exc)
    for parameter in getattr(exc, "parameters", ()):
        pattern = rf"(?<![\w-]){re.escape(parameter)}(?![\w-])"
        message = re.sub(pattern, flag(parameter).replace("\\", "\\\\"), message, count=1)
    return message
