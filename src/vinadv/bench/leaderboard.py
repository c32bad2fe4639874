"""The leaderboard: benchmark entries (`vinadv.bench.entry`) of one folder as a Markdown and an HTML table, per suite,
sorted by the worst-case harmful rate at one edited cell (the most robust first; ties by the worst case at the
largest k, then by name), each row linking to its entry file, its flags shown beside it, and how long it took (the
sum of its chunks' seconds: on the machine and load of the time, not a speed figure)."""

from __future__ import annotations

import html
import os
from pathlib import Path

from vinadv.bench.suites import ENTRY_FORMAT
from vinadv.errors import InputError
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


def upgrade_entry(entry: dict) -> dict:
    """An entry as read: its planner's name in today's spelling (`vin_robust` -> `vin-robust`); the rest as stored.
    Its key (`entry_key`) is unchanged by this."""
    from vinadv.planners.registry import canonical_name  # noqa: PLC0415 (light: the declarations)

    planner = entry.get("planner")
    if isinstance(planner, dict) and isinstance(planner.get("name"), str):
        entry = {**entry, "planner": {**planner, "name": canonical_name(planner["name"])}}
    return entry


def read_entries(folder: str | os.PathLike) -> list[tuple[Path, dict]]:
    """Every entry file (`*.json` of format `ENTRY_FORMAT`) in `folder`, in name order, upgraded (`upgrade_entry`);
    InputError for a folder that
    is not there, or a JSON file that is not an entry's or is not valid JSON."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: no such folder", "folder")
    entries = []
    for path in sorted(folder.glob("*.json")):
        entries.append((path, upgrade_entry(read_json_document(path, ENTRY_FORMAT, "benchmark entry"))))
    return entries


def _pct(value) -> str:
    return "—" if value is None else f"{100 * value:.1f}%"


def _search_exp(entry: dict) -> float | None:
    """Exp, Neural A*'s share of A*'s expansions a search planner saves on the clean maps; None for a policy."""
    search = entry["clean"].get("search")
    return None if not search else search["exp"]


def _removal_harmful(entry: dict) -> float | None:
    """The share of valid maps some removal attack harms (the worst over the removal attacks, at one cell)."""
    rates = [a["by_obstacles"][0]["harmful_rate"] for a in entry["attacks"].values() if a["edit"] == "remove"]
    rates = [r for r in rates if r is not None]
    return max(rates) if rates else None


def planner_label(spec: dict) -> str:
    """The planner as `--planner` names it: its name, with the values of its registered parameters
    (`wastar:w=2`), so that two settings of one planner read apart."""
    from vinadv.planners.registry import REGISTRY  # noqa: PLC0415 (the registry: only to render)

    info = REGISTRY.get(spec["name"])
    config = spec.get("config") or {}
    given = [] if info is None else [p.name for p in info.params if p.name in config]
    if not given:
        return spec["name"]
    return spec["name"] + ":" + ",".join(f"{k}={config[k]:g}" for k in given)


def compute_time(entry: dict) -> str:
    """How long the entry took: the sum of its chunks' seconds (a resumed entry's too, whatever the sessions), in
    minutes, and the device type it ran on; "—" for an entry without them."""
    chunks = (entry.get("time") or {}).get("chunks_s")
    if not chunks:
        return "—"
    device = (entry.get("machine") or {}).get("device")
    return f"{sum(chunks) / 60:.1f} min" + (f" ({device})" if device else "")


def rows(entries: list[tuple[Path, dict]]) -> dict[str, list[dict]]:
    """{suite name: rows, sorted}: each row the entry's file, its cells' values and its raised flags."""
    by_suite: dict[str, list[dict]] = {}
    for path, e in entries:
        worst = e["worst_case"]
        weights = e.get("weights_sha256")
        row = {
            "file": path.name,
            "suite": f"{e['suite']['name']} ({e['suite']['checksum'][:12]})",
            "planner": planner_label(e["planner"]),
            "weights": weights[:12] if weights else "—",
            "clean": e["clean"]["success_rate"],
            "optimal": e["clean"].get("percent_optimal"),
            "exp": _search_exp(e),
            "harmful": worst[0]["harmful_rate"],
            "paper": worst[0]["paper_success_rate"],
            "harmful_k": worst[-1]["harmful_rate"],
            "k": worst[-1]["k"],
            "removal": _removal_harmful(e),
            "flags": [name for name, f in e["flags"].items() if f["raised"]],
            "time": compute_time(e),
        }
        by_suite.setdefault(e["suite"]["name"], []).append(row)

    def order(r):
        return (
            1.0 if r["harmful"] is None else r["harmful"],
            1.0 if r["harmful_k"] is None else r["harmful_k"],
            r["planner"],
            r["weights"],
        )

    return {suite: sorted(rs, key=order) for suite, rs in sorted(by_suite.items())}


def _cells(r: dict) -> list[str]:
    return [
        r["planner"],
        r["weights"],
        _pct(r["clean"]),
        _pct(r["optimal"]),
        _pct(r["exp"]),
        _pct(r["harmful"]),
        _pct(r["paper"]),
        f"{_pct(r['harmful_k'])} (k = {r['k']})",
        _pct(r["removal"]),
        ", ".join(r["flags"]) or "—",
        r["time"],
    ]


def render_markdown(table: dict[str, list[dict]], link_prefix: str = "") -> str:
    """The leaderboard as Markdown: one table per suite, the planner cell linking to `link_prefix` + entry file."""
    out = []
    for rs in table.values():
        out.append(f"### {rs[0]['suite']}\n")
        out.append("| # | " + " | ".join(COLUMNS) + " |")
        out.append("|" + " --- |" * (len(COLUMNS) + 1))
        for i, r in enumerate(rs, start=1):
            cells = _cells(r)
            cells[0] = f"[{cells[0]}]({link_prefix}{r['file']})"
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
        "<p>Sorted by the worst-case harmful rate at one edited cell (the most robust first).</p>",
    ]
    for rs in table.values():
        parts.append(f"<h2>{html.escape(rs[0]['suite'])}</h2><table>")
        parts.append("<tr><th>#</th>" + "".join(f"<th>{html.escape(c)}</th>" for c in COLUMNS) + "</tr>")
        for i, r in enumerate(rs, start=1):
            cells = [html.escape(c) for c in _cells(r)]
            link = html.escape(link_prefix + r["file"], quote=True)
            cells[0] = f'<a href="{link}">{cells[0]}</a>'
            parts.append(f"<tr><td>{i}</td>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
        parts.append("</table>")
    parts.append("</body></html>\n")
    return "\n".join(parts)
