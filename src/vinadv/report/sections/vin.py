"""The planner's quality: as the evaluation stage stored it (`vinadv.evaluation.planner_quality`), beside how the
run's original paths ended."""

from __future__ import annotations

from dataclasses import dataclass

from vinadv.report.data import Context, Figure, Table
from vinadv.vocabulary import PLANNER_QUALITY

#: the stored quality figures, in the table's order
KEYS = (
    "success_rate",
    "optimal_rate",
    "optimal_rate_of_reached",
    "action_accuracy",
    "mean_extra_cost",
    "maps",
    "starts_per_map",
)


@dataclass
class VinData:
    """`evaluated`: the evaluation stage stored the planner's quality (else `source` is None and `metrics` empty);
    `source`: where the stored metrics come from, or why there are none."""

    run_id: int
    url: str
    evaluated: bool
    source: str | None
    metrics: dict
    terminations: dict[str, int]
    reached: int
    total: int
    table: Table

    def tables(self) -> list[Table]:
        return [self.table]

    def figures(self) -> list[Figure]:
        return []


def gather(ctx: Context) -> VinData:
    stored = ctx.store.read_measurement(ctx.run_id, PLANNER_QUALITY)
    metrics = (stored or {}).get("metrics") or {}
    terms = ctx.store.termination_counts(ctx.run_id, "o")
    total, reached = sum(terms.values()), terms.get("goal", 0)
    table = Table(
        "vin_quality.csv",
        ("figure", "value"),
        [[k, metrics.get(k)] for k in KEYS]
        + [["run_original_paths", total], ["run_original_paths_reaching_goal", reached]]
        + [[f"run_original_paths_ended_by_{k}", v] for k, v in terms.items()],
    )
    return VinData(
        run_id=ctx.run_id,
        url=ctx.store.url,
        evaluated=stored is not None,
        source=None if stored is None else stored["source"],
        metrics=metrics,
        terminations=terms,
        reached=reached,
        total=total,
        table=table,
    )
