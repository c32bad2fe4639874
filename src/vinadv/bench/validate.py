"""The schema of benchmark entries (`vinadv.bench.scoring`) and of their stored chunk results, checked in plain Python.

An entry is read from a file anyone can edit, a chunk result from a database anyone can write to: every field the
leaderboard, the index or `make_entry` reads is checked before it is used, so a malformed one is one line naming the
field (`entry_problem`, `chunk_problem`: the first problem, or None), never a traceback or a figure that lies.

What an entry must hold (fields not listed are not read, and not checked):
- `format`: one of `ENTRY_FORMATS`; `suite`: `name` (a non-empty string of at most `MAX_TEXT` characters) and `checksum`
  (64 hex digits; one of a released suite's, `suites.FROZEN`, or the leaderboard labels it unknown);
- `planner`: `name` (as `suite.name`), `config` (absent, null, or an object of plain JSON values, `MAX_DEPTH` deep at
  most, every float finite); `weights_sha256` (here and in `planner`): absent, null or 64 hex digits;
- `clean`: `success_rate` a rate (a finite number in [0, 1]); `percent_optimal` a rate or null; `maps`, `reached`
  counts (integers in [0, `MAX_COUNT`]); `mean_regret` finite or null; `gppn` null or its two rates; `search` null or
  its rates (`opt`, `exp`, `success`, `hmean`), `rows` a count, `cost_ratio`, `expansions`, `astar_expansions`
  finite and non-negative or null;
- `attacks`: an object of attacks, each with `edit` (`add` or `remove`), `strategy` (text) and `by_obstacles`, a
  non-empty list of figures; `worst_case`: a non-empty list of figures, `k` increasing; a figure: `k` an integer in
  [1, `MAX_K`], `harmful_rate` and `paper_success_rate` rates or null, `mean_regret` finite or null, its counts
  (`maps`, `valid`, `attacked`, `broken`, `harmful`, `reached`, `attacks`, each label's) counts;
- `flags`: an object of flags, each `raised` (true or false) and `why` (text);
- `time` (absent or null, or `wall_s` and every `chunks_s` finite and non-negative), `machine` (absent or null, or
  `device` text or null), `vinadv_version` (absent, null or text).

An entry of format 2 (`ENTRY_FORMAT_2`) also holds `submission` (`check_submission`: `display_name` text or null,
`authors` a list of at most `MAX_AUTHORS` names, `paper` and `code` null or http/https URLs with a host, `external` true
or false), `checks` (`gradient_masked` and `non_deterministic` true, false or null) and `per_map` (`check_per_map`:
one value per map in every list, one record per figure of every attack with its `k`, labels of the vocabulary or "",
a harmful map or a regret only where the pair is valid, the chunks' maps summing to the maps; where the planner
reports its expansions, every record's `effort` (a ratio >= 0 or null) and `effort_harmful` (true or false), neither
set on a map without a valid pair; a search planner's optional `per_map.clean.exp`, rates or null, and
`per_map.clean.cost_ratio`, >= 0 where the clean path reaches the goal and null elsewhere). A figure's
`effort_harmful` is a count and its `effort_harmful_rate` a rate. Its optional `computed_with` (`check_computed_with`:
entries made before it have none) holds `results_format` and `strategies`, integers >= 1; an entry recomputed from
another (`vinadv.bench.reuse`) has `time.reused`: `entry_sha256` (64 hex digits) and `attacks` (texts); one made from
parts (`vinadv.bench.parts`) has `time.parts`: per part its file's `sha256` and its `chunks` (counts). Its optional
`per_map.start_cells` holds, per attack of the entry, one cell per map: `[row, column]` (counts) or null.

Strings are checked for type and length only: the renderers escape them (`vinadv.bench.leaderboard`).
"""

from __future__ import annotations

import math
import re
import urllib.parse
from collections.abc import Callable

from vinadv.bench.suites import ENTRY_FORMAT_2, ENTRY_FORMATS, Suite
from vinadv.vocabulary import EDITS, LABELS

#: the longest name or text field read (characters)
MAX_TEXT = 200
#: the largest count (maps, pairs) an entry or chunk may hold
MAX_COUNT = 10**9
#: the largest number of edited cells k
MAX_K = 1000
#: how deep a planner's config may nest
MAX_DEPTH = 4
#: the most authors a submission names
MAX_AUTHORS = 50
_HEX64 = re.compile(r"[0-9a-f]{64}")
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")
_FIGURE_COUNTS = ("maps", "valid", "attacked", "broken", "harmful", "reached", "attacks", "effort_harmful")


class Bad(Exception):
    """A field that is not what the schema says: `field` (dotted path) and `why`."""

    def __init__(self, field: str, why: str):
        super().__init__(f"field '{field}' {why}")
        self.field, self.why = field, why


def _show(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _kind(value) -> str:
    return {dict: "an object", list: "a list", str: "a string", bool: "a boolean", type(None): "null"}.get(
        type(value), _show(value)
    )


def _obj(value, field: str) -> dict:
    if not isinstance(value, dict):
        raise Bad(field, f"is {_kind(value)}, expected an object")
    return value


def _list(value, field: str, nonempty: bool = False) -> list:
    if not isinstance(value, list):
        raise Bad(field, f"is {_kind(value)}, expected a list")
    if nonempty and not value:
        raise Bad(field, "is an empty list")
    return value


def _get(d: dict, key: str, field: str):
    if key not in d:
        raise Bad(f"{field}.{key}" if field else key, "is missing")
    return d[key]


def _number(value, field: str, lo: float | None = None, hi: float | None = None, null: bool = False):
    if value is None and null:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise Bad(field, f"is {_kind(value)}, expected a number" + (" or null" if null else ""))
    if not math.isfinite(value):
        raise Bad(field, f"is {_show(value)}, expected a finite number")
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        bounds = f"in [{lo:g}, {hi:g}]" if hi is not None else f">= {lo:g}"
        raise Bad(field, f"is {_show(value)}, expected a number {bounds}")
    return value


def rate(value, field: str, null: bool = False):
    """A share: a finite number in [0, 1] (or None where `null`)."""
    return _number(value, field, 0.0, 1.0, null)


def count(value, field: str, hi: int = MAX_COUNT) -> int:
    """A count: an integer in [0, hi]."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise Bad(field, f"is {_kind(value)}, expected an integer")
    if not 0 <= value <= hi:
        raise Bad(field, f"is {_show(value)}, expected an integer in [0, {hi}]")
    return value


def text(value, field: str, null: bool = False, nonempty: bool = False):
    """A string of at most `MAX_TEXT` characters (or None where `null`)."""
    if value is None and null:
        return None
    if not isinstance(value, str):
        raise Bad(field, f"is {_kind(value)}, expected a string" + (" or null" if null else ""))
    if len(value) > MAX_TEXT or (nonempty and not value):
        raise Bad(field, f"is a string of {len(value)} characters, expected 1 to {MAX_TEXT}")
    return value


def sha256(value, field: str, null: bool = False):
    """64 lowercase hex digits (or None where `null`)."""
    if value is None and null:
        return None
    if not isinstance(value, str) or not _HEX64.fullmatch(value):
        raise Bad(field, f"is {_show(value)}, expected a sha256 (64 hex digits)" + (" or null" if null else ""))
    return value


def _plain(value, field: str, depth: int = 0) -> None:
    """Plain JSON: strings, finite numbers, booleans, null, and lists and objects of them `MAX_DEPTH` deep."""
    if isinstance(value, float) and not math.isfinite(value):
        raise Bad(field, f"is {_show(value)}, expected a finite number")
    if isinstance(value, (dict, list)):
        if depth >= MAX_DEPTH:
            raise Bad(field, f"nests deeper than {MAX_DEPTH}")
        items = value.items() if isinstance(value, dict) else enumerate(value)
        for key, v in items:
            _plain(v, f"{field}.{key}" if isinstance(value, dict) else f"{field}[{key}]", depth + 1)
    elif isinstance(value, str):
        text(value, field)


def figures(value, field: str) -> dict:
    """One figure of an attack or of the worst case at one k (`vinadv.robustness.Figures`)."""
    f = _obj(value, field)
    count(_get(f, "k", field), f"{field}.k", MAX_K)
    if f["k"] < 1:
        raise Bad(f"{field}.k", f"is {f['k']}, expected an integer in [1, {MAX_K}]")
    rate(_get(f, "harmful_rate", field), f"{field}.harmful_rate", null=True)
    rate(_get(f, "paper_success_rate", field), f"{field}.paper_success_rate", null=True)
    if "effort_harmful_rate" in f:  # a planner that reports its expansions
        rate(f["effort_harmful_rate"], f"{field}.effort_harmful_rate", null=True)
    if "mean_regret" in f:
        _number(f["mean_regret"], f"{field}.mean_regret", null=True)
    for name in _FIGURE_COUNTS:
        if name in f:
            count(f[name], f"{field}.{name}")
    if "counts" in f:
        for label, n in _obj(f["counts"], f"{field}.counts").items():
            if label not in LABELS:
                raise Bad(f"{field}.counts", f"has label {_show(label)}, expected one of {', '.join(LABELS)}")
            count(n, f"{field}.counts.{label}")
    return f


def check_entry(entry) -> None:
    """Raise `Bad` for the first field of `entry` that is not what the schema (module doc) says."""
    e = _obj(entry, "(entry)")
    if e.get("format") not in ENTRY_FORMATS:
        raise Bad("format", f"is {_show(e.get('format'))}, expected one of {', '.join(ENTRY_FORMATS)}")
    suite = _obj(_get(e, "suite", ""), "suite")
    text(_get(suite, "name", "suite"), "suite.name", nonempty=True)
    sha256(_get(suite, "checksum", "suite"), "suite.checksum")
    planner = _obj(_get(e, "planner", ""), "planner")
    text(_get(planner, "name", "planner"), "planner.name", nonempty=True)
    if planner.get("config") is not None:
        _plain(_obj(planner["config"], "planner.config"), "planner.config")
    for key in planner:
        if key not in ("name", "config"):
            _plain(planner[key], f"planner.{key}", MAX_DEPTH - 1)
    sha256(planner.get("weights_sha256"), "planner.weights_sha256", null=True)
    sha256(e.get("weights_sha256"), "weights_sha256", null=True)
    text(e.get("vinadv_version"), "vinadv_version", null=True)
    clean = _obj(_get(e, "clean", ""), "clean")
    rate(_get(clean, "success_rate", "clean"), "clean.success_rate")
    rate(clean.get("percent_optimal"), "clean.percent_optimal", null=True)
    for name in ("maps", "reached"):
        if name in clean:
            count(clean[name], f"clean.{name}")
    _number(clean.get("mean_regret"), "clean.mean_regret", null=True)
    if clean.get("gppn") is not None:
        gppn = _obj(clean["gppn"], "clean.gppn")
        for name in ("percent_optimal", "percent_success"):
            rate(gppn.get(name), f"clean.gppn.{name}", null=True)
    if clean.get("search") is not None:
        search = _obj(clean["search"], "clean.search")
        for name in ("opt", "exp", "success", "hmean"):
            rate(search.get(name), f"clean.search.{name}", null=True)
        for name in ("cost_ratio", "expansions", "astar_expansions"):
            _number(search.get(name), f"clean.search.{name}", lo=0.0, null=True)
        if "rows" in search:
            count(search["rows"], "clean.search.rows")
    attacks = _obj(_get(e, "attacks", ""), "attacks")
    for key, attack in attacks.items():
        field = f"attacks.{key}"
        text(key, field)
        a = _obj(attack, field)
        if _get(a, "edit", field) not in EDITS:
            raise Bad(f"{field}.edit", f"is {_show(a['edit'])}, expected one of {', '.join(EDITS)}")
        text(a.get("strategy"), f"{field}.strategy", null=True)
        for i, f in enumerate(_list(_get(a, "by_obstacles", field), f"{field}.by_obstacles", nonempty=True)):
            figures(f, f"{field}.by_obstacles[{i}]")
    worst = _list(_get(e, "worst_case", ""), "worst_case", nonempty=True)
    for i, f in enumerate(worst):
        figures(f, f"worst_case[{i}]")
        if i and f["k"] <= worst[i - 1]["k"]:
            raise Bad(f"worst_case[{i}].k", f"is {f['k']}, not above worst_case[{i - 1}].k ({worst[i - 1]['k']})")
    for name, flag in _obj(_get(e, "flags", ""), "flags").items():
        text(name, f"flags.{name}", nonempty=True)
        flag = _obj(flag, f"flags.{name}")
        if not isinstance(_get(flag, "raised", f"flags.{name}"), bool):
            raise Bad(f"flags.{name}.raised", f"is {_kind(flag['raised'])}, expected true or false")
        text(flag.get("why", ""), f"flags.{name}.why")
    if e.get("time") is not None:
        t = _obj(e["time"], "time")
        _number(t.get("wall_s"), "time.wall_s", lo=0.0, null=True)
        if t.get("chunks_s") is not None:
            for i, s in enumerate(_list(t["chunks_s"], "time.chunks_s")):
                _number(s, f"time.chunks_s[{i}]", lo=0.0)
        if t.get("reused") is not None:  # recomputed from an older entry (`vinadv.bench.reuse`)
            reused = _obj(t["reused"], "time.reused")
            sha256(_get(reused, "entry_sha256", "time.reused"), "time.reused.entry_sha256")
            for i, key in enumerate(_list(_get(reused, "attacks", "time.reused"), "time.reused.attacks")):
                text(key, f"time.reused.attacks[{i}]")
        for i, part in enumerate(_list(t.get("parts") or [], "time.parts")):  # made from parts (`vinadv.bench.parts`)
            part = _obj(part, f"time.parts[{i}]")
            sha256(_get(part, "sha256", f"time.parts[{i}]"), f"time.parts[{i}].sha256")
            for j, chunk in enumerate(_list(_get(part, "chunks", f"time.parts[{i}]"), f"time.parts[{i}].chunks")):
                count(chunk, f"time.parts[{i}].chunks[{j}]")
    if e.get("machine") is not None:
        text(_obj(e["machine"], "machine").get("device"), "machine.device", null=True)
    if e["format"] == ENTRY_FORMAT_2:
        check_submission(_get(e, "submission", ""), "submission")
        checks = _obj(_get(e, "checks", ""), "checks")
        for name in ("gradient_masked", "non_deterministic"):
            if checks.get(name) is not None and not isinstance(checks[name], bool):
                raise Bad(f"checks.{name}", f"is {_kind(checks[name])}, expected true, false or null")
        check_per_map(_get(e, "per_map", ""), attacks, e["clean"])
        if "computed_with" in e:  # optional: entries made before it have none (`vinadv.bench.reuse`)
            check_computed_with(e["computed_with"])


def check_computed_with(value, field: str = "computed_with") -> None:
    """What an entry of format 2 was computed with: `results_format` an integer >= 1, `strategies` an object of
    strategy names (text) and their revisions (integers >= 1)."""
    c = _obj(value, field)
    if count(_get(c, "results_format", field), f"{field}.results_format", MAX_K) < 1:
        raise Bad(f"{field}.results_format", f"is {c['results_format']}, expected an integer >= 1")
    for name, revision in _obj(_get(c, "strategies", field), f"{field}.strategies").items():
        text(name, f"{field}.strategies", nonempty=True)
        if count(revision, f"{field}.strategies.{name}", MAX_K) < 1:
            raise Bad(f"{field}.strategies.{name}", f"is {revision}, expected an integer >= 1")


def url(value, field: str) -> str | None:
    """A link an entry shows: null, or an http or https URL with a host (no other scheme: `javascript:`, `file:`)."""
    if value is None:
        return None
    text(value, field)
    parts = urllib.parse.urlsplit(value)
    if parts.scheme not in ("http", "https") or not parts.netloc or _CONTROL.search(value) or " " in value:
        raise Bad(field, f"is {_show(value)}, expected an http or https URL")
    return value


def check_submission(value, field: str = "submission") -> None:
    """An entry's submission (`vinadv.bench.scoring.submission_fields`): `display_name` text or null, `authors` a list
    of names (at most `MAX_AUTHORS`), `paper` and `code` links (`url`) or null, `external` true or false."""
    s = _obj(value, field)
    text(_get(s, "display_name", field), f"{field}.display_name", null=True, nonempty=True)
    authors = _list(_get(s, "authors", field), f"{field}.authors")
    if len(authors) > MAX_AUTHORS:
        raise Bad(f"{field}.authors", f"holds {len(authors)} names, expected at most {MAX_AUTHORS}")
    for i, name in enumerate(authors):
        text(name, f"{field}.authors[{i}]", nonempty=True)
    for name in ("paper", "code"):
        url(_get(s, name, field), f"{field}.{name}")
    if not isinstance(_get(s, "external", field), bool):
        raise Bad(f"{field}.external", f"is {_kind(s['external'])}, expected true or false")


def _problem(check: Callable[..., None], *args) -> str | None:
    """What `check(*args)` refuses, as "field 'F' ...", or None where it accepts them: the one way the
    `*_problem` functions turn a `Bad` into their answer."""
    try:
        check(*args)
    except Bad as exc:
        return str(exc)
    return None


def submission_problem(submission) -> str | None:
    """The first problem of an entry's submission fields as "field 'F' ...", or None."""
    return _problem(check_submission, submission)


def check_per_map(value, attacks: dict, clean: dict) -> None:
    """The per-map outcomes of a `vinadv.bench_entry/2` entry (`vinadv.bench.outcomes`): one value per map in every
    list, a record per figure of every attack (its `k` that figure's), labels of the vocabulary, a harmful map or a
    regret only where the pair is valid, the chunks' maps summing to the maps."""
    p = _obj(value, "per_map")
    pc = _obj(_get(p, "clean", "per_map"), "per_map.clean")
    reached = _list(_get(pc, "reached", "per_map.clean"), "per_map.clean.reached", nonempty=True)
    n = len(reached)
    if n > MAX_COUNT:
        raise Bad("per_map.clean.reached", f"holds {n} values, expected at most {MAX_COUNT}")
    _bools(reached, "per_map.clean.reached", n)
    _reals(_get(pc, "regret", "per_map.clean"), "per_map.clean.regret", n)
    if clean.get("maps", n) != n:
        raise Bad("per_map.clean.reached", f"holds {n} values, expected {clean['maps']} (clean.maps)")
    chunks = _list(_get(p, "chunks", "per_map"), "per_map.chunks", nonempty=True)
    if "exp" in pc:  # a search planner's per-map protocol values (optional)
        for i, v in enumerate(_reals(pc["exp"], "per_map.clean.exp", n)):
            rate(v, f"per_map.clean.exp[{i}]", null=True)
    if "cost_ratio" in pc:
        for i, (v, ok) in enumerate(zip(_reals(pc["cost_ratio"], "per_map.clean.cost_ratio", n), reached)):
            if (v is None) == ok:
                why = "null where the clean path reaches the goal" if ok else f"{_show(v)} where it does not"
                raise Bad(f"per_map.clean.cost_ratio[{i}]", f"is {why}")
            _number(v, f"per_map.clean.cost_ratio[{i}]", lo=0.0, null=True)
    if ("exp" in pc or "cost_ratio" in pc) and not all(isinstance(c, dict) and "search" in c for c in chunks):
        name = "cost_ratio" if "cost_ratio" in pc else "exp"
        raise Bad(f"per_map.clean.{name}", "is a search planner's, where per_map.chunks hold no search")
    for i, c in enumerate(chunks):
        at = f"per_map.chunks[{i}]"
        c = _obj(c, at)
        count(_get(c, "maps", at), f"{at}.maps")
        if "search" in c:
            search = _obj(c["search"], f"{at}.search")
            count(_get(search, "rows", f"{at}.search"), f"{at}.search.rows")
            for name in ("opt", "exp", "success"):
                rate(_get(search, name, f"{at}.search"), f"{at}.search.{name}", null=True)
            for name in ("cost_ratio", "expansions", "astar_expansions"):
                _number(_get(search, name, f"{at}.search"), f"{at}.search.{name}", lo=0.0, null=True)
        else:
            for name in ("gppn_percent_optimal", "gppn_percent_success"):
                rate(_get(c, name, at), f"{at}.{name}")
    if sum(c["maps"] for c in chunks) != n:
        raise Bad("per_map.chunks", f"hold {sum(c['maps'] for c in chunks)} maps, expected {n}")
    records = _obj(_get(p, "attacks", "per_map"), "per_map.attacks")
    for key, attack in attacks.items():
        field = f"per_map.attacks.{key}"
        per_k = _list(_get(records, key, "per_map.attacks"), field)
        ks = [f["k"] for f in attack["by_obstacles"]]
        if len(per_k) != len(ks):
            raise Bad(field, f"holds {len(per_k)} records, expected {len(ks)} (one per figure of attacks.{key})")
        for i, (record, k) in enumerate(zip(per_k, ks)):
            _record(_obj(record, f"{field}[{i}]"), f"{field}[{i}]", n, k)
    if set(records) != set(attacks):
        extra = sorted(set(records) - set(attacks))[0]
        raise Bad(f"per_map.attacks.{extra}", "is an attack the entry has no figures of")
    has_effort = {
        f"per_map.attacks.{key}[{i}]": "effort_harmful" in record
        for key in attacks
        for i, record in enumerate(records[key])
    }
    with_effort = [field for field, has in has_effort.items() if has]
    if with_effort and len(with_effort) != len(has_effort):  # from the planner: every record has them, or none
        field = next(field for field, has in has_effort.items() if not has)
        raise Bad(f"{field}.effort_harmful", f"is missing, where {with_effort[0]} has efforts (all records or none)")
    if "worst_effort" in p:
        for i, values in enumerate(_list(p["worst_effort"], "per_map.worst_effort")):
            _reals(values, f"per_map.worst_effort[{i}]", n)
    if "start_cells" in p:  # the one-cell cells the chains start from (optional)
        for key, values in _obj(p["start_cells"], "per_map.start_cells").items():
            if key not in attacks:
                raise Bad(f"per_map.start_cells.{key}", "is an attack the entry has no figures of")
            _cells(values, f"per_map.start_cells.{key}", n)


def _cells(value, field: str, n: int, hi: int = MAX_COUNT) -> list:
    """Per map, a cell `[row, column]` (integers in [0, `hi`]) or null (no pair)."""
    values = _per_map(value, field, n)
    for i, cell in enumerate(values):
        if cell is not None:
            if not isinstance(cell, list) or len(cell) != 2:
                raise Bad(f"{field}[{i}]", f"is {_show(cell)}, expected [row, column] or null")
            for j, v in enumerate(cell):
                count(v, f"{field}[{i}][{j}]", hi=hi)
    return values


def _record(r: dict, at: str, n: int, k: int) -> None:
    """One attack's per-map record at k."""
    if _get(r, "k", at) != k or isinstance(r["k"], bool):
        raise Bad(f"{at}.k", f"is {_show(r['k'])}, expected {k}")
    labels = _per_map(_get(r, "label", at), f"{at}.label", n)
    for i, label in enumerate(labels):
        if label != "" and label not in LABELS:
            raise Bad(f"{at}.label[{i}]", f'is {_show(label)}, expected "" or one of {", ".join(LABELS)}')
    harmful = _bools(_get(r, "harmful", at), f"{at}.harmful", n)
    regret = _reals(_get(r, "regret", at), f"{at}.regret", n)
    _only_with_pairs(labels, (harmful, f"{at}.harmful"), (regret, f"{at}.regret"))
    if "effort" in r or "effort_harmful" in r:  # a planner that reports its expansions: both, or neither
        effort = _reals(_get(r, "effort", at), f"{at}.effort", n)
        verdict = _bools(_get(r, "effort_harmful", at), f"{at}.effort_harmful", n)
        _only_with_pairs(labels, (verdict, f"{at}.effort_harmful"), (effort, f"{at}.effort"))
        for i, e in enumerate(effort):
            if e is not None and e < 0:
                raise Bad(f"{at}.effort[{i}]", f"is {_show(e)}, expected a ratio >= 0")


def _only_with_pairs(labels: list, verdicts: tuple[list, str], values: tuple[list, str]) -> None:
    """A verdict true or a value not null only on the maps with a valid pair (`verdicts`, `values`: per map, with
    their fields)."""
    for i, (label, h, v) in enumerate(zip(labels, verdicts[0], values[0])):
        if label in ("", "invalid") and (h or v is not None):
            field = verdicts[1] if h else values[1]
            raise Bad(f"{field}[{i}]", f"is {_show(h if h else v)} on a map without a valid pair")


def entry_problem(entry) -> str | None:
    """The first problem of `entry` as "field 'F' ...", or None for an entry the schema accepts."""
    return _problem(check_entry, entry)


def _per_map(value, field: str, n: int) -> list:
    values = _list(value, field)
    if len(values) != n:
        raise Bad(field, f"holds {len(values)} values, expected {n} (one per map)")
    return values


def _bools(value, field: str, n: int) -> list:
    values = _per_map(value, field, n)
    for i, v in enumerate(values):
        if not isinstance(v, bool):
            raise Bad(f"{field}[{i}]", f"is {_kind(v)}, expected true or false")
    return values


def _reals(value, field: str, n: int) -> list:
    values = _per_map(value, field, n)
    for i, v in enumerate(values):
        _number(v, f"{field}[{i}]", null=True)
    return values


def check_chunk(result, suite: Suite, chunk: int) -> None:
    """Raise `Bad` for the first field of the stored result of chunk `chunk` of `suite` (`compute_chunk`) that is
    not what `make_entry` reads: its maps, the clean planner's per-map outcomes and means, every attack of the suite
    at every k with one value per map, the labels, the counts; the optional `start_cells`: a cell of the map or null
    per map for each start of a chain (`Suite.start_keys`)."""
    r = _obj(result, "(result)")
    lo = chunk * suite.chunk
    expected = min(suite.n, lo + suite.chunk) - lo
    if _get(r, "first_map", "") != lo or isinstance(r["first_map"], bool):
        raise Bad("first_map", f"is {_show(r['first_map'])}, expected {lo}")
    if _get(r, "maps", "") != expected or isinstance(r["maps"], bool):
        raise Bad("maps", f"is {_show(r['maps'])}, expected {expected}")
    n = expected
    clean = _obj(_get(r, "clean", ""), "clean")
    _bools(_get(clean, "reached", "clean"), "clean.reached", n)
    _reals(_get(clean, "regret", "clean"), "clean.regret", n)
    if "search" in clean:
        search = _obj(clean["search"], "clean.search")
        for name in ("exp", "cost_ratio"):  # each map's values (optional)
            if name in clean:
                _reals(clean[name], f"clean.{name}", n)
        count(_get(search, "rows", "clean.search"), "clean.search.rows")
        for name in ("opt", "exp", "success"):
            rate(_get(search, name, "clean.search"), f"clean.search.{name}", null=True)
        for name in ("cost_ratio", "expansions", "astar_expansions"):
            _number(_get(search, name, "clean.search"), f"clean.search.{name}", lo=0.0, null=True)
    else:
        for name in ("gppn_percent_optimal", "gppn_percent_success"):
            rate(_get(clean, name, "clean"), f"clean.{name}")
    attacks = _obj(_get(r, "attacks", ""), "attacks")
    for group in suite.attacks:
        for key in group.keys():
            field = f"attacks.{key}"
            per_k = _list(_get(attacks, key, "attacks"), field)
            if len(per_k) != len(group.ks):
                raise Bad(field, f"holds {len(per_k)} values of k, expected {len(group.ks)}")
            for k, part in enumerate(per_k):
                at = f"{field}[{k}]"
                part = _obj(part, at)
                for name in ("pair", "valid", "broken", "harmful"):
                    _bools(_get(part, name, at), f"{at}.{name}", n)
                _reals(_get(part, "regret", at), f"{at}.regret", n)
                labels = _list(_get(part, "label", at), f"{at}.label")
                if len(labels) != n:
                    raise Bad(f"{at}.label", f"holds {len(labels)} values, expected {n} (one per map)")
                for i, label in enumerate(labels):
                    if label != "" and label not in LABELS:
                        raise Bad(f"{at}.label[{i}]", f"is {_show(label)}, expected one of {', '.join(LABELS)}")
                if "effort" in part or "effort_harmful" in part:  # a planner that reports its expansions
                    _reals(_get(part, "effort", at), f"{at}.effort", n)
                    _bools(_get(part, "effort_harmful", at), f"{at}.effort_harmful", n)
                for label, c in _obj(_get(part, "counts", at), f"{at}.counts").items():
                    if label not in LABELS:
                        raise Bad(f"{at}.counts", f"has label {_show(label)}, expected one of {', '.join(LABELS)}")
                    count(c, f"{at}.counts.{label}")
    if "start_cells" in r:  # the one-cell cells the chains start from (optional: chunks stored before have none)
        cells = _obj(r["start_cells"], "start_cells")
        if sorted(cells) != sorted(suite.start_keys()):
            raise Bad("start_cells", f"holds {_show(sorted(cells))}, expected {_show(suite.start_keys())}")
        for key, values in cells.items():
            _cells(values, f"start_cells.{key}", n, hi=suite.size - 1)
    _number(_get(r, "seconds", ""), "seconds", lo=0.0)


def chunk_problem(result, suite: Suite, chunk: int) -> str | None:
    """The first problem of a stored chunk result as "field 'F' ...", or None for one the schema accepts."""
    return _problem(check_chunk, result, suite, chunk)
