"""The leaderboard: benchmark entries (`vinadv.bench.scoring`) of folders and files as a Markdown and an HTML table,
per suite, sorted by the worst-case harmful rate at one edited cell (the most robust first; ties by the worst case at
the largest k, then by name), each row linking to its entry file, its flags shown beside it, and how long it took (the
sum of its chunks' seconds: on the machine and load of the time, not a speed figure). Every rate is shown with its
Wilson 95% interval (`vinadv.intervals`), computed here from the counts the entry holds (`vinadv.bench_entry/1`
entries included; a row says its entry's format, `v1` or `v2`, and a table of `v1` entries says so in its heading),
and each row carries it as `{rate}_low`, `{rate}_high`. A row shows the entry's display name
(`submission.display_name` of a `vinadv.bench_entry/2` entry) with the planner's label, or the label alone.

Every entry is checked against the entry schema (`vinadv.bench.validate`) before it is used: a bad one is one line
naming its file and field (`read_entries_checked`), the others still rendered. An entry whose suite checksum is not
one of the released suites' (`vinadv.bench.suites.FROZEN`) is listed under its own heading, labelled unknown, never
beside the released suite's entries. Markdown and HTML escape every string taken from an entry (`markdown_text`,
`html.escape`)."""

from __future__ import annotations

import html
import math
import os
import re
import urllib.parse
from pathlib import Path

from vinadv.bench.suites import ENTRY_FORMAT, ENTRY_FORMATS, FROZEN
from vinadv.bench.validate import entry_problem
from vinadv.errors import InputError
from vinadv.intervals import rate_interval
from vinadv.jsonfile import read_json_document

#: the columns: title, and how each reads an entry
COLUMNS = (
    "planner",
    "weights",
    "clean success",
    "clean optimal",
    "Exp",
    "worst-case harmful (k = 1)",
    "worst-case paper success (k = 1)",
    "worst-case harmful (largest k)",
    "removal harmful",
    "flags",
    "time",
)


#: the submission of an entry that carries none (`vinadv.bench_entry/1`): what `upgrade_entry` fills in
NO_SUBMISSION = {"display_name": None, "authors": [], "paper": None, "code": None, "external": False}


def upgrade_entry(entry: dict) -> dict:
    """An entry as read: its planner's name in today's spelling (`vin_robust` -> `vin-robust`), and a
    `vinadv.bench_entry/1` entry's `submission` filled in (`NO_SUBMISSION`: it had none); the rest as stored (a
    format 1 entry has no per-map outcomes: its intervals come from its counts). Its key (`entry_key`) is unchanged
    by this."""
    from vinadv.planners.registry import canonical_name  # noqa: PLC0415 (light: the declarations)

    planner = entry.get("planner")
    if isinstance(planner, dict) and isinstance(planner.get("name"), str):
        entry = {**entry, "planner": {**planner, "name": canonical_name(planner["name"])}}
    if entry.get("format") == ENTRY_FORMAT:
        entry = {**entry, "submission": dict(NO_SUBMISSION)}
    return entry


Sources = str | os.PathLike | list[str | os.PathLike] | tuple[str | os.PathLike, ...]


def read_entries(sources: Sources) -> list[tuple[Path, dict]]:
    """Every entry of `sources` (`entry_files`: a folder's `*.json`, or an entry file; one or a list), checked
    against the entry schema (`vinadv.bench.validate`) and upgraded (`upgrade_entry`); InputError for a source that is
    not there, or for the first file that is not a valid entry (naming the file and the field)."""
    entries, problems = read_entries_checked(sources)
    if problems:
        raise InputError(problems[0])
    return entries


def entry_files(sources: Sources) -> list[Path]:
    """The entry files of `sources` (a folder or a file, or a list of them): each folder's `*.json` in name order,
    each file as given, in the order given, a file named twice (the same file, by two paths) once. InputError for a
    source that is neither."""
    if isinstance(sources, (str, os.PathLike)):
        sources = [sources]
    files, seen = [], set()
    for source in map(Path, sources):
        if source.is_dir():
            found = sorted(source.glob("*.json"))
        elif source.exists():
            found = [source]
        else:
            raise InputError(f"{source}: no such folder or file (the result entries)", "sources")
        for path in found:
            if path.resolve() not in seen:
                seen.add(path.resolve())
                files.append(path)
    return files


def read_entries_checked(sources: Sources) -> tuple[list[tuple[Path, dict]], list[str]]:
    """The valid entries of `sources` as `read_entries` reads them, and one line per file that is not one (not
    readable, not JSON, not an entry, or a field the schema refuses), naming the file and the field; InputError for a
    source that is not there."""
    entries, problems = [], []
    for path in entry_files(sources):
        try:
            entry = _read_document(path)
        except InputError as exc:
            problems.append(str(exc))
            continue
        problem = entry_problem(entry)
        if problem is not None:
            problems.append(f"{path}: {problem}: not a valid benchmark entry")
            continue
        entries.append((path, upgrade_entry(entry)))
    return entries, problems


def _read_document(path: Path) -> dict:
    """The JSON document of `path`, an entry of one of `ENTRY_FORMATS` (InputError naming the file otherwise)."""
    try:
        return read_json_document(path, ENTRY_FORMATS[-1], "benchmark entry")
    except InputError as exc:
        for fmt in ENTRY_FORMATS[:-1]:
            try:
                return read_json_document(path, fmt, "benchmark entry")
            except InputError:
                pass
        raise exc from None


def _pct(value) -> str:
    return "—" if value is None else f"{100 * value:.1f}%"


def _search_exp(entry: dict) -> float | None:
    """Exp, Neural A*'s share of A*'s expansions a search planner saves on the clean maps; None for a policy."""
    search = entry["clean"].get("search")
    return None if not search else search["exp"]


def _removal_harmful(entry: dict) -> dict | None:
    """The figures at one cell of the removal attack that harms the largest share of valid maps (the worst over the
    removal attacks; ties: the first); None without a removal attack that has valid maps."""
    figures = [a["by_obstacles"][0] for a in entry["attacks"].values() if a["edit"] == "remove"]
    figures = [f for f in figures if f["harmful_rate"] is not None]
    return max(figures, key=lambda f: f["harmful_rate"]) if figures else None


def _optimal_count(clean: dict) -> int | None:
    """The clean maps whose path is optimal, recovered from the stored share (`percent_optimal`, that count over the
    maps: `round(share * maps)` is exact)."""
    share, maps = clean.get("percent_optimal"), clean.get("maps")
    return None if share is None or maps is None else round(share * maps)


def _with_interval(row: dict, name: str, rate, count, n) -> None:
    """`row[name]` = `rate`, and `row[name + "_low"]`, `row[name + "_high"]` its Wilson 95% interval from the counts
    (`vinadv.intervals`; None where there is no rate)."""
    row[name] = rate
    row[f"{name}_low"], row[f"{name}_high"] = (None, None) if rate is None else rate_interval(count, n)


def _value(value) -> str:
    """A config value as a label shows it: a number by `g`, anything else as text."""
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        return f"{value:g}"
    return str(value)


def planner_label(spec: dict) -> str:
    """The planner as `--planner` names it: its name, with the values of its registered parameters
    (`wastar:w=2`), so that two settings of one planner read apart."""
    from vinadv.planners.registry import REGISTRY  # noqa: PLC0415 (the registry: only to render)

    info = REGISTRY.get(spec["name"])
    config = spec.get("config") or {}
    given = [] if info is None else [p.name for p in info.params if p.name in config]
    if not given:
        return spec["name"]
    return spec["name"] + ":" + ",".join(f"{k}={_value(config[k])}" for k in given)


def compute_time(entry: dict) -> str:
    """How long the entry took: the sum of its chunks' seconds (a resumed entry's too, whatever the sessions), in
    minutes, and the device type it ran on; "—" for an entry without them."""
    chunks = (entry.get("time") or {}).get("chunks_s")
    if not chunks:
        return "—"
    device = (entry.get("machine") or {}).get("device")
    return f"{sum(chunks) / 60:.1f} min" + (f" ({device})" if device else "")


def suite_heading(suite: dict) -> tuple[str, str]:
    """(the key of a suite's table, its heading): the suite's name and checksum, and for a checksum that is not the
    released suite's of that name (`FROZEN`) the label "unknown", keyed apart from the released suite."""
    name, checksum = suite["name"], suite["checksum"]
    if FROZEN.get(name) == checksum:
        return name, f"{name} ({checksum[:12]})"
    return f"{name} (unknown {checksum[:12]})", f"{name} ({checksum[:12]}, unknown: not a released suite)"


def rows(entries: list[tuple[Path, dict]], base: str | os.PathLike | None = None) -> dict[str, list[dict]]:
    """{suite: rows, sorted}: each row the entry's file (its name; with `base`, its path from the folder `base`, where
    the pages link from), its cells' values and its raised flags. A suite is keyed by its name (for an unreleased
    checksum, by its name and checksum, labelled unknown: `suite_heading`); the released suites first."""
    by_suite: dict[str, list[dict]] = {}
    for path, e in entries:
        worst, clean = e["worst_case"], e["clean"]
        weights = e.get("weights_sha256")
        key, heading = suite_heading(e["suite"])
        removal = _removal_harmful(e)
        row = {
            "file": path.name if base is None else os.path.relpath(path, base).replace(os.sep, "/"),
            "format": "v" + e["format"].rsplit("/", 1)[-1],  # v1: `vinadv.bench_entry/1`
            # a suite's entries are all of its format: a table of format 1 entries says so in its heading
            "suite": heading + (", v1 entries" if e["format"] == ENTRY_FORMAT else ""),
            "planner": planner_label(e["planner"]),
            # the submission (an entry of format 1 has none: `NO_SUBMISSION`), for the renderers to show
            **{name: (e.get("submission") or NO_SUBMISSION).get(name) for name in NO_SUBMISSION},
            "weights": weights[:12] if weights else "—",
        }
        _with_interval(row, "clean", clean["success_rate"], clean.get("reached"), clean.get("maps"))
        _with_interval(row, "optimal", clean.get("percent_optimal"), _optimal_count(clean), clean.get("maps"))
        row["exp"] = _search_exp(e)
        _with_interval(row, "harmful", worst[0]["harmful_rate"], worst[0].get("harmful"), worst[0].get("valid"))
        _with_interval(row, "paper", worst[0]["paper_success_rate"], worst[0].get("broken"), worst[0].get("valid"))
        _with_interval(row, "harmful_k", worst[-1]["harmful_rate"], worst[-1].get("harmful"), worst[-1].get("valid"))
        row["k"] = worst[-1]["k"]
        removal = removal or {"harmful_rate": None}
        _with_interval(row, "removal", removal["harmful_rate"], removal.get("harmful"), removal.get("valid"))
        row["flags"] = [name for name, f in e["flags"].items() if f["raised"]]
        row["time"] = compute_time(e)
        by_suite.setdefault(key, []).append(row)

    def order(r):
        return (
            1.0 if r["harmful"] is None else r["harmful"],
            1.0 if r["harmful_k"] is None else r["harmful_k"],
            r["planner"],
            r["weights"],
        )

    def released_first(item):
        return (item[0] not in FROZEN, item[0])

    return {suite: sorted(rs, key=order) for suite, rs in sorted(by_suite.items(), key=released_first)}


def _pct_ci(r: dict, name: str) -> str:
    """A rate with its Wilson 95% interval in points: `57.7% [47.9, 67.0]` ("—" without a rate)."""
    low, high = r[f"{name}_low"], r[f"{name}_high"]
    if r[name] is None or low is None or high is None:
        return _pct(r[name])
    return f"{_pct(r[name])} [{100 * low:.1f}, {100 * high:.1f}]"


def _name(r: dict) -> str:
    """The row's name: its display name with the planner's label, or the label."""
    return r["planner"] if not r.get("display_name") else f"{r['display_name']} ({r['planner']})"


def _cells(r: dict) -> list[str]:
    return [
        _name(r),
        r["weights"],
        _pct_ci(r, "clean"),
        _pct_ci(r, "optimal"),
        _pct(r["exp"]),
        _pct_ci(r, "harmful"),
        _pct_ci(r, "paper"),
        f"{_pct_ci(r, 'harmful_k')} (k = {r['k']})",
        _pct_ci(r, "removal"),
        ", ".join(r["flags"]) or "—",
        r["time"],
    ]


#: what a Markdown table cell must not hold raw: inline markup, links, HTML, the cell separator
_MARKDOWN_SPECIAL = re.compile(r"([\\`*\[\]<>|&~]|(?<![A-Za-z0-9])_|_(?![A-Za-z0-9]))")
_CONTROL = re.compile(r"[\x00-\x1f\x7f\u2028\u2029]")


def markdown_text(value: str) -> str:
    """`value` as literal text in a Markdown table cell: line breaks and other control characters as spaces, every
    character that could start markup (a link, HTML, emphasis, code, a cell separator) backslash-escaped."""
    return _MARKDOWN_SPECIAL.sub(r"\\\1", _CONTROL.sub(" ", str(value)))


def _link(prefix: str, file: str) -> str:
    """A link target to the entry file: percent-encoded (a file name cannot end the link or start markup)."""
    return urllib.parse.quote(prefix + file, safe="/.-_~")


def render_markdown(table: dict[str, list[dict]], link_prefix: str = "") -> str:
    """The leaderboard as Markdown: one table per suite, the planner cell linking to `link_prefix` + entry file; the
    strings taken from the entries escaped (`markdown_text`)."""
    out = []
    for rs in table.values():
        out.append(f"### {markdown_text(rs[0]['suite'])}\n")
        out.append("| # | " + " | ".join(COLUMNS) + " |")
        out.append("|" + " --- |" * (len(COLUMNS) + 1))
        for i, r in enumerate(rs, start=1):
            cells = [markdown_text(c) for c in _cells(r)]
            cells[0] = f"[{cells[0]}]({_link(link_prefix, r['file'])})"
            out.append(f"| {i} | " + " | ".join(cells) + " |")
        out.append("")
    return "\n".join(out)


def render_html(table: dict[str, list[dict]], link_prefix: str = "") -> str:
    """The leaderboard as a standalone HTML page (escaped), the planner cell linking to its entry file."""
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8"><title>vinadv robustness leaderboard</title>',
        "<style>table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px}</style></head><body>",
        "<h1>vinadv robustness leaderboard</h1>",
        "<p>Sorted by the worst-case harmful rate at one edited cell (the most robust first). Each rate is followed "
        "by its 95% Wilson score interval in points, over the maps counted in its denominator.</p>",
    ]
    for rs in table.values():
        parts.append(f"<h2>{html.escape(rs[0]['suite'])}</h2><table>")
        parts.append("<tr><th>#</th>" + "".join(f"<th>{html.escape(c)}</th>" for c in COLUMNS) + "</tr>")
        for i, r in enumerate(rs, start=1):
            cells = [html.escape(c) for c in _cells(r)]
            link = html.escape(_link(link_prefix, r["file"]), quote=True)
            cells[0] = f'<a href="{link}">{cells[0]}</a>'
            parts.append(f"<tr><td>{i}</td>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
        parts.append("</table>")
    parts.append("</body></html>\n")
    return "\n".join(parts)
