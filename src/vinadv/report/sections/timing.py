"""Processing time for 100 pairs (table 7): the rule labeller's and the database read's times as the evaluation
stage measured and stored them (`vinadv.evaluation.timing`), the hybrid classifier's from its stored evaluation."""

from __future__ import annotations

from dataclasses import dataclass

from vinadv.report import paper
from vinadv.report.data import Context, Figure, Table
from vinadv.vocabulary import TIMING


@dataclass
class TimingData:
    """`evaluated`: the evaluation stage stored the times (else `pairs`, `read_s`, `rule_s`, `machine` and `repeats`
    are None and `counts` empty); seconds are for all `pairs` of the paper's mix."""

    run_id: int
    url: str
    evaluated: bool
    pairs: int | None
    counts: dict[str, int]
    read_s: float | None
    rule_s: float | None
    hybrid: list[tuple[str, int, float]]  # (setting, pairs, seconds) measured by the stored evaluation
    machine: str | None
    repeats: int | None
    table: Table
    #: the paper's times shown beside ours: the main run is in the paper's setting (`Context.not_papers`)
    papers: bool = True

    def tables(self) -> list[Table]:
        return [self.table]

    def figures(self) -> list[Figure]:
        return []

    @property
    def scale(self) -> float:
        """Factor from `pairs` to 100 pairs."""
        return 100.0 / max(self.pairs or 0, 1)


def per_100(seconds: float | None, scale: float) -> float | None:
    return None if seconds is None else seconds * scale


def gather(ctx: Context) -> TimingData:
    stored = ctx.store.read_measurement(ctx.run_id, TIMING) or {}
    latest = {
        r["setting"]: r
        for r in ctx.store.read_evaluations(ctx.run_id)
        if r["classifier"] == "hybrid"
        and r["training"] == "balanced"
        and r["train_fraction"] >= 1.0
        and (r["metrics"].get("five_way") or {}).get("paper_mix_pairs")
    }
    hybrid = [
        (setting, int(r["metrics"]["five_way"]["paper_mix_pairs"]), float(r["metrics"]["five_way"]["paper_mix_s"]))
        for setting, r in sorted(latest.items())
    ]
    n, rule_s, read_s = stored.get("pairs"), stored.get("rule_s"), stored.get("read_s")
    scale = 100.0 / max(n or 0, 1)
    papers = ctx.not_papers() is None
    rows = [
        *[
            [f"hybrid_svm_{setting}", k, s, s * 100.0 / max(k, 1)]
            + [paper.PROCESSING_S["training"] if setting == "baseline" else None] * papers
            for setting, k, s in hybrid
        ],
        ["rule", n, rule_s, per_100(rule_s, scale)] + [None] * papers,
        ["database_read", n, read_s, per_100(read_s, scale)] + [None] * papers,
        *([["manual", None, None, None, paper.PROCESSING_S["manual"]]] if papers else []),
    ]
    header = ("method", "pairs", "seconds_measured", "seconds_per_100", *(("paper_seconds",) if papers else ()))
    table = Table("table7_processing_time.csv", header, rows)
    return TimingData(
        run_id=ctx.run_id,
        url=ctx.store.url,
        evaluated=bool(stored),
        pairs=n,
        counts=stored.get("counts") or {},
        read_s=read_s,
        rule_s=rule_s,
        hybrid=hybrid,
        machine=stored.get("machine"),
        repeats=stored.get("repeats"),
        table=table,
        papers=papers,
    )
