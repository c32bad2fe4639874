"""The index of the committed benchmark entries, shipped in the package for the model zoo (`vinadv planners`).

The entries themselves are committed under `docs/results/bench/` (`vinadv bench run --out`), which the wheel does not
carry; `vinadv bench leaderboard docs/results/bench --out OUT --index src/vinadv/bench/entries.json` writes this
index of them beside the leaderboard: per entry its file (the folder as given, then the name), the file's sha256,
the suite (name and checksum), the planner's spec and weights sha256, its headline figures (clean success, the
worst-case harmful rate at one edited cell, the raised flags) and its wall time. A test holds the shipped index to the
committed entries, so the two cannot drift apart. `entries_of` picks a planner's entries out of it by name and
weights checksum.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from vinadv.errors import InputError
from vinadv.jsonfile import read_json_document

INDEX_FORMAT = "vinadv.bench_index/1"
#: the index shipped with vinadv, of the entries committed under docs/results/bench/
SHIPPED_INDEX = Path(__file__).resolve().parent / "entries.json"


def make_index(entries: list[tuple[Path, dict]], folder: str | None = None) -> dict:
    """The index of `entries` (`vinadv.bench.leaderboard.read_entries`), their files named `folder/NAME`, or without
    `folder` as read (the paths as given)."""
    rows = []
    for path, e in entries:
        rows.append(
            {
                "file": path.as_posix() if folder is None else f"{folder.rstrip('/')}/{path.name}",
                "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
                "suite": e["suite"]["name"],
                "suite_checksum": e["suite"]["checksum"],
                "planner": e["planner"],
                "weights_sha256": e.get("weights_sha256"),
                "vinadv_version": e.get("vinadv_version"),
                "clean_success": e["clean"]["success_rate"],
                "worst_case_harmful_rate": e["worst_case"][0]["harmful_rate"],
                "flags": [name for name, f in e["flags"].items() if f["raised"]],
                "wall_s": (e.get("time") or {}).get("wall_s"),
            }
        )
    return {"format": INDEX_FORMAT, "entries": rows}


def index_json(index: dict) -> str:
    """The index as written: sorted keys, two-space indentation, a final newline."""
    return json.dumps(index, sort_keys=True, indent=2) + "\n"


def read_index(path: str | os.PathLike = SHIPPED_INDEX) -> list[dict]:
    """The entries of the index file `path` (default: the shipped one); InputError naming the file otherwise."""
    data = read_json_document(path, INDEX_FORMAT, "benchmark index")
    if not isinstance(data.get("entries"), list):
        raise InputError(f"{path}: field 'entries' is not a list")
    return data["entries"]


def entries_of(rows: list[dict], planner: str, weights_sha256: str | None) -> list[dict]:
    """The rows of `planner` (the registered name, as its spec records it) with those weights (None: a planner
    without weights), in suite order."""
    from vinadv.planners.registry import canonical_name  # noqa: PLC0415 (light: the declarations)

    name = canonical_name(planner)  # an old spelling, in the planner asked for or in the index
    found = [r for r in rows if canonical_name(r["planner"]["name"]) == name and r["weights_sha256"] == weights_sha256]
    return sorted(found, key=lambda r: (r["suite"], r["file"]))
