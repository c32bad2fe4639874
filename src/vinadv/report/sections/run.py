"""The run and its configuration, as stored."""

from __future__ import annotations

import json
from dataclasses import dataclass

from vinadv.grid.moves import DEFAULT_MOVES
from vinadv.report.data import Context, Figure, Table


@dataclass
class RunData:
    rows: list[tuple[str, object]]
    config: list[tuple[str, object]]
    timings: list[tuple[str, object]]
    table: Table

    def tables(self) -> list[Table]:
        return [self.table]

    def figures(self) -> list[Figure]:
        return []


def gather(ctx: Context) -> RunData:
    info = ctx.store.run_info(ctx.run_id)
    sources = ctx.store.label_sources(ctx.run_id)
    rows = [
        ("run id", info["id"]),
        ("name", info.get("name")),
        ("created (UTC)", info["created"]),
        ("status", info["status"]),
        ("attack strategy", info.get("attack")),
        ("labelled by", info.get("classifier") or ", ".join(sources)),
        ("label sources", ", ".join(sources)),
        ("seed", info.get("seed")),
        ("stored pairs", int(ctx.runs[ctx.run_id]["n_pairs"])),
        ("planner", (info.get("config") or {}).get("planner") or "vin"),
        ("attacks found on planner (transfer)", ((info.get("config") or {}).get("attack_planner") or {}).get("name")),
        ("planner weights (SHA-256)", info.get("weights_checksum")),
        ("vinadv version", info["version"]),
    ]
    if info["moves"] != DEFAULT_MOVES:  # an octile run's table is what it was before movement models
        rows.insert(rows.index(("seed", info.get("seed"))), ("movement model", info["moves"]))
    config = [
        (k, json.dumps(v) if isinstance(v, (dict, list)) else v) for k, v in sorted((info.get("config") or {}).items())
    ]
    timings = list((info.get("timings") or {}).items())
    table = Table(
        "run_config.csv",
        ("key", "value"),
        [[k, v] for k, v in rows] + [[f"config.{k}", v] for k, v in config] + [[f"timings.{k}", v] for k, v in timings],
    )
    return RunData(rows=rows, config=config, timings=timings, table=table)
