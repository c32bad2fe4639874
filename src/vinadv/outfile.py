"""The one way vinadv writes an output file: atomically, so a failure never leaves half a file or a temp file.

`atomic_output(path)` opens a temporary file in the target's own directory (so the final rename stays on one file
system), hands it to the caller, then flushes, fsyncs and renames it over `path`. On any error (full disk,
read-only target, an exception in the caller) the temporary file is removed and `path` keeps its old content;
OS errors become `OutputError` naming `path` (one line, exit status 2 in the CLI).

`check_output_path(path, inputs=...)` is the one rule every command applies to its outputs before its work: the
folder exists, the file can be written there (a probe file is made and removed), and it is none of the command's
inputs (the same file by its resolved path, through a symlink or as a hard link), which writing it would destroy.
`check_output_folder` is the same for an output folder (a report).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import IO

from vinadv.errors import OutputError, output_error

_UMASK = os.umask(0o022)
os.umask(_UMASK)  # read once: mkstemp makes 0600 files, outputs get the usual 0666 & ~umask


#: a command's inputs for `check_output_path`: what names each (its flag) -> a path, several paths, or None (not given)
Inputs = Mapping[str, "str | os.PathLike | Iterable[str | os.PathLike] | None"]


def check_output_path(
    path: str | os.PathLike, *, mkdir: bool = False, inputs: Inputs | None = None, probe: bool = True
) -> Path:
    """`path` as a Path, refused with OutputError when it cannot be an output file: a directory is in the way,
    its folder is missing (created instead when `mkdir`), it is one of `inputs` (`{"--maps": args.maps, ...}`: the
    same file, resolved, through a symlink or a hard link), or (`probe`) it cannot be written: an existing file that
    is read-only, or a folder where no file can be made (read-only, full, no permission). Call it before the work."""
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"cannot write {path}: is a directory (give a file name)")
    check_not_input(path, inputs)
    parent = path.parent
    if not parent.is_dir():
        if not mkdir or parent.exists():
            raise OutputError(f"cannot write {path}: folder {parent} does not exist")
        try:
            parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise output_error(path, exc) from None
    if probe:
        _probe(path, parent)
    return path


def check_output_folder(path: str | os.PathLike, *, inputs: Inputs | None = None) -> Path:
    """`path` as a Path, refused with OutputError when it cannot be an output folder (created by the command): a
    file is in the way (one of `inputs`, or another), or it exists and no file can be made in it."""
    path = Path(path)
    check_not_input(path, inputs)
    if path.exists() and not path.is_dir():
        raise OutputError(f"cannot write the folder {path}: it exists and is not a folder (give a folder name)")
    made = path  # the folder files go into, or the nearest existing one above it, where the command makes it
    while not made.exists() and made != made.parent:
        made = made.parent
    if not made.is_dir():
        raise OutputError(f"cannot write the folder {path}: {made} is not a folder")
    _probe(made / "index.html", made)
    return path


def check_not_input(path: str | os.PathLike, inputs: Inputs | None) -> None:
    """Refuse (OutputError) the output `path` when it is one of `inputs` (see `check_output_path`)."""
    for name, given in (inputs or {}).items():
        for source in _paths(given):
            if same_file(path, source):
                also = "" if str(source) == str(path) else f" ({source})"
                raise OutputError(
                    f"cannot write {path}: it is the input {name}{also}, which writing it would destroy; "
                    "give another output file"
                )


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether `a` and `b` are one file: by inode where both exist (symlinks and hard links), else by the
    resolved path (an output not written yet, or a dangling link to the input)."""
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        try:
            return Path(a).resolve() == Path(b).resolve()
        except (OSError, RuntimeError, ValueError):  # a symlink loop, a NUL in the name: not the same as anything
            return False


def _paths(given) -> list:
    if given is None:
        return []
    if isinstance(given, str | os.PathLike):
        return [given]
    return [p for p in given if p is not None]


def _probe(path: Path, parent: Path) -> None:
    """Refuse `path` when it cannot be written: an existing file not writable, or no file can be made in `parent`."""
    if path.exists() and not os.access(path, os.W_OK):
        raise OutputError(f"cannot write {path}: the file is read-only")
    try:
        fd, tmp = tempfile.mkstemp(dir=parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as exc:
        raise output_error(path, exc) from None
    os.close(fd)
    _remove(tmp)


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, mode: str = "wb", *, mkdir: bool = False, **open_kwargs) -> Iterator[IO]:
    """Write `path` through a temporary file: `with atomic_output(p, "w") as fh: fh.write(...)`.

    `mode` is "wb" or "w" (`open_kwargs` such as encoding, newline go to `open`). With `mkdir`, a missing folder is
    created. Raises OutputError (naming `path`) for OS errors; other exceptions pass through; either way nothing
    but the finished file is ever left.
    """
    path = check_output_path(path, mkdir=mkdir, probe=False)  # its own temporary file is the probe
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


def save_torch(obj: object, path: str | os.PathLike, *, mkdir: bool = False) -> None:
    """`torch.save(obj)` to `path` through `atomic_output`. torch wraps a failed write (a full disk) in a RuntimeError
    ("unexpected pos ..."): that is the OutputError naming `path`, and the temporary file is removed."""
    import torch  # noqa: PLC0415 (outfile stays light: only the commands that write weights load PyTorch)

    with atomic_output(path, "wb", mkdir=mkdir) as fh:
        try:
            torch.save(obj, fh)
        except RuntimeError as exc:
            cause = exc.__cause__ or exc.__context__
            if isinstance(cause, OSError):  # the file's own write failed: atomic_output reports it
                raise cause from None
            raise


def _remove(tmp: str) -> None:
    with contextlib.suppress(OSError):
        os.remove(tmp)
