"""A bring-your-own planner's provenance (`vinadv.planners.provenance.source_provenance`) against the way it was
found before (every module's path resolved afresh with `pathlib`), side by side, in a process holding what
`vinadv run` loads (torch and the command line; a test process holds more).

    .venv/bin/python perf/provenance.py [--rounds 15] [--json]

The two must find the same files; the planner is examples/my_search_planner.py, which imports nothing from beside it.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import torch  # noqa: F401 (loaded, as in a run: its modules are among those looked through)

import vinadv.cli  # noqa: F401 (likewise)
from common import add_output_arguments, timed_side_by_side
from vinadv.checksums import file_sha256
from vinadv.planners.provenance import _excluded, source_provenance

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "my_search_planner.py"


def pathlib_provenance(folder) -> dict:
    """The files found as before: each module's path resolved with `Path.resolve`, its folders with `.parents`."""
    folder = Path(folder).resolve()
    excluded = [Path(e) for e in _excluded()]
    excluded = [e for e in excluded if e != folder and e not in folder.parents]
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


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_output_arguments(parser, rounds=15)
    args = parser.parse_args()
    sys.path.insert(0, str(EXAMPLE.parent))
    module = __import__(EXAMPLE.stem)
    fns = [lambda: pathlib_provenance(EXAMPLE.parent), lambda: source_provenance(module, EXAMPLE.parent)]
    best, results = timed_side_by_side(fns, args.rounds)
    assert results[0] == results[1], results
    out = {"modules": len(sys.modules), "pathlib_s": round(best[0], 4), "now_s": round(best[1], 4)}
    out["speedup"] = round(best[0] / best[1], 1)
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{out['modules']} modules loaded; found {sorted(results[1]['files'])}")
        print(f"  before (pathlib)  {best[0] * 1000:7.1f} ms")
        print(f"  now               {best[1] * 1000:7.1f} ms  ({out['speedup']}x faster)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
