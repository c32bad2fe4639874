"""The evaluation stage: what the report shows beyond the stored pairs, computed and stored (`vinadv evaluate`).

- `classifiers`: the paper's classifier comparison on a run's FP/DP pairs (section 5.2: tables 5, 6, figs. 8, 9),
  rows of the `evaluations` table.
- `planner_quality`: the quality of the planner the run used (a shipped metrics file, the weights' training record
  or a quick evaluation on fresh maps), a measurement of the run.
- `timing`: table 7's processing time of the rule labeller and the database read, a measurement of the run.

The report (`vinadv.report`) only reads what this stage stored; `evaluate_for_report` is the stage as
`vinadv run --report` (and so `make demo`) runs it before writing the report.
"""

from __future__ import annotations

from vinadv.evaluation.classifiers import CLASSIFIERS, compare_for_report, evaluate_run
from vinadv.evaluation.planner_quality import evaluate_planner_quality
from vinadv.evaluation.timing import evaluate_timing

__all__ = ["CLASSIFIERS", "evaluate_for_report", "evaluate_planner_quality", "evaluate_run", "evaluate_timing"]


def evaluate_for_report(store, run_id: int, *, compare: bool = True, progress: bool = False) -> str | None:
    """Evaluate the stored run `run_id` for its report and store the results: the quick classifier comparison
    (`compare_for_report`: both settings, the quick profile) unless `compare` is False or the run has one stored,
    then the planner's quality and the processing time. Return why no comparison was run: `"skipped"` (not
    `compare`), the reason the run cannot be compared, or None (run now, or stored before)."""
    reason = "skipped" if not compare else None
    if compare and not store.read_evaluations(run_id):
        _, reason = compare_for_report(store, run_id, progress=progress)
    evaluate_planner_quality(store, run_id)
    evaluate_timing(store, run_id)
    return reason
