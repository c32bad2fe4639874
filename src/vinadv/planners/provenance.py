"""Where a bring-your-own planner's code comes from (`provenance`): what a resumed benchmark compares before it reuses
the chunks a run stored (`vinadv.bench.scoring.chunk_fingerprint`), kept out of the planner's spec (the entry key).

A planner module that declares `PLANNER_VERSION = "..."` (a string of at most 200 characters) is known by it: its
author says when its computation changed. Otherwise it is known by the files it imports from beside it: the sha256 of
every Python module loaded in this process from the planner's folder (the file's folder, or the package folder of a
`module:factory`), its subfolders included, the planner's own file among them; modules of vinadv itself and of the
Python installation (its prefix, a virtual environment's site-packages) are left out, so a planner file at the root
of a checkout is not known by the libraries it uses.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from vinadv.checksums import file_sha256

#: the module attribute a planner declares its version by
VERSION_ATTRIBUTE = "PLANNER_VERSION"


def _excluded() -> list[str]:
    """Folders whose modules are not the planner's: the Python installation and vinadv's own package (resolved)."""
    import vinadv  # noqa: PLC0415 (its folder)

    roots = {sys.prefix, sys.base_prefix, sys.exec_prefix, os.path.dirname(vinadv.__file__)}
    return [os.path.realpath(r) for r in roots if r]


def _under(path: str, folder: str) -> bool:
    """Whether the resolved `path` lies in the resolved `folder`, at any depth (not the folder itself)."""
    return path != folder and path.startswith(folder if folder.endswith(os.sep) else folder + os.sep)


def _resolved(name: str, folders: dict[str, str]) -> str:
    """`name` with every link resolved, as `Path(name).resolve()`; the folders resolved once each (`folders`, a
    cache): a process holds a thousand modules or more from a few hundred folders, and resolving each path afresh
    (a `stat` per part) took a quarter second for each planner loaded."""
    head, tail = os.path.split(name)
    if head not in folders:
        folders[head] = os.path.realpath(head)
    path = os.path.join(folders[head], tail)
    return os.path.realpath(path) if os.path.islink(path) else path


def source_provenance(module, folder: str | os.PathLike) -> dict:
    """The provenance of a planner whose factory is in `module`, loaded from `folder` (module doc):
    `{"version": TEXT}` where the module declares one, else `{"files": {path relative to folder: sha256}}`."""
    declared = getattr(module, VERSION_ATTRIBUTE, None)
    if isinstance(declared, str) and declared and len(declared) <= 200:
        return {"version": declared}
    folder = os.path.realpath(folder)
    # not a root the folder itself lies in (a planner package installed in site-packages is known by its own files)
    excluded = [e for e in _excluded() if e != folder and not _under(folder, e)]
    files = {}
    folders: dict[str, str] = {}
    for mod in list(sys.modules.values()):
        name = getattr(mod, "__file__", None)
        if not isinstance(name, str) or not name.endswith(".py"):
            continue
        path = _resolved(name, folders)
        if not _under(path, folder) or any(e == path or _under(path, e) for e in excluded):
            continue
        if os.path.isfile(path):
            files[Path(path).relative_to(folder).as_posix()] = file_sha256(path)
    return {"files": dict(sorted(files.items()))}
