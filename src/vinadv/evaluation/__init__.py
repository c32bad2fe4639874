"""The evaluation stage: measuring planners and classifiers, and what the report shows beyond the stored pairs,
computed and stored (`vinadv evaluate`).

Planners:
- `planner_metrics`: a policy planner's rollout metrics (success, optimal, action accuracy, by path length);
- `search_metrics`: Opt / Exp / Hmean, the Neural A* authors' metrics, for any planner;
- `protocols`: other code's evaluation protocols (GPPN's %Opt / %Suc, the kentsommer port's), run on vinadv's planners;
- `length_curve`: success by optimal path length, with Wilson intervals, and its figure.

A run's report:
- `classifiers`: the paper's classifier comparison on a run's FP/DP pairs (section 5.2: tables 5, 6, figs. 8, 9),
  rows of the `evaluations` table.
- `planner_quality`: the quality of the planner the run used, measured on the run's own maps (the first distinct
  original maps of its stored pairs) as the planner's capabilities allow, a measurement of the run.
- `timing`: table 7's processing time of the rule labeller and the database read, a measurement of the run.
- `job`: `vinadv evaluate` as a job (`EvaluateConfig`, `run(config, executor)`, `EvaluateResult`): the three above
  on a stored run, stored.

The report (`vinadv.report`) only reads what this stage stored; `evaluate_for_report` is the stage as
`vinadv run --report` (and so `make demo`) runs it before writing the report. The package's names are imported at
their first use (PEP 562), so that the planner metrics load without the classifiers' libraries.
"""

from __future__ import annotations

from vinadv import lazy_names

#: the package's names imported at first use, by the module that defines them
_MODULES = {
    "classifiers": ("CLASSIFIERS", "compare_for_report", "evaluate_run"),
    "planner_quality": ("evaluate_planner_quality",),
    "timing": ("evaluate_timing",),
    "job": ("EvaluateConfig", "EvaluateResult"),
}
_lazy, __getattr__, __dir__ = lazy_names(__name__, _MODULES)
__all__ = sorted([*_lazy, "evaluate_for_report"])


def evaluate_for_report(store, run_id: int, *, compare: bool = True, progress: bool = False) -> str | None:
    """Evaluate the stored run `run_id` for its report and store the results: the quick classifier comparison
    (`compare_for_report`: both settings, the quick profile) unless `compare` is False or the run has one stored,
    then the planner's quality and the processing time. Return why no comparison was run: `"skipped"` (not
    `compare`), the reason the run cannot be compared, or None (run now, or one stored already)."""
    from vinadv.evaluation.classifiers import compare_for_report  # noqa: PLC0415 (the package imports its modules at first use)
    from vinadv.evaluation.planner_quality import evaluate_planner_quality  # noqa: PLC0415 (the package imports its modules at first use)
    from vinadv.evaluation.timing import evaluate_timing  # noqa: PLC0415 (the package imports its modules at first use)

    reason = "skipped" if not compare else None
    if compare and not store.read_evaluations(run_id):
        _, reason = compare_for_report(store, run_id, progress=progress)
    evaluate_planner_quality(store, run_id)
    evaluate_timing(store, run_id)
    return reason
