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
from importlib import resources
from pathlib import Path

from vinadv import display
from vinadv.bench.comparison import FAMILY_NOTE, family_rows, family_table, mean_intervals, p_text, vs_next
from vinadv.bench.suites import ENTRY_FORMAT, ENTRY_FORMATS, FROZEN
from vinadv.bench.validate import entry_problem
from vinadv.errors import InputError
from vinadv.intervals import interval_fields, rate_interval
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
    "worst-case effort-harmful (k = 1)",
    "removal harmful",
    "vs next",
    "flags",
    "time",
)

#: what each column of the leaderboard says: the figure, its denominator, its interval (`render_legend`)
LEGEND = {
    "#": "the rank in the suite: by the worst-case harmful rate at one edited cell, the most robust first (ties: at "
    "the largest k, then the name).",
    "planner": "the planner as `--planner` names it, with its parameters' values (`wastar:w=2`), after the entry's "
    "display name where it has one, linking to its entry file; in the compact table the weights (first 12 hex "
    "digits of their SHA-256) and the entry's format (`v1`, `v2`) below it.",
    "weights": "the first 12 hex digits of the weights file's SHA-256; — for a planner without weights.",
    "clean success": "the share of the suite's maps on which the planner reaches the goal from the start on the "
    "unattacked map. Denominator: the suite's maps.",
    "clean optimal": "the share of the suite's maps whose clean path is optimal (Neural A*'s Opt). Denominator: the "
    "suite's maps.",
    "Exp": "search planners only: the share of A*'s expansions the planner saves on the clean maps, averaged over the "
    "maps (the Neural A* authors' Exp); — for a policy, which expands nothing. A mean, with its percentile "
    "bootstrap 95% interval over the maps where the entry holds each map's value (`per_map.clean.exp`; none in an "
    "entry computed before).",
    "worst-case harmful (k = 1)": "the share of the valid maps on which some attack of the suite with one edited "
    "cell makes a harmful pair (the adversarial path misses the goal, or its regret exceeds the clean path's by more "
    "than the harm tolerance). A map is valid when a pair was made and the planner reaches the goal on the clean "
    "map. Denominator: the valid maps.",
    "worst-case paper success (k = 1)": "the share of the valid maps on which some attack with one edited cell makes "
    "a pair the paper counts as a success (labelled UrP or FP). Denominator: the valid maps.",
    "worst-case harmful (largest k)": "the harmful rate of the worst case at the suite's largest k. Denominator: "
    "the valid maps at that k. In a `-v2` suite the worst case at k is over every attack of at most k edited cells, "
    "so it never falls as k grows; in a `-v1` suite it is over the attacks of exactly k cells (only the cheap ones "
    "make k > 1) and can be below the one at k = 1.",
    "worst-case effort-harmful (k = 1)": "search planners only: the share of the valid maps on which some attack "
    "with one edited cell makes an effort-harmful pair (the planner's search expands more cells on the adversarial "
    'map, and its growth is more than twice A*\'s on the same pair: DESIGN.md "Search effort"). Denominator: the '
    "valid maps. — for a planner that reports no expansions, or an entry computed before entries held efforts.",
    "removal harmful": "the harmful rate at one freed cell of the removal attack that harms the most valid maps. "
    "Denominator: that attack's valid maps.",
    "vs next": "McNemar's exact test (two-sided) of this planner against the next row's on the worst-case harmful "
    "verdict at k = 1, map by map, over the maps valid for both (`vinadv bench compare` tests every k): more robust "
    "than the next (or less, on their shared maps) where p < 0.05, else not distinguishable; — for the last row and "
    "for a v1 entry, which holds no per-map outcomes (needs a format 2 entry).",
    "flags": "the raised flags (gradient_masking, non_deterministic, too_weak): figures not to be taken at face "
    "value; — for none.",
    "time": "how long the entry took: the sum of its chunks' seconds, in minutes, and the device type; on the machine "
    "and load of the time, not a speed figure.",
}
#: every rate is shown with its interval (`LEGEND` says over which maps)
INTERVAL_NOTE = (
    "Every rate is followed by its Wilson 95% score interval in percentage points, over the maps counted in its "
    "denominator (`vinadv.intervals`): with 100 maps a rate near one half is known to about +-10 points, so two "
    "planners whose intervals overlap are not told apart by these figures."
)
#: the compact table (the docs column): `(title, LEGEND key)`; the intervals on a second line of each cell
COMPACT = (
    ("#", "#"),
    ("planner", "planner"),
    ("clean success", "clean success"),
    ("harmful, k = 1", "worst-case harmful (k = 1)"),
    ("paper success, k = 1", "worst-case paper success (k = 1)"),
    ("harmful, largest k", "worst-case harmful (largest k)"),  # the k in the title where the rows share it
    ("removal harmful", "removal harmful"),
    ("vs next", "vs next"),
    ("flags", "flags"),
    ("time", "time"),
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


def _search_exp(entry: dict) -> float | None:
    """Exp, Neural A*'s share of A*'s expansions a search planner saves on the clean maps; None for a policy."""
    search = entry["clean"].get("search")
    return None if not search else search.get("exp")  # a v1 entry may leave a figure out (null)


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
    by_suite: dict[str, list[tuple[dict, dict]]] = {}
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
        # a search planner's entry of format 2 holds efforts: the effort-harmful rate (absent elsewhere: None)
        effort = worst[0].get("effort_harmful_rate")
        _with_interval(row, "effort", effort, worst[0].get("effort_harmful"), worst[0].get("valid"))
        row["k"] = worst[-1]["k"]
        row["curve"] = [
            {
                "k": f["k"],
                "harmful_rate": f["harmful_rate"],
                **interval_fields("harmful_rate", f.get("harmful"), f.get("valid")),
            }
            for f in worst
        ]
        removal = removal or {"harmful_rate": None}
        _with_interval(row, "removal", removal["harmful_rate"], removal.get("harmful"), removal.get("valid"))
        row["flags"] = [name for name, f in e["flags"].items() if f["raised"]]
        row["time"] = compute_time(e)
        row["families"] = family_rows(e)
        row["means"] = mean_intervals(e)
        by_suite.setdefault(key, []).append((row, e))

    def order(item):
        r = item[0]
        return (
            1.0 if r["harmful"] is None else r["harmful"],
            1.0 if r["harmful_k"] is None else r["harmful_k"],
            r["planner"],
            r["weights"],
        )

    def released_first(item):
        return (item[0] not in FROZEN, item[0])

    return {suite: _ranked(sorted(rs, key=order)) for suite, rs in sorted(by_suite.items(), key=released_first)}


def _ranked(items: list[tuple[dict, dict]]) -> list[dict]:
    """The rows of one suite in rank order, each with its paired test against the next (`vs_next`: None for the last
    and where one of the two entries holds no per-map outcomes)."""
    for (row, e), (_, after) in zip(items, items[1:] + [(None, None)]):
        row["vs_next"] = None if after is None else vs_next(e, after)
    return [row for row, _ in items]


def _vs_next_lines(r: dict) -> tuple[str, str]:
    """The paired test's cell: its verdict against the next row, and its p-value ("—" without a test)."""
    test = r.get("vs_next")
    if test is None:
        return display.NONE, ""
    if test["verdict"] == "not distinguishable":
        return test["verdict"], p_text(test["p_value"])
    return f"{test['verdict']} than the next", p_text(test["p_value"])


def _pct_ci(r: dict, name: str) -> str:
    """A rate with its Wilson 95% interval in points: `57.7% [47.9, 67.0]` ("—" without a rate)."""
    interval = display.points(r[f"{name}_low"], r[f"{name}_high"])
    if r[name] is None or interval == display.NONE:
        return display.percent(r[name])
    return f"{display.percent(r[name])} {interval}"


def _exp_cell(r: dict) -> str:
    """Exp with its bootstrap interval in points where the entry holds each map's value: `12.3% [8.1, 16.0]`."""
    means = (r.get("means") or {}).get("clean_exp")
    interval = display.NONE if not means else display.points(means["low"], means["high"])
    if r["exp"] is None or interval == display.NONE:
        return display.percent(r["exp"])
    return f"{display.percent(r['exp'])} {interval}"


def _name(r: dict) -> str:
    """The row's name: its display name with the planner's label, or the label."""
    return r["planner"] if not r.get("display_name") else f"{r['display_name']} ({r['planner']})"


def _cells(r: dict) -> list[str]:
    return [
        _name(r),
        r["weights"],
        _pct_ci(r, "clean"),
        _pct_ci(r, "optimal"),
        _exp_cell(r),
        _pct_ci(r, "harmful"),
        _pct_ci(r, "paper"),
        f"{_pct_ci(r, 'harmful_k')} (k = {r['k']})",
        _pct_ci(r, "effort"),
        _pct_ci(r, "removal"),
        "{} ({})".format(*_vs_next_lines(r)) if r.get("vs_next") else display.NONE,
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


def _rate_lines(r: dict, name: str) -> tuple[str, str]:
    """A rate and its interval as two lines of a compact cell: `57.7%`, `[47.9, 67.0]` (the second empty without
    one)."""
    interval = display.points(r[f"{name}_low"], r[f"{name}_high"])
    return display.percent(r[name]), "" if interval == display.NONE else interval


def _second_line(text: str, compact: bool) -> str:
    """A cell's second line in Markdown: below the first in smaller type (`compact`), else after it."""
    return f"<br><small>{text}</small>" if compact else f" {text}"


def _compact_cells(r: dict, show_k: bool) -> list[tuple[str, str]]:
    """The compact table's cells of row `r` (after the rank), each `(first line, second line)`, plain text; the
    largest k beside its rate with `show_k` (else the column's title says it)."""
    largest = _rate_lines(r, "harmful_k")
    below = " · ".join(x for x in (r["weights"] if r["weights"] != "—" else "", f"entry {r['format']}") if x)
    return [
        (_name(r), below),
        _rate_lines(r, "clean"),
        _rate_lines(r, "harmful"),
        _rate_lines(r, "paper"),
        (f"{largest[0]} (k = {r['k']})" if show_k else largest[0], largest[1]),
        _rate_lines(r, "removal"),
        _vs_next_lines(r),
        (", ".join(r["flags"]) or "—", ""),
        _time_lines(r["time"]),
    ]


def _time_lines(time: str) -> tuple[str, str]:
    """`compute_time`'s text as two lines: the minutes, then the device (`12.3 min`, `cpu`)."""
    minutes, _, device = time.partition(" (")
    return minutes, device.removesuffix(")")


def render_legend(compact: bool = False) -> str:
    """The legend of the leaderboard's columns as a Markdown list (the compact table's, or the full one's), with
    the note on intervals."""
    keys = [key for _, key in COMPACT] if compact else ["#", *COLUMNS]
    titles = {key: title for title, key in COMPACT} if compact else {}
    lines = [f"- **{markdown_text(titles.get(k, k))}**: {LEGEND[k]}" for k in keys]
    return "\n".join([*lines, "", INTERVAL_NOTE])


def render_markdown(
    table: dict[str, list[dict]], link_prefix: str = "", compact: bool = False, legend: bool = False
) -> str:
    """The leaderboard as Markdown: one table per suite, the planner cell linking to `link_prefix` + entry file; the
    strings taken from the entries escaped (`markdown_text`). `compact`: the columns of `COMPACT`, each interval on
    a second line of its cell (a table that fits the docs' column; the cells hold `<br>` and `<small>`); `legend`:
    the columns' legend after the tables (`render_legend`)."""
    out = []
    for rs in table.values():
        titles = [t for t, _ in COMPACT] if compact else ["#", *COLUMNS]
        ks = {r["k"] for r in rs}
        if compact and len(ks) == 1:
            titles[titles.index("harmful, largest k")] = f"harmful, k = {next(iter(ks))}"
        out.append(f"### {markdown_text(rs[0]['suite'])}\n")
        out.append("| " + " | ".join(titles) + " |")
        out.append("|" + " --- |" * len(titles))
        for i, r in enumerate(rs, start=1):
            if compact:
                cells = [
                    markdown_text(a) + (f"<br><small>{markdown_text(b)}</small>" if b else "")
                    for a, b in _compact_cells(r, len(ks) > 1)
                ]
                name = markdown_text(_name(r))
                cells[0] = cells[0].replace(name, f"[{name}]({_link(link_prefix, r['file'])})", 1)
            else:
                cells = [markdown_text(c) for c in _cells(r)]
                cells[0] = f"[{cells[0]}]({_link(link_prefix, r['file'])})"
            out.append(f"| {i} | " + " | ".join(cells) + " |")
        out.append("")
        titles, family_cells = family_table(rs, _name)
        if family_cells:
            out += [FAMILY_NOTE, "", "| " + " | ".join(markdown_text(t) for t in titles) + " |"]
            out.append("|" + " --- |" * len(titles))
            for cells in family_cells:
                joined = [markdown_text(a) + (_second_line(markdown_text(b), compact) if b else "") for a, b in cells]
                out.append("| " + " | ".join(joined) + " |")
            out.append("")
    if legend:
        out += [render_legend(compact), ""]
    return "\n".join(out)


def stylesheet() -> str:
    """The report's stylesheet (`vinadv/report/templates/style.css`), read as package data: the leaderboard page is
    styled like the report's pages."""
    return (resources.files("vinadv.report") / "templates" / "style.css").read_text(encoding="utf-8")


#: the leaderboard's own rules on top of the report's stylesheet: an interval in smaller grey type
_BOARD_CSS = (
    ".ci { color: #555; font-size: .85em; } dl.legend dt { font-weight: 600; } dl.legend dd { margin: 0 0 .4em 1.5em; }"
)


def _html_text(markdown: str) -> str:
    """A legend's Markdown sentence as HTML text: escaped, code spans in `<code>`."""
    return re.sub(r"`([^`]*)`", r"<code>\1</code>", html.escape(markdown))


def k_curve_name(suite_key: str, ext: str) -> str:
    """The file name of a suite's k-curve figure (`k-curve.vin28-v1.svg`): the suite's key, one safe word."""
    return f"k-curve.{re.sub(r'[^A-Za-z0-9._-]+', '-', suite_key)}.{ext}"


def render_html(table: dict[str, list[dict]], link_prefix: str = "", figures: bool = False) -> str:
    """The leaderboard as a standalone HTML page styled like the report (its stylesheet inlined), every string
    escaped, the planner cell linking to its entry file, each rate's interval in smaller type beside it, and the
    columns' legend. `figures`: each suite's k curve (`k_curve_name(suite, "png")`, beside the page) under its
    table."""
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        "<title>vinadv robustness leaderboard</title>",
        f"<style>\n{stylesheet()}{_BOARD_CSS}\n</style></head><body>",
        "<h1>vinadv robustness leaderboard</h1>",
        "<p>Sorted by the worst-case harmful rate at one edited cell (the most robust first). "
        f'{_html_text(INTERVAL_NOTE)} The columns are explained <a href="#legend">below the tables</a>.</p>',
    ]
    for key, rs in table.items():
        parts.append(f"<h2>{html.escape(rs[0]['suite'])}</h2>")
        parts.append('<div class="scroll"><table class="numbers lead3">')
        parts.append(
            "<thead><tr><th>#</th>"
            + "".join(f'<th title="{html.escape(LEGEND[c], quote=True)}">{html.escape(c)}</th>' for c in COLUMNS)
            + "</tr></thead><tbody>"
        )
        for i, r in enumerate(rs, start=1):
            cells = [html.escape(c) for c in _cells(r)]
            cells = [re.sub(r" (\[[^\]]*\])", r' <span class="ci">\1</span>', c) for c in cells]
            link = html.escape(_link(link_prefix, r["file"]), quote=True)
            cells[0] = f'<a href="{link}">{cells[0]}</a>'
            parts.append(f"<tr><td>{i}</td>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
        parts.append("</tbody></table></div>")
        titles, family_cells = family_table(rs, _name)
        if family_cells:
            parts.append(f"<p>{_html_text(FAMILY_NOTE)}</p>")
            parts.append('<div class="scroll"><table class="numbers"><thead><tr>')
            parts.append("".join(f"<th>{html.escape(t)}</th>" for t in titles) + "</tr></thead><tbody>")
            for cells in family_cells:
                tds = "".join(f'<td>{html.escape(a)} <span class="ci">{html.escape(b)}</span></td>' for a, b in cells)
                parts.append(f"<tr>{tds}</tr>")
            parts.append("</tbody></table></div>")
        if figures:
            name = html.escape(k_curve_name(key, "png"), quote=True)
            svg = html.escape(k_curve_name(key, "svg"), quote=True)
            parts.append(
                f'<figure><img src="{name}" alt="harmful rate against k, {html.escape(key)}" style="max-width:640px">'
                f"<figcaption>The worst-case harmful rate against the number of edited cells k, one line per "
                f'planner, its Wilson 95% interval as a bar (<a href="{svg}">SVG</a>, <a href="{name}">PNG'
                "</a>).</figcaption></figure>"
            )
    parts.append('<h2 id="legend">Legend</h2><dl class="legend">')
    for c in ["#", *COLUMNS]:
        parts.append(f"<dt>{html.escape(c)}</dt><dd>{_html_text(LEGEND[c])}</dd>")
    parts.append("</dl>")
    parts.append("</body></html>\n")
    return "\n".join(parts)


def curve_series(rs: list[dict]) -> list[tuple[str, list[dict]]]:
    """The k curves of one suite's rows (`rows`): `[(name, points)]` in the table's order, each point the worst-case
    harmful rate at k with its interval (`harmful_rate_low`, `harmful_rate_high`); a planner listed with several
    weights is named with them."""
    names = [_name(r) for r in rs]
    return [(_name(r) if names.count(_name(r)) == 1 else f"{_name(r)} ({r['weights']})", r["curve"]) for r in rs]


def k_curve_figure(key: str, rs: list[dict]):
    """The k-curve figure of one suite (`vinadv.plot.k_curve` of `curve_series`): the worst-case harmful rate against
    k, one line per planner, with its interval."""
    from vinadv.plot.curves import k_curve  # noqa: PLC0415 (matplotlib: only to draw)

    return k_curve(
        curve_series(rs), title=f"{rs[0]['suite']}: worst case over the attacks", xlabel="edited cells (k)", dodge=0.06
    )


def write_k_curves(table: dict[str, list[dict]], out: str | os.PathLike) -> list[Path]:
    """Each suite's k curve as `k_curve_name(suite, "png")` and `.svg` in `out` (the SVG without a date: the same
    entries give the same bytes); the paths written."""
    from vinadv.plot.files import save_figure  # noqa: PLC0415 (matplotlib: only to draw)

    written = []
    for key, rs in table.items():
        for ext in ("png", "svg"):
            path = Path(out) / k_curve_name(key, ext)
            save_figure(k_curve_figure(key, rs), path)
            written.append(path)
    return written
