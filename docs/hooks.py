"""MkDocs hook: the Results page's figures, read at build time from committed JSON, never copied by hand.

Each shipped weights file `src/vinadv/weights/NAME.pt` has `NAME.metrics.json` beside it: the evaluation on the
1,000 held-out maps, written by `vinadv vin eval --out` or `vinadv eval --out`, with the command that made it. A page
holding one of the markers below gets the table built from those files in its place, so a re-measured metrics file
changes the page at the next build and nothing goes stale. The README's headline table is the same table; a test
(`tests/test_docs.py`) holds the two equal.

Markers: `<!-- vinadv:weights-table -->` (one row per shipped weights file), `<!-- vinadv:weights-commands -->`
(the command and checksum behind each row), `<!-- vinadv:by-length -->` (rollout success by the optimal path's move
count, for the metrics files that have it).
"""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WEIGHTS_DIR = ROOT / "src" / "vinadv" / "weights"

WEIGHTS_TABLE = "<!-- vinadv:weights-table -->"
WEIGHTS_COMMANDS = "<!-- vinadv:weights-commands -->"
BY_LENGTH = "<!-- vinadv:by-length -->"


def percent(fraction: float | None) -> str:
    """A share as a percentage with one decimal; two where one would round a share below 1 up to 100%."""
    if fraction is None:
        return ""
    text = f"{100 * fraction:.1f}%"
    return f"{100 * fraction:.2f}%" if text == "100.0%" and fraction < 1 else text


def weights_metrics(folder: Path = WEIGHTS_DIR) -> list[dict]:
    """One entry per `*.metrics.json` in `folder`, in file name order.

    Both layouts are read: `vinadv vin eval --json` (the vinadv protocol's figures at the top level) and
    `vinadv eval --json` (`{"planner", "vinadv": {...}, "gppn": {...}}`). Each entry has `weights` (the file name),
    `planner` (the registry name: the file name without the map size), `sha256`, `command`, `vinadv` (figures) and
    `gppn` (figures or None).
    """
    entries = []
    for path in sorted(folder.glob("*.metrics.json")):
        data = json.loads(path.read_text())
        weights = path.name.removesuffix(".metrics.json") + ".pt"
        figures = data.get("vinadv", data)
        size = figures["size"]
        entries.append(
            {
                "weights": weights,
                "planner": weights.removesuffix(".pt").replace(str(size), "", 1),
                "sha256": data.get("weights_sha256") or data["planner"]["weights_sha256"],
                "command": data["command"],
                "vinadv": figures,
                "gppn": data.get("gppn"),
            }
        )
    return entries


def weights_table(folder: Path = WEIGHTS_DIR) -> str:
    """The shipped weights' figures as a Markdown table (no trailing newline)."""
    rows = [
        "| planner | weights | rollout success | optimal paths | action accuracy | GPPN's %Suc | GPPN's %Opt |",
        "|---|---|---|---|---|---|---|",
    ]
    for entry in weights_metrics(folder):
        fig, gppn = entry["vinadv"], entry["gppn"] or {}
        rows.append(
            f"| `{entry['planner']}` | `{entry['weights']}` | {percent(fig['success_rate'])} of "
            f"{fig['rollouts']:,} | {percent(fig['optimal_rate'])} | {percent(fig['action_accuracy'])} | "
            f"{percent(gppn.get('percent_success'))} | {percent(gppn.get('percent_optimal'))} |"
        )
    return "\n".join(rows)


def weights_commands(folder: Path = WEIGHTS_DIR) -> str:
    """The command and weights checksum behind each row of `weights_table`, as a Markdown list."""
    return "\n".join(
        f"- `{entry['weights']}` (SHA-256 `{entry['sha256'][:16]}…`): `{entry['command']}`"
        for entry in weights_metrics(folder)
    )


def by_length_table(folder: Path = WEIGHTS_DIR) -> str:
    """Rollout success by the optimal path's move count (buckets of 5 moves), one column per metrics file that has
    the `by_length` figures."""
    entries = [e for e in weights_metrics(folder) if e["vinadv"].get("by_length")]
    if not entries:
        return "(no metrics file has figures by path length yet)"
    buckets: dict[tuple[int, int], dict[str, dict]] = {}
    for entry in entries:
        for bucket in entry["vinadv"]["by_length"]:
            buckets.setdefault(tuple(bucket["moves"]), {})[entry["planner"]] = bucket
    head = "| optimal moves | " + " | ".join(f"`{e['planner']}`: success (starts)" for e in entries) + " |"
    rows = [head, "|---|" + "---|" * len(entries)]
    for (low, high), by_planner in sorted(buckets.items()):
        cells = []
        for entry in entries:
            bucket = by_planner.get(entry["planner"])
            cells.append(f"{percent(bucket['success_rate'])} ({bucket['rollouts']:,})" if bucket else "")
        rows.append(f"| {low}-{high} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def on_page_markdown(markdown: str, **kwargs) -> str:
    """MkDocs event: put the tables in place of their markers."""
    for marker, build in (
        (WEIGHTS_TABLE, weights_table),
        (WEIGHTS_COMMANDS, weights_commands),
        (BY_LENGTH, by_length_table),
    ):
        if marker in markdown:
            markdown = markdown.replace(marker, build())
    return markdown
