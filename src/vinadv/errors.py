"""The exception types that mean "the user's input is wrong" or "the output the user named cannot be written".

The CLI turns them into a one-line message and exit status 2; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import errno
import os


class InputError(ValueError):
    """Bad input: a file, field or value that is wrong. The message names it.

    `parameters`: the library parameters the message names (say `"n"`, `"shard_size"`), in the order they
    appear in it. Library code speaks of parameters only; the command line shows the matching flags instead
    (`vinadv.commands.cli_message`).
    """

    def __init__(self, message: str, *parameters: str):
        super().__init__(message)
        self.parameters = parameters


class OutputError(InputError):
    """An output (a file, a folder, a database) that cannot be written: read-only, full disk, a directory in the
    way... The message names the path. A subclass of InputError, so every caller that reports bad input in one
    line (the CLI: exit status 2) reports it too."""


#: what the user can do about the common OS errors, shorter than `strerror`'s wording where it helps
_HINTS = {
    errno.ENOSPC: "no space left on the device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EROFS: "read-only file system",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
    errno.EISDIR: "is a directory",
    errno.ENOTDIR: "a parent is not a directory",
    errno.ENOENT: "no such file or directory",
}


def first_line(exc: BaseException) -> str:
    """The first line of an exception's message (its type name when it has none): for one-line errors."""
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


#: what `one_line` writes for the characters that would break a line or show as nothing: their escapes
_LINE_BREAKERS = {c: repr(chr(c))[1:-1] for c in (*range(0x20), 0x7F, 0x85, 0x2028, 0x2029)}


def one_line(text: str) -> str:
    """`text` on one line: line breaks and other control characters in it (a file name or a value the user gave)
    written as their escapes (`\\n`, `\\x1b`), so an error message stays the one line the CLI promises."""
    return text.translate(_LINE_BREAKERS)


def os_error_message(exc: OSError, path: str | os.PathLike | None = None) -> str:
    """One line for an OSError: the path it concerns (`path`, else the error's own) and what went wrong."""
    where = path if path is not None else exc.filename
    what = _HINTS.get(exc.errno or -1) or exc.strerror or str(exc) or type(exc).__name__
    return f"{where}: {what}" if where is not None else what


def output_error(path: str | os.PathLike, exc: OSError) -> OutputError:
    """The OutputError for an OSError met while writing `path`."""
    return OutputError(f"cannot write {os_error_message(exc, path)}")
