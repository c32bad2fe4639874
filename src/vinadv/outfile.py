"""The one way vinadv writes an output file: atomically, so a failure never leaves half a file or a temp file.

`atomic_output(path)` opens a temporary file in the target's own directory (so the final rename stays on one file
system), hands it to the caller, then flushes, fsyncs and renames it over `path`. On any error (full disk,
read-only target, an exception in the caller) the temporary file is removed and `path` keeps its old content;
OS errors become `OutputError` naming `path` (one line, exit status 2 in the CLI).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

from vinadv.errors import OutputError, output_error

_UMASK = os.umask(0o022)
os.umask(_UMASK)  # read once: mkstemp makes 0600 files, outputs get the usual 0666 & ~umask


def check_output_path(path: str | os.PathLike, *, mkdir: bool = False) -> Path:
    """`path` as a Path, refused with OutputError when it cannot be an output file: a directory is in the way,
    or its folder is missing (created instead when `mkdir`)."""
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"cannot write {path}: is a directory (give a file name)")
    parent = path.parent
    if not parent.is_dir():
        if not mkdir or parent.exists():
            raise OutputError(f"cannot write {path}: folder {parent} does not exist")
        try:
            parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise output_error(path, exc) from None
    return path


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, mode: str = "wb", *, mkdir: bool = False, **open_kwargs) -> Iterator[IO]:
    """Write `path` through a temporary file: `with atomic_output(p, "w") as fh: fh.write(...)`.

    `mode` is "wb" or "w" (`open_kwargs` such as encoding, newline go to `open`). With `mkdir`, a missing folder is
    created. Raises OutputError (naming `path`) for OS errors; other exceptions pass through; either way nothing
    but the finished file is ever left.
    """
    path = check_output_path(path, mkdir=mkdir)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as exc:
        raise output_error(path, exc) from None
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)
        with os.fdopen(fd, mode, **open_kwargs) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        _remove(tmp)
        raise output_error(path, exc) from None
    except BaseException:
        _remove(tmp)
        raise


def _remove(tmp: str) -> None:
    with contextlib.suppress(OSError):
        os.remove(tmp)
