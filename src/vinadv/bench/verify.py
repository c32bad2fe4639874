"""`vinadv bench verify`: does an entry someone sends hold what it says?

Two checks of a `vinadv.bench_entry/2` entry (`verify_entry`), each difference one line naming the field:

1. Every figure follows from the per-map outcomes the entry holds (`vinadv.bench.outcomes.entry_figures`): `clean`,
   every attack's figures at every k, the worst case at every k, the worst efforts and the flags (from the entry's
   `checks`) are recomputed and compared value for value; a search planner's chunk means (`exp`, `cost_ratio`) are
   compared with the mean of the maps' values where `per_map.clean` holds them (`outcomes.chunk_mean_problems`).
2. `chunks` chunks of maps, chosen by a seeded draw (`pick_chunks`), are recomputed with the planner
   (`vinadv.bench.scoring.compute_chunk`) and their per-map outcomes compared byte for byte (as JSON) with the
   entry's, as are the planner's checks (gradient masking, determinism) when at least one chunk is recomputed, and,
   where the entry holds them (`per_map.start_cells`: optional), the one-cell cells the chains start from.

An entry that is not a valid entry of format 2, of a suite this vinadv does not have (another checksum), or whose
planner is not the one loaded, is bad input (InputError), not a difference.

The entry's `computed_with` (`vinadv.bench.scoring.computed_with`; optional) is not compared: the chunks are
recomputed whole with this vinadv's strategies, so an entry recomputed from another (`bench run --reuse`) is checked
as any other, and one computed with an older revision of a strategy differs in that strategy's attacks (recompute it
with `--reuse`).
"""

from __future__ import annotations

import json
import os

import numpy as np

from vinadv.bench.flags import raise_flags
from vinadv.bench.outcomes import chunk_mean_problems, chunk_per_map, entry_figures
from vinadv.bench.suites import ENTRY_FORMAT, ENTRY_FORMAT_2, get_suite
from vinadv.bench.validate import entry_problem
from vinadv.errors import InputError


def _show(value) -> str:
    text = json.dumps(value, sort_keys=True)
    return text if len(text) <= 60 else text[:57] + "..."


def differences(field: str, stored, expected, source: str) -> list[str]:
    """One line per leaf where `stored` (the entry's) is not `expected` (what `source` gives), named by its dotted
    path under `field`; a whole list where the two differ in length or hold scalars (named at its first difference)."""
    if isinstance(stored, dict) and isinstance(expected, dict):
        out = []
        for key in sorted(set(stored) | set(expected), key=str):
            if key not in expected:
                out.append(f"field '{field}.{key}': in the entry, not in what {source} give")
            elif key not in stored:
                out.append(f"field '{field}.{key}': not in the entry, {_show(expected[key])} from {source}")
            else:
                out += differences(f"{field}.{key}", stored[key], expected[key], source)
        return out
    nested = isinstance(stored, list) and isinstance(expected, list) and len(stored) == len(expected)
    if nested and any(isinstance(v, (dict, list)) for v in stored + expected):
        return [
            line
            for i, (a, b) in enumerate(zip(stored, expected))
            for line in differences(f"{field}[{i}]", a, b, source)
        ]
    if json.dumps(stored, sort_keys=True) == json.dumps(expected, sort_keys=True):
        return []
    if isinstance(stored, list) and isinstance(expected, list) and len(stored) == len(expected):
        i = next(i for i, (a, b) in enumerate(zip(stored, expected)) if json.dumps(a) != json.dumps(b))
        return [f"field '{field}[{i}]': {_show(stored[i])} in the entry, {_show(expected[i])} from {source}"]
    return [f"field '{field}': {_show(stored)} in the entry, {_show(expected)} from {source}"]


def check_figures(entry: dict, suite) -> list[str]:
    """The differences between the entry's figures and those its per-map outcomes give (module doc, check 1)."""
    per_map = entry["per_map"]
    try:
        figures = entry_figures(suite, per_map)
    except (KeyError, IndexError, ValueError) as exc:
        return [f"field 'per_map': its outcomes do not give the suite's figures ({type(exc).__name__}: {exc})"]
    source = "its per-map outcomes"
    out = []
    for name in ("clean", "attacks", "worst_case"):
        out += differences(name, entry[name], figures[name], source)
    out += differences("per_map.worst_effort", per_map.get("worst_effort"), figures.get("worst_effort"), source)
    out += [
        f"field '{field}': {_show(stored)} in the entry, {_show(mean)} from {source} (per_map.clean)"
        for field, stored, mean in chunk_mean_problems(per_map)
    ]
    flags = raise_flags(suite, entry["checks"], figures["clean"]["success_rate"], figures["attacks"])
    return out + differences("flags", entry["flags"], flags, "its checks and per-map outcomes")


def pick_chunks(n_chunks: int, chunks: int, seed: int) -> list[int]:
    """`chunks` of the `n_chunks` chunks (all when more are asked), drawn without replacement by `seed`, in order."""
    rng = np.random.default_rng(seed)
    return sorted(int(c) for c in rng.choice(n_chunks, size=min(chunks, n_chunks), replace=False))


def _chunk_slice(per_map: dict, suite, chunk: int) -> dict:
    """The entry's per-map outcomes of the maps of `chunk`, in the form `chunk_per_map` gives one chunk's."""
    lo, hi = chunk * suite.chunk, min(suite.n, (chunk + 1) * suite.chunk)
    attacks = {
        key: [{k: v[lo:hi] if isinstance(v, list) else v for k, v in r.items()} for r in records]
        for key, records in per_map["attacks"].items()
    }
    clean = {name: values[lo:hi] for name, values in per_map["clean"].items()}
    return {"clean": clean, "chunks": [per_map["chunks"][chunk]], "attacks": attacks}


def read_entry(path: str | os.PathLike, reader: str = "verify") -> dict:
    """The entry in the file `path`, checked (a valid `vinadv.bench_entry/2` entry): InputError naming the file
    otherwise (a `vinadv.bench_entry/1` entry, which holds no per-map outcomes, included; `reader` names what needs
    them in the message)."""
    from vinadv.bench.leaderboard import upgrade_entry  # noqa: PLC0415 (the readers' upgrade)
    from vinadv.jsonfile import read_json_document  # noqa: PLC0415 (light)

    try:
        entry = read_json_document(path, ENTRY_FORMAT_2, "benchmark entry of format 2")
    except InputError:
        try:
            read_json_document(path, ENTRY_FORMAT, "benchmark entry")
        except InputError:
            raise InputError(f"{path}: not a {ENTRY_FORMAT_2} entry (field 'format', or not readable)") from None
        raise InputError(
            f"{path}: a {ENTRY_FORMAT} entry (field 'format'), which holds no per-map outcomes: {reader} needs a "
            f"format 2 entry "
            f"({ENTRY_FORMAT_2}; a format 1 entry is recomputed whole by `vinadv bench run` of its suite)"
        ) from None
    problem = entry_problem(entry)
    if problem is not None:
        raise InputError(f"{path}: {problem}: not a valid benchmark entry")
    return upgrade_entry(entry)


def verify_entry(
    entry: dict,
    chunks: int = 0,
    seed: int = 0,
    data: str | os.PathLike | None = None,
    planner=None,
    progress: bool = False,
) -> dict:
    """Verify `entry` (module doc; checked by `read_entry`): {"differences": lines, "chunks": the recomputed chunks}.
    `planner`: the entry's planner, loaded (needed when `chunks` > 0); InputError where its spec is not the entry's."""
    from vinadv.bench.scoring import compute_chunk, planner_checks, suite_maps  # noqa: PLC0415 (PyTorch)

    suite = get_suite(entry["suite"]["name"])
    if suite.checksum != entry["suite"]["checksum"]:
        raise InputError(
            f"suite {suite.name}: the entry's checksum {entry['suite']['checksum'][:12]} is not this vinadv's "
            f"{suite.checksum[:12]}: another suite, which this vinadv cannot recompute",
            "suite",
        )
    if suite.entry_format != ENTRY_FORMAT_2:
        raise InputError(f"suite {suite.name} makes {suite.entry_format} entries, not {ENTRY_FORMAT_2}", "suite")
    if chunks < 0:
        raise InputError(f"chunks must be >= 0, got {chunks}", "chunks")
    lines = check_figures(entry, suite)
    picked = pick_chunks(-(-suite.n // suite.chunk), chunks, seed) if chunks > 0 else []
    if picked:
        if planner is None:
            raise InputError("planner: recomputing chunks needs the entry's planner", "planner")
        spec = planner.spec()
        mine = {**spec, "name": entry["planner"]["name"]} if _same_name(spec, entry["planner"]) else spec
        if json.dumps(mine, sort_keys=True) != json.dumps(entry["planner"], sort_keys=True):
            raise InputError(
                f"planner: the planner loaded ({_show(spec)}) is not the entry's ({_show(entry['planner'])}): give its "
                "planner and weights",
                "planner",
            )
        maps = suite_maps(suite, data)
        lines += differences("checks", entry["checks"], planner_checks(suite, planner, maps), "the planner's checks")
        bar = None
        if progress:
            from tqdm import tqdm  # noqa: PLC0415 (only with a progress bar)

            bar = tqdm(total=len(picked), desc=f"verify {suite.name}", unit="chunk")
        for chunk in picked:
            result = compute_chunk(suite, planner, maps, chunk, progress=progress)
            again = chunk_per_map(suite, [result])
            source = f"the recomputed chunk {chunk}"
            stored = _chunk_slice(entry["per_map"], suite, chunk)
            for name in ("clean", "attacks"):
                found = differences(f"per_map.{name}", stored[name], again[name], source)
                lines += [_in_chunk(line, chunk, suite) for line in found]
            lines += differences(f"per_map.chunks[{chunk}]", stored["chunks"][0], again["chunks"][0], source)
            if "start_cells" in entry["per_map"]:
                lines += _start_cell_differences(entry["per_map"]["start_cells"], again, suite, chunk)
            if bar is not None:
                bar.update(1)
        if bar is not None:
            bar.close()
    return {"differences": lines, "chunks": picked}


def _start_cell_differences(stored: dict, again: dict, suite, chunk: int) -> list[str]:
    """One line per start of a chain whose cells in the entry (`stored`: `per_map.start_cells`) differ from those of
    the recomputed chunk (`again`: its `chunk_per_map`), named at the first map that differs."""
    lo, hi = chunk * suite.chunk, min(suite.n, (chunk + 1) * suite.chunk)
    source = f"the recomputed chunk {chunk}"
    theirs = again.get("start_cells") or {}
    out = []
    for key in sorted(set(stored) | set(theirs)):
        if key not in theirs:
            out.append(f"field 'per_map.start_cells.{key}': in the entry, not in what {source} give")
        elif key not in stored:
            out.append(f"field 'per_map.start_cells.{key}': not in the entry, {_show(theirs[key])} from {source}")
        else:
            mine = stored[key][lo:hi]
            i = next((i for i, (a, b) in enumerate(zip(mine, theirs[key])) if a != b), None)
            if i is not None:
                out.append(
                    f"field 'per_map.start_cells.{key}[{lo + i}]': {_show(mine[i])} in the entry, "
                    f"{_show(theirs[key][i])} from {source}"
                )
    return out


def _same_name(spec: dict, stored: dict) -> bool:
    """Whether the two specs name one planner (an old spelling of its name, `vin_robust`, included)."""
    from vinadv.planners.registry import canonical_name  # noqa: PLC0415 (light: the declarations)

    return canonical_name(spec["name"]) == canonical_name(stored["name"])


def _in_chunk(line: str, chunk: int, suite) -> str:
    """A difference found in a chunk's slice, its map index made the suite's: `field 'per_map.X[i]'` -> `[lo + i]`."""
    lo = chunk * suite.chunk
    head, sep, rest = line.partition("': ")
    name, bracket, index = head.rpartition("[")
    if bracket and index.endswith("]") and index[:-1].isdigit() and name.rsplit(".", 1)[-1] in _PER_MAP_LISTS:
        head = f"{name}[{lo + int(index[:-1])}]"
    return head + sep + rest


#: the per-map lists of an attack record and of the clean outcomes (one value per map)
_PER_MAP_LISTS = ("label", "harmful", "regret", "effort", "effort_harmful", "reached", "exp", "cost_ratio")
