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


def _excluded() -> list[Path]:
    """Folders whose modules are not the planner's: the Python installation and vinadv's own package."""
    import vinadv  # noqa: PLC0415 (its folder)

    roots = {sys.prefix, sys.base_prefix, sys.exec_prefix, os.path.dirname(vinadv.__file__)}
    return [Path(r).resolve() for r in roots if r]


def source_provenance(module, folder: str | os.PathLike) -> dict:
    """The provenance of a planner whose factory is in `module`, loaded from `folder` (module doc):
    `{"version": TEXT}` where the module declares one, else `{"files": {path relative to folder: sha256}}`."""
    declared = getattr(module, VERSION_ATTRIBUTE, None)
    if isinstance(declared, str) and declared and len(declared) <= 200:
        return {"version": declared}
    folder = Path(folder).resolve()
    # not a root the folder itself lies in (a planner package installed in site-packages is known by its own files)
    excluded = [e for e in _excluded() if e != folder and e not in folder.parents]
    files = {}
    for mod in list(sys.modules.values()):
        name = getattr(mod, "__file__", None)
        if not isinstance(name, str) or not name.endswith(".py"):
            continue
        path = Path(name).resolve()
        if folder not in path.parents or any(e == path or e in path.parents for e in excluded):
            continue
        if path.is_file():
            files[path.relative_to(folder).as_posix()] = file_sha256(path)
    return {"files": dict(sorted(files.items()))}
