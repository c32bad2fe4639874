"""An entry computed in parts (`vinadv bench run --chunks LIST --out PART`, then `--parts PART ...`): some of the
suite's chunks of maps computed on one machine, or in one sitting, written as a part file; the entry made later from
the parts (and any chunk none of them holds, computed then). For what a database (`--db`) cannot do: machines that
share no database (a cluster's array jobs), sittings that keep only files.

A part file (`vinadv.bench_part/1`, JSON) holds its suite (name and checksum), the planner's spec, the fingerprint
its chunks were computed with (`vinadv.bench.scoring.chunk_fingerprint`) and its chunks' results (`{"chunk": result}`,
each `vinadv.bench.scoring.compute_chunk`'s). An entry takes a part's chunks only where the part is of its suite and
its fingerprint is the entry's, as `--resume` takes a database's (`vinadv.bench.chunkstore`); a chunk in two parts
must be the same in both (but for its time)."""

from __future__ import annotations

import hashlib
import json
import os
import re
from dataclasses import dataclass
from pathlib import Path

from vinadv.bench.chunkstore import refuse_other_computation, same_chunk
from vinadv.bench.suites import Suite
from vinadv.errors import InputError
from vinadv.records import BENCH_CHUNK, upgrade

PART_FORMAT = "vinadv.bench_part/1"


def parse_chunks(text: str, n_chunks: int) -> list[int]:
    """The chunks named by `text`: numbers and ranges `A-B` (both ends included), comma-separated, of 0 ..
    `n_chunks` - 1 (`0-4,9`); sorted, each once. InputError naming `chunks` for another text or a chunk out of range."""
    chunks: set[int] = set()
    for item in str(text).split(","):
        m = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", item)
        if m is None:
            raise InputError(f"chunks: {item.strip()!r} is not a chunk or a range A-B (e.g. 0-4,9)", "chunks")
        lo, hi = int(m[1]), int(m[2] if m[2] is not None else m[1])
        if lo > hi or hi >= n_chunks:
            raise InputError(f"chunks: {item.strip()!r} is not within the suite's chunks 0-{n_chunks - 1}", "chunks")
        chunks.update(range(lo, hi + 1))
    return sorted(chunks)


def make_part(suite: Suite, spec: dict, fingerprint: dict, chunks: dict[int, dict], seconds: float) -> dict:
    """The part file's document: `chunks` ({chunk: result}) of the planner of `spec` on `suite`, computed with
    `fingerprint`, in `seconds` of wall time."""
    return {
        "format": PART_FORMAT,
        "suite": {"name": suite.name, "checksum": suite.checksum},
        "planner": spec,
        "fingerprint": fingerprint,
        "chunks": {str(c): chunks[c] for c in sorted(chunks)},
        "wall_s": round(seconds, 3),
    }


def part_json(part: dict) -> str:
    """The part as written: sorted keys, one line per chunk (a part is read by programs, not people)."""
    body = ",\n".join(f"    {json.dumps(str(c))}: {json.dumps(r, sort_keys=True)}" for c, r in part["chunks"].items())
    head = json.dumps({k: v for k, v in part.items() if k != "chunks"}, sort_keys=True, indent=2)
    return f'{head[:-2]},\n  "chunks": {{\n{body}\n  }}\n}}\n'


@dataclass(frozen=True)
class Part:
    """A part file as read: its path, its document and the sha256 of its bytes."""

    path: str
    part: dict
    sha256: str

    @classmethod
    def read(cls, path: str | os.PathLike, suite: Suite) -> Part:
        """The part in the file `path`, of `suite`: InputError naming `parts`, the file and the field for a file that
        is not a part, a part of another suite (or checksum), or a chunk the schema refuses
        (`vinadv.bench.validate.chunk_problem`; each chunk is read in today's form, `vinadv.records`)."""
        from vinadv.bench.validate import chunk_problem  # noqa: PLC0415 (the schema: light, plain Python)
        from vinadv.jsonfile import read_json_document  # noqa: PLC0415 (light)

        def bad(why: str) -> InputError:
            return InputError(f"parts: {path}: {why}", "parts")

        try:
            raw = Path(path).read_bytes()
            part = read_json_document(path, PART_FORMAT, "benchmark entry's part")
        except (OSError, InputError) as exc:
            raise InputError(f"parts: {exc}", "parts") from None
        name = (part.get("suite") or {}).get("name") if isinstance(part.get("suite"), dict) else None
        if name != suite.name:
            raise bad(f"field 'suite.name' is {name!r}, not this run's suite {suite.name!r}")
        if part["suite"].get("checksum") != suite.checksum:
            raise bad(f"field 'suite.checksum' is not suite {suite.name}'s {suite.checksum[:12]}: another suite")
        for field in ("planner", "fingerprint", "chunks"):
            if not isinstance(part.get(field), dict):
                raise bad(f"field {field!r} is not an object")
        n_chunks = -(-suite.n // suite.chunk)
        chunks = {}
        for key, result in part["chunks"].items():
            if not (key.isdigit() and int(key) < n_chunks):
                raise bad(f"field 'chunks': {key!r} is not a chunk of suite {suite.name} (0-{n_chunks - 1})")
            try:
                result = upgrade(BENCH_CHUNK, result)
            except InputError as exc:
                raise bad(f"field 'chunks.{key}': {exc}") from None
            problem = chunk_problem(result, suite, int(key))
            if problem is not None:
                raise bad(f"field 'chunks.{key}': {problem}")
            chunks[int(key)] = result
        return cls(str(path), {**part, "chunks": chunks}, hashlib.sha256(raw).hexdigest())


def part_chunks(parts: list[Part], fingerprint: dict) -> dict[int, dict]:
    """The chunks of `parts` ({chunk: result}) for an entry computed with `fingerprint`: InputError naming `parts`
    and the file where a part's chunks were computed otherwise (`vinadv.bench.chunkstore.reusable`), or where a chunk
    in two parts differs."""
    chunks: dict[int, dict] = {}
    for part in parts:
        where = f"parts: {part.path}"
        for chunk, result in part.part["chunks"].items():
            # the part's fingerprint is its chunks': checked per chunk as a database's are
            result = {**result, "fingerprint": part.part["fingerprint"]}
            refuse_other_computation(
                where, chunk, result, fingerprint, "was computed with", "parts", "compute the part again"
            )
            if chunk in chunks:
                result = same_chunk(
                    where, chunk, chunks[chunk], result, fingerprint, "parts", "in an earlier part", "this part's"
                )
            chunks[chunk] = result
    return chunks
