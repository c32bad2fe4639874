"""Recomputing an entry of format 2 from an older one (`vinadv bench run --reuse ENTRY`): the attacks whose
strategies did not change are taken from its per-map outcomes, the others computed again.

An entry of format 2 records what it was computed with (`computed_with`): the results format of its chunks
(`vinadv.bench.scoring.chunk_format`) and the revision of every strategy the suite runs
(`vinadv.attacks.strategies.Attack.revision`, bumped whenever a change alters a strategy's results). An entry made
before the field existed reads as results format 2 where its attack records carry efforts, else 1, and every revision
1 (`recorded_computation`).

The older entry must be of format 2, of this suite (its checksum) and of this planner (its spec, weights included):
InputError naming the field otherwise. The unit is the attack, a strategy within its group (`edit:strategy`, or
`edit:start+strategy` for a chain, `AttackGroup.start`): each strategy of a group runs alone, with the group's edit,
k and settings (`vinadv.robustness.robustness` makes one attack per strategy), so a group runs only its strategies
to compute (`plan_reuse`). An attack is taken when the recorded results format is this run's and its strategy has the
recorded revision, and, for a chain, its start strategy too (the chain's pairs depend on both). A computed chain
starts from its start's one-cell cells: those the entry holds (`per_map.start_cells`, where its start strategy is
unchanged), else from its start strategy computed again in its group (an entry made before the field). The clean part
of each chunk (`per_map.clean`, `per_map.chunks`) is taken when the results format is this run's. Each chunk is then
an ordinary chunk (`compute_chunk` with the strategies to compute and the records and start cells rebuilt from the
entry in a chunk's shape: `chunk_part`), stored with `--db` and resumed as usual; the entry's deterministic part is
that of a full recompute (but `per_map.start_cells`, absent where neither the older entry held them nor a start ran),
and its `time` says what was taken (`reused`: the older file's sha256 and the attacks taken).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from pathlib import Path

from vinadv.bench.outcomes import outcome
from vinadv.bench.scoring import computed_with, entry_json, strategy_revisions
from vinadv.bench.suites import ENTRY_FORMAT_2, UNRECORDED_REVISION, Suite
from vinadv.bench.validate import entry_problem
from vinadv.errors import InputError
from vinadv.planners.interface import Planner
from vinadv.vocabulary import label_counts


def recorded_computation(entry: dict, suite: Suite) -> dict:
    """What `entry` (of format 2, of `suite`) was computed with: its `computed_with`; for an entry made before the
    field, results format 2 where its attack records carry efforts (else 1) and every strategy's revision 1."""
    if "computed_with" in entry:
        return entry["computed_with"]
    records = [r for records in entry["per_map"]["attacks"].values() for r in records]
    efforts = bool(records) and all("effort" in r for r in records)
    return {
        "results_format": 2 if efforts else 1,
        "strategies": dict.fromkeys(strategy_revisions(suite), UNRECORDED_REVISION),
    }


@dataclasses.dataclass(frozen=True)
class ReusedEntry:
    """An older entry to reuse (`entry`, as read) and the sha256 of its file's bytes."""

    entry: dict
    sha256: str

    @classmethod
    def read(cls, path: str | os.PathLike) -> ReusedEntry:
        """The entry in the file `path`, checked (`vinadv.bench.verify.read_entry`: a valid entry of format 2);
        InputError naming `reuse`, the file and the field otherwise."""
        from vinadv.bench.verify import read_entry  # noqa: PLC0415 (the reader verify uses)

        try:
            entry = read_entry(path, reader="bench run --reuse")
            digest = hashlib.sha256(Path(path).read_bytes()).hexdigest()
        except InputError as exc:
            raise InputError(f"reuse: {exc}", "reuse") from None
        return cls(entry, digest)


@dataclasses.dataclass(frozen=True)
class ReusePlan:
    """What a recompute takes from an older entry: the strategies to compute per group (`computed`, {group index:
    strategies in the group's order}; a group absent is taken whole), whether the chunks' clean parts are taken
    (`clean`), the attacks taken (`reused`, their keys in suite order), the chains' starts whose one-cell cells are
    taken (`start_cells`, `edit:start` keys), the older entry's `per_map` and its file's sha256."""

    computed: dict[int, tuple[str, ...]]
    clean: bool
    reused: tuple[str, ...]
    per_map: dict = dataclasses.field(repr=False)
    entry_sha256: str = ""
    start_cells: tuple[str, ...] = ()

    def chunk_part(self, suite: Suite, chunk: int) -> dict:
        """The parts of chunk `chunk` taken from the entry, in a chunk's shape (`compute_chunk`'s `reused`): `clean`
        (where taken), `attacks`, each reused attack's records of the chunk's maps, and `start_cells` (where taken)."""
        lo, hi = chunk * suite.chunk, min(suite.n, (chunk + 1) * suite.chunk)
        part: dict = {
            "attacks": {key: [_chunk_record(r, lo, hi) for r in self.per_map["attacks"][key]] for key in self.reused}
        }
        if self.clean:
            means = {k: v for k, v in self.per_map["chunks"][chunk].items() if k != "maps"}
            part["clean"] = {**{name: values[lo:hi] for name, values in self.per_map["clean"].items()}, **means}
        if self.start_cells:
            part["start_cells"] = {key: self.per_map["start_cells"][key][lo:hi] for key in self.start_cells}
        return part

    def reused_time(self) -> dict:
        """The entry's `time.reused`: the older file's sha256 and the attacks taken from it."""
        return {"entry_sha256": self.entry_sha256, "attacks": list(self.reused)}


def _chunk_record(record: dict, lo: int, hi: int) -> dict:
    """An entry's record of one attack at one k (`per_map.attacks[key][i]`), maps `lo:hi`, as a chunk holds it:
    `pair`, `valid` and `broken` from the label (`vinadv.bench.outcomes.outcome`), the label counts of the pairs."""
    part = {name: values[lo:hi] for name, values in record.items() if name != "k"}
    o = outcome(part)
    return {
        **part,
        "pair": o.pair.tolist(),
        "valid": o.valid.tolist(),
        "broken": o.broken.tolist(),
        "counts": label_counts(o.label[o.pair]),
    }


def _start_group(suite: Suite, i: int) -> int:
    """The index of the group whose one-cell cells group `i` starts from (`AttackGroup.start`)."""
    group = suite.attacks[i]
    return next(
        j
        for j, g in enumerate(suite.attacks[:i])
        if g.start is None and g.edit == group.edit and g.max_obstacles == 1 and group.start in g.strategies
    )


def plan_reuse(suite: Suite, planner: Planner, reuse) -> ReusePlan:
    """What a recompute of `planner` on `suite` takes from the older entry `reuse` (a `ReusedEntry`, or an entry as a
    dict: its sha256 that of `entry_json`); module doc. InputError naming `reuse` and the field for an entry that is
    not of format 2 or not valid, of another suite, or of another planner or weights."""
    if not isinstance(reuse, ReusedEntry):
        reuse = ReusedEntry(reuse, hashlib.sha256(entry_json(reuse).encode()).hexdigest())
    entry = reuse.entry
    problem = entry_problem(entry)
    if problem is None and entry.get("format") != ENTRY_FORMAT_2:
        problem = f"field 'format' is {entry['format']!r}: an entry without per-map outcomes, not {ENTRY_FORMAT_2}"
    if problem is not None:
        raise InputError(f"reuse: {problem}: not an entry to reuse", "reuse")
    if entry["suite"]["checksum"] != suite.checksum:
        raise InputError(
            f"reuse: field 'suite.checksum' is {entry['suite']['checksum'][:12]} (suite {entry['suite']['name']}), "
            f"not this run's {suite.checksum[:12]} (suite {suite.name}): an entry of another suite",
            "reuse",
        )
    _check_planner(entry["planner"], planner.spec())
    per_map = entry["per_map"]
    expected = [min(suite.n, lo + suite.chunk) - lo for lo in range(0, suite.n, suite.chunk)]
    if [c["maps"] for c in per_map["chunks"]] != expected:
        raise InputError(f"reuse: field 'per_map.chunks' does not cut the maps as suite {suite.name} does", "reuse")
    recorded, now = recorded_computation(entry, suite), computed_with(suite, planner)
    same_format = recorded.get("results_format") == now["results_format"]
    revisions = recorded.get("strategies") or {}

    def unchanged(name: str) -> bool:
        return same_format and revisions.get(name) == now["strategies"][name]

    todo: dict[int, set[str]] = {}
    for i, group in enumerate(suite.attacks):  # a chain's pairs depend on its strategy and its start's
        for name in group.strategies:
            if not (unchanged(name) and (group.start is None or unchanged(group.start))):
                todo.setdefault(i, set()).add(name)
    stored = per_map.get("start_cells") or {}
    starts = {f"{g.edit}:{g.start}": (_start_group(suite, i), g.start) for i, g in enumerate(suite.attacks) if g.start}
    cells = tuple(key for key, (j, name) in starts.items() if key in stored and name not in todo.get(j, ()))
    for i, group in enumerate(suite.attacks):  # a computed chain without its start's cells: its start runs again
        key = f"{group.edit}:{group.start}"
        if group.start is not None and i in todo and key not in cells:
            todo.setdefault(starts[key][0], set()).add(group.start)
    computed = {i: tuple(s for s in suite.attacks[i].strategies if s in names) for i, names in sorted(todo.items())}
    reused = tuple(
        key
        for i, g in enumerate(suite.attacks)
        for name, key in zip(g.strategies, g.keys())
        if name not in computed.get(i, ())
    )
    for group in suite.attacks:
        for key in (k for k in group.keys() if k in reused):
            if [r["k"] for r in per_map["attacks"].get(key, [])] != list(group.ks):
                raise InputError(f"reuse: field 'per_map.attacks.{key}' is not the records of that attack", "reuse")
    for key in cells:  # a chain starts from them: cells of the suite's maps
        values = stored[key]
        if len(values) != suite.n or any(c is not None and max(c) >= suite.size for c in values):
            raise InputError(f"reuse: field 'per_map.start_cells.{key}' is not cells of the suite's maps", "reuse")
    # a search planner's clean part holds each map's cost ratio since results format 2 (`compute_chunk`)
    clean = same_format and ("search" not in per_map["chunks"][0] or "cost_ratio" in per_map["clean"])
    return ReusePlan(computed, clean, reused, per_map, reuse.sha256, cells)


def _check_planner(stored: dict, spec: dict) -> None:
    """InputError naming the field where the entry's planner `stored` is not this run's (`spec`; the old spelling of
    a name, `vin_robust`, is the same planner)."""
    from vinadv.planners.registry import canonical_name  # noqa: PLC0415 (light: the declarations)

    def named(s: dict) -> dict:
        return {**s, "name": canonical_name(s["name"])}

    if json.dumps(named(stored), sort_keys=True) == json.dumps(named(spec), sort_keys=True):
        return
    if named({**stored, "weights_sha256": None}) == named({**spec, "weights_sha256": None}):
        raise InputError(
            f"reuse: field 'planner.weights_sha256' is {str(stored.get('weights_sha256'))[:12]}, not this run's "
            f"{str(spec.get('weights_sha256'))[:12]}: an entry of other weights",
            "reuse",
        )
    raise InputError(
        f"reuse: field 'planner' is {json.dumps(stored, sort_keys=True)[:80]}, not this run's "
        f"{json.dumps(spec, sort_keys=True)[:80]}: an entry of another planner",
        "reuse",
    )
