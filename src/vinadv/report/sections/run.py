"""The run and its configuration, as stored."""

from __future__ import annotations

import json
from dataclasses import dataclass

from vinadv.grid.moves import DEFAULT_MOVES
from vinadv.records import run_config_kind
from vinadv.report.data import Context, Figure, Table
from vinadv.vocabulary import ADD


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


def run_edit(config: dict | None) -> str:
    """What a run's attack did to the maps, from its stored config (a `vinadv run` or `vinadv identify` config
    records its `edit`, `vinadv.records`): `remove` (obstacle cells freed) or `add`; `add` for a run without such a
    config."""
    return str(config["edit"]) if run_config_kind(config) is not None else ADD


def gather(ctx: Context) -> RunData:
    info = ctx.store.run_info(ctx.run_id)
    sources = ctx.store.label_sources(ctx.run_id)
    removal = [("edit", "remove (obstacle cells freed)")] if run_edit(info.get("config")) == "remove" else []
    rows = [
        ("run id", info["id"]),
        ("name", info.get("name")),
        ("created (UTC)", info["created"]),
        ("status", info["status"]),
        ("attack strategy", info.get("attack")),
        *removal,  # the edit row only for a run that frees obstacles
        ("labelled by", info.get("classifier") or ", ".join(sources)),
        ("label sources", ", ".join(sources)),
        ("seed", info.get("seed")),
        ("stored pairs", int(ctx.runs[ctx.run_id]["n_pairs"])),
        ("planner", (info.get("config") or {}).get("planner") or "vin"),
        ("attacks found on planner (transfer)", ((info.get("config") or {}).get("attack_planner") or {}).get("name")),
        ("planner weights (SHA-256)", info.get("weights_checksum")),
        ("vinadv version", info["version"]),
    ]
    if info["moves"] != DEFAULT_MOVES:  # the movement model row only for a run off octile maps
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
