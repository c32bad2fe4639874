"""`--json` and `--quiet`: one meaning in every command, and how a command prints its result.

- `--json`: the result as one JSON line on standard output, and nothing else there (no progress bar or progress
  lines; notes go to standard error; while the command runs, `reserve_stdout` sends what anything else prints there,
  a planner of the user's say, to standard error).
- `--quiet`: no progress bars, progress lines, logs or notes; the result itself and errors still print.

A command adds the options with `add_output_options`, shows progress where `shows_progress(args)` (or through
`progress_bar`), prints notes with `note` and ends with `emit`, which prints the result as JSON or as text.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from tqdm import tqdm

#: standard output as it was before `reserve_stdout` sent the command's prints to standard error: where `emit` writes
_result_stream = None

#: the help of `--quiet`, the same in every command
QUIET_HELP = "no progress bars, progress lines, logs or notes; the result and errors still print"


def add_output_options(parser: argparse.ArgumentParser, json: str | None = None, quiet: bool = False) -> None:
    """Add `--json` to `parser` when `json` names what it prints ("the summary": "print the summary as JSON"), and
    `--quiet` (`QUIET_HELP`) when `quiet`: commands that report figures take `--json`, long ones `--quiet`."""
    if json is not None:
        parser.add_argument("--json", action="store_true", help=f"print {json} as JSON")
    if quiet:
        parser.add_argument("--quiet", action="store_true", help=QUIET_HELP)


def is_quiet(args: argparse.Namespace) -> bool:
    """Whether `--quiet` was given (False for a command without the option)."""
    return bool(getattr(args, "quiet", False))


def wants_json(args: argparse.Namespace) -> bool:
    """Whether `--json` was given (False for a command without the option)."""
    return bool(getattr(args, "json", False))


def shows_progress(args: argparse.Namespace) -> bool:
    """Whether a command shows progress bars and progress lines: neither with `--quiet` nor with `--json`."""
    return not (is_quiet(args) or wants_json(args))


@contextlib.contextmanager
def reserve_stdout(args: argparse.Namespace) -> Iterator[None]:
    """Run a command with `--json` inside this: what it prints to `sys.stdout` on the way (a bring-your-own planner's
    prints, a library's) goes to standard error, and standard output holds the result `emit` writes alone. Without
    `--json`, nothing changes."""
    global _result_stream
    if not wants_json(args):
        yield
        return
    previous, _result_stream = _result_stream, sys.stdout
    try:
        with contextlib.redirect_stdout(sys.stderr):
            yield
    finally:
        _result_stream = previous


def progress_bar(args: argparse.Namespace, *, hidden: bool = False, **options: Any) -> tqdm:
    """A `tqdm` progress bar (`options` are tqdm's: total, unit, desc, file ...), shown where `shows_progress(args)`
    and not `hidden` (a command's own reason: say, the rows it exports going to standard output)."""
    # imported when a bar is made: 50-80 ms on the 2-core machine, a third or more of `vinadv --help`'s start-up
    from tqdm import tqdm

    return tqdm(disable=hidden or not shows_progress(args), **options)


def progress_lines(args: argparse.Namespace) -> Callable[[str], None] | None:
    """A function that prints one progress line (an epoch done, flushed at once), or None where
    `shows_progress(args)` is false: the `log` argument of the library's long functions."""
    if not shows_progress(args):
        return None
    return lambda line: print(line, flush=True)


def note(args: argparse.Namespace, text: str) -> None:
    """Print `text`, a note beside the result (a warning, something done on the way), to standard error unless
    `--quiet`; it never mixes into the result on standard output."""
    if not is_quiet(args):
        print(text, file=sys.stderr)


def emit(
    args: argparse.Namespace,
    result: dict,
    text: str | Callable[[], None],
    json_default: Callable[[Any], Any] | None = None,
) -> int:
    """End a command: `result` as one JSON line with `--json` (`json_default` turns values JSON cannot hold into
    ones it can, as `json.dumps`' `default`), else `text`, a line or a function that prints; `--quiet` does not
    hide it. Returns the exit status, 0."""
    if wants_json(args):
        print(json.dumps(result, default=json_default), file=_result_stream or sys.stdout, flush=True)
    elif callable(text):
        text()
    else:
        print(text)
    return 0
