"""`vinadv report`: the paper's evaluation of a stored run as one self-contained HTML page, figures and CSV tables.

`build_report(db, out_dir, run_id=None, runs=None)` gathers every section (`vinadv.report.sections`: the database
through `Store`, what the evaluation stage stored included) and renders it (`vinadv.report.render`: Jinja2
templates, one stylesheet, CSV files) into `out_dir`: `index.html` (relative links only, no script, no external
resource), PNG + SVG figures and CSV tables. The report computes no evaluation: `vinadv evaluate`
(`vinadv.evaluation`) does, and `vinadv run --report` runs it first. The paper's numbers are shown beside ours
wherever the paper has one, when the run is in the paper's setting (its VIN on 28x28 octile maps,
one obstacle added: `vinadv.report.paper.papers_setting`); for any other run the page says why they are left out.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from vinadv.errors import InputError
from vinadv.report.data import Context
from vinadv.report.render import render_report, render_robustness_page
from vinadv.report.sections import SECTIONS, gather_report
from vinadv.report.sections.robustness import robustness_section

__all__ = ["SECTIONS", "ReportResult", "build_report", "robustness_report", "write_report"]


@dataclass
class ReportResult:
    """What `build_report` wrote and measured."""

    index: Path
    run_id: int
    runs: list[int]
    files: list[str] = field(default_factory=list)
    timing: dict = field(default_factory=dict)
    planner: dict = field(default_factory=dict)
    evaluated: bool = False
    not_papers: str | None = None

    def to_dict(self) -> dict:
        return {
            "index": str(self.index),
            "run_id": self.run_id,
            "runs": self.runs,
            "files": self.files,
            "timing": self.timing,
            "planner": self.planner,
            "evaluated": self.evaluated,
            "not_papers": self.not_papers,
        }


def write_report(db: str | None, out_dir, run_id: int | str | None = None, runs: list[int | str] | None = None) -> Path:
    """Write the report to `out_dir` (see `build_report`); return the path of `index.html`."""
    return build_report(db, out_dir, run_id=run_id, runs=runs).index


def build_report(
    db: str | None, out_dir, run_id: int | str | None = None, runs: list[int | str] | None = None
) -> ReportResult:
    """Write the report of the main run to `out_dir` and return what was written and measured.

    Runs are ids or names (`Store.resolve_run`). The main run is `run_id`, else the first of `runs`, else the
    latest run. Table 4 and the classifier section
    show every run of `runs` (the main run first; default: just the main run), each with its stored evaluation.
    """
    from vinadv.store import Store  # noqa: PLC0415 (SQLAlchemy)

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"out_dir {out}: exists and is not a directory")
    with Store.open(db, readonly=True) as store:
        ctx = report_context(store, out, run_id, runs)
        out.mkdir(parents=True, exist_ok=True)
        data = gather_report(ctx)
    index = render_report(data, out)
    quality, timing = data.sections["planner"], data.sections["timing"]
    return ReportResult(
        index=index,
        run_id=ctx.run_id,
        runs=ctx.compare,
        files=[*data.files(), "style.css"],
        timing={
            "pairs": timing.pairs,
            "counts": timing.counts,
            "read_s": timing.read_s,
            "rule_s": timing.rule_s,
            "hybrid_svm_s": {setting: s for setting, _, s in timing.hybrid},
        },
        planner={
            "source": quality.source,
            "capabilities": quality.capabilities,
            **{k: quality.metrics.get(k) for k in ("success_rate", "optimal_rate")},
            **(
                {"action_accuracy": quality.metrics.get("action_accuracy")}
                if quality.capabilities.get("policy")
                else {}
            ),
            **({"search": quality.search} if quality.search is not None else {}),
            "run_original_reached": quality.reached / quality.total if quality.total else None,
        },
        evaluated=any(ev.main for ev in data.sections["classifiers"].evaluations),
        not_papers=data.not_papers,
    )


def report_context(store, out: Path, run_id: int | str | None, runs: list[int | str] | None) -> Context:
    """The `Context` of a report on the open `store` into `out` (see `build_report` for `run_id` and `runs`)."""
    listed = store.list_runs()
    if not listed:
        raise InputError(f"database {store.url}: no runs stored yet (run `vinadv run` first)")
    known = {int(r["id"]): r for r in listed}
    runs = None if runs is None else [store.resolve_run(r, "runs") for r in runs]
    run_id = None if run_id is None else store.resolve_run(run_id)
    main = int(run_id) if run_id is not None else int(runs[0]) if runs else max(known)
    compare = [main, *(int(r) for r in dict.fromkeys(runs or []) if int(r) != main)]
    if known[main]["n_pairs"] == 0:
        raise InputError(f"run {main} has no stored pairs")
    return Context(store=store, out=out, run_id=main, compare=compare, runs=known)


def robustness_report(out_dir, db: str | None = None, results: list[dict] | None = None) -> Path:
    """Write the robustness page (`vinadv robustness --report DIR`) to `out_dir`: every robustness benchmark stored in
    `db` (when given), then `results`, benchmarks not stored (rows as `Store.read_robustness` returns them, `id`
    None). Return the path of `index.html`."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"out_dir {out}: exists and is not a directory")
    rows, url = [], None
    if db is not None:
        from vinadv.store import Store  # noqa: PLC0415 (SQLAlchemy: only with a database)

        with Store.open(db, readonly=True) as store:
            rows, url = store.read_robustness(), store.url
    out.mkdir(parents=True, exist_ok=True)
    data = robustness_section([*rows, *(results or [])], out)
    return render_robustness_page(data, out, url)
