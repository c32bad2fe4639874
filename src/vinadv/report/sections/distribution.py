"""Category distribution (table 4)."""

from __future__ import annotations

from dataclasses import dataclass

from vinadv.report import paper
from vinadv.report.data import ALL_LABELS, CATEGORY_ORDER, RULE_SOURCE, Context, Figure, Table
from vinadv.report.sections.run import run_edit


@dataclass(frozen=True)
class RunCounts:
    """Table 4's row of one run. `by_model`: a trained classifier (not the exact rule) labelled some pairs."""

    run_id: int
    name: str | None
    attack: str | None
    labelled_by: str
    by_model: bool
    counts: dict[str, int]

    @property
    def total(self) -> int:
        return sum(self.counts.values())

    @property
    def valid(self) -> int:
        return self.total - self.counts.get("invalid", 0)

    @property
    def success(self) -> int:
        return self.counts.get("UrP", 0) + self.counts.get("FP", 0)


@dataclass
class DistributionData:
    runs: list[RunCounts]
    paper: dict[str, int] | None  # None: the main run is not in the paper's setting
    table: Table
    figure: Figure

    def tables(self) -> list[Table]:
        return [self.table]

    def figures(self) -> list[Figure]:
        return [self.figure]


def gather(ctx: Context) -> DistributionData:
    from vinadv.report import figures  # noqa: PLC0415 (Matplotlib: drawn when gathered)

    rows = []
    for rid in ctx.compare:
        info = ctx.runs[rid]
        sources = ctx.store.label_sources(rid)
        rows.append(
            RunCounts(
                run_id=rid,
                name=info.get("name"),
                # a run that frees obstacles says so; one that adds them shows its strategy alone
                attack=info.get("attack")
                and info["attack"] + (" (remove)" if run_edit(info.get("config")) == "remove" else ""),
                labelled_by=", ".join(sources) or (info.get("classifier") or RULE_SOURCE),
                by_model=any(s != RULE_SOURCE for s in sources),
                counts={lab: int(ctx.store.label_counts(rid).get(lab, 0)) for lab in ALL_LABELS},
            )
        )
    theirs = paper.TABLE4 if ctx.not_papers() is None else None
    table = Table(
        "table4_categories.csv",
        ("run", "attack", "labelled_by", "pairs", *ALL_LABELS, "successful", "valid"),
        [
            [r.run_id, r.attack, r.labelled_by, r.total, *[r.counts[lab] for lab in ALL_LABELS], r.success, r.valid]
            for r in rows
        ]
        + [
            [
                "paper",
                "",
                "Liu et al. rules",
                sum(paper.TABLE4.values()),
                *[paper.TABLE4[lab] for lab in CATEGORY_ORDER],
                None,
                paper.TABLE4["UrP"] + paper.TABLE4["FP"],
                sum(paper.TABLE4.values()),
            ]
        ]
        * (theirs is not None),
    )
    bars = [(f"run {r.run_id} ({r.attack or '—'})" + (" †" if r.by_model else ""), r.counts) for r in rows]
    figure = Figure(
        tuple(figures.category_bars(bars, theirs, ctx.out / "fig_table4_categories")),
        "Table 4 as bars: share of each category" + (" (paper: no invalid category)." if theirs else "."),
        "category distribution",
        760,
    )
    return DistributionData(runs=rows, paper=None if theirs is None else dict(theirs), table=table, figure=figure)
