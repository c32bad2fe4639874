"""The chunks of an entry stored in a database (`vinadv bench run --db`, `vinadv.bench.scoring.run_bench`): which
stored chunks may join this run's entry (their fingerprint: `reusable`), the chunks read back (`stored_chunks`), and
a chunk another run stored while this one computed it (`same_chunk`)."""

from __future__ import annotations

import json

from vinadv.bench.suites import UNRECORDED_REVISION, Suite
from vinadv.errors import InputError


def stored_fingerprint(stored: dict | None, fingerprint: dict) -> dict:
    """The fingerprint a stored chunk was computed with, in full: a chunk stored before fingerprints (`stored`
    None) is results format 1 of its entry's suite (the suite is in the entry key), its provenance unknown; one
    stored before strategy revisions were recorded ran every strategy at revision 1."""
    stored = {**fingerprint, "format": 1} if stored is None else stored
    return {"strategies": dict.fromkeys(fingerprint["strategies"], UNRECORDED_REVISION), **stored}


def _describe(fingerprint: dict, other: dict) -> str:
    """The parts of `fingerprint` that differ from `other`, in words."""
    parts = []
    if fingerprint.get("format") != other.get("format"):
        parts.append(f"results format {fingerprint.get('format')}")
    if fingerprint.get("suite") != other.get("suite"):
        parts.append(f"suite checksum {str(fingerprint.get('suite'))[:12]}")
    revisions, others = fingerprint.get("strategies") or {}, other.get("strategies") or {}
    parts += [
        f"{n} revision {revisions.get(n)}"
        for n in sorted(set(revisions) | set(others))
        if revisions.get(n) != others.get(n)
    ]
    mine, theirs = fingerprint.get("provenance") or {}, other.get("provenance") or {}
    if mine != theirs:
        if "version" in mine or "version" in theirs:
            parts.append(f"planner version {mine.get('version')!r}")
        files, others = mine.get("files") or {}, theirs.get("files") or {}
        changed = sorted(n for n in set(files) | set(others) if files.get(n) != others.get(n))
        parts += [f"{n} {files[n][:12] if n in files else '(not imported)'}" for n in changed[:4]]
    return ", ".join(parts) or "the same"


def reusable(stored: dict | None, fingerprint: dict) -> bool:
    """Whether a chunk stored with the fingerprint `stored` may join an entry computed with `fingerprint`: the same
    results format, suite checksum, strategy revisions and planner provenance (`stored_fingerprint`)."""
    return stored_fingerprint(stored, fingerprint) == fingerprint


def check_stored(suite: Suite, n_chunks: int):
    """The check of a stored chunk's result (`Store.read_bench_chunks`): the chunk schema
    (`vinadv.bench.validate.check_chunk`) and a fingerprint that is an object; chunks past the suite are not read."""
    from vinadv.bench.validate import chunk_problem  # noqa: PLC0415 (only with --db)

    def check(chunk: int, result) -> str | None:
        if not 0 <= chunk < n_chunks:
            return None
        problem = chunk_problem(result, suite, chunk)
        if problem is None and not isinstance(result.get("fingerprint", {}), dict):
            problem = "field 'fingerprint' is not an object"
        return problem

    return check


def stored_chunks(
    store, db: str, keys: list[str], suite: Suite, n_chunks: int, fingerprint: dict, resume: bool
) -> tuple[dict[int, dict], str]:
    """The chunks of this entry stored in `db` ({chunk: result}, each checked: `check_stored`) and the key they are
    stored under (the first of `keys` when none); InputError for chunks stored without `resume`, or one whose
    fingerprint is not this run's (`reusable`), naming both."""
    done: dict[int, dict] = {}
    for key in keys:  # continued under the key its chunks are stored under
        try:
            stored = store.read_bench_chunks(key, check_stored(suite, n_chunks))
        except InputError as exc:
            raise InputError(f"database {db}: {exc}", "db") from None
        done = {c: r for c, r in stored.items() if 0 <= c < n_chunks}
        if done:
            break
    else:
        key = keys[0]
    if done and not resume:
        raise InputError(
            f"database {db} holds {len(done)} chunks of this entry already: pass --resume to continue it", "resume"
        )
    for c, r in sorted(done.items()):  # one computation per entry: every chunk's fingerprint is this run's
        refuse_other_computation(f"database {db}", c, r, fingerprint, "was computed with")
    return done, key


def refuse_other_computation(
    where: str, chunk: int, stored: dict, fingerprint: dict, how: str, field: str = "resume", advice: str = ""
) -> None:
    """InputError naming both computations (and `field`) where the stored chunk `chunk`'s fingerprint (none: a chunk
    stored before chunks had one, results format 1) is not `reusable` by this run's `fingerprint`; `where` names the
    store ("database D", "parts: FILE"), `how` says how the chunk was stored; `advice` ends the message (default:
    use another database)."""
    if reusable(stored.get("fingerprint"), fingerprint):
        return
    theirs = stored_fingerprint(stored.get("fingerprint"), fingerprint)
    raise InputError(
        f"{where}: chunk {chunk} of this entry {how} {_describe(theirs, fingerprint)}, this run with "
        f"{_describe(fingerprint, theirs)}; the entry would mix two computations: {advice or 'use another database'}",
        field,
    )


#: the fields of a chunk's result that are not a function of the suite and the planner (`same_chunk`)
_CHUNK_VOLATILE = ("seconds", "fingerprint")


def same_chunk(
    where: str,
    chunk: int,
    stored: dict,
    result: dict,
    fingerprint: dict,
    field: str = "resume",
    how: str = "stored meanwhile by another run",
    than: str = "this run's",
) -> dict:
    """The chunk `chunk` stored before (`stored`, read back: by another run while this one computed it, where `how`
    says so), where it is the same as `result` (`than` names it) but for the time taken; InputError naming `field`
    and both where it was computed otherwise (another fingerprint) or came out otherwise (a planner that is not
    deterministic): the entry would mix two computations. `where` names the store ("database D", "parts: FILE")."""
    refuse_other_computation(where, chunk, stored, fingerprint, f"was {how} computed with", field)

    def kept(part: dict) -> dict:
        return {k: v for k, v in part.items() if k not in _CHUNK_VOLATILE}

    mine, theirs = kept(result), kept(stored)
    if json.dumps(mine, sort_keys=True) != json.dumps(theirs, sort_keys=True):
        fields = sorted(
            k
            for k in set(mine) | set(theirs)
            if json.dumps(mine.get(k), sort_keys=True) != json.dumps(theirs.get(k), sort_keys=True)
        )
        raise InputError(
            f"{where}: chunk {chunk} of this entry was {how}, with another result than {than} (field "
            f"{', '.join(map(repr, fields[:3])) or '?'}): the planner does not compute the same result twice; the "
            "first is kept",
            field,
        )
    return stored
