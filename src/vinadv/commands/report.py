"""`vinadv evaluate` (the evaluation stage on a stored run: classifier comparison, planner quality, processing
time; stored) and `vinadv report` (the HTML report, read from the store)."""

from __future__ import annotations

import argparse

from vinadv.commands import add_db_argument, db_file, option_values
from vinadv.commands.classify import add_setting_argument
from vinadv.commands.output import add_output_options, emit, shows_progress
from vinadv.errors import InputError
from vinadv.outfile import check_output_folder

CLASSIFIER_NAMES = ("svm", "cnn", "mlp", "hausdorff", "frechet", "dtw", "hybrid", "rule")


def register(subparsers) -> None:
    ev = subparsers.add_parser(
        "evaluate",
        help="evaluate a stored run (classifier comparison, planner quality, processing time) and store the "
        "results (for `vinadv report`)",
        description="The paper's classifier comparison on the FP/DP pairs of a stored run (truth: the exact rule "
        "labeller): 7:3 stratified split; each classifier trained on the balanced training set (flipped/rotated "
        "copies of the minority class) and on the imbalanced one, tested on the real mix; accuracy against "
        "training set size; ROC and PR curves. Results go to the database's `evaluations` table. Then the "
        "quality of the run's planner, measured on the run's own maps, and the processing time of the paper's "
        "100 pairs (table 7), stored with "
        "the run.",
    )
    add_db_argument(ev)
    ev.add_argument("--run", help="run id, or run name (its latest run); default: the latest run")
    ev.add_argument(
        "--classifiers",
        default=",".join(CLASSIFIER_NAMES),
        help=f"comma-separated, from {','.join(CLASSIFIER_NAMES)} (default: all)",
    )
    add_setting_argument(ev)
    ev.add_argument(
        "--sizes",
        default=None,
        help="training set fractions for fig. 8, comma-separated in (0, 1] (default 0.1,0.2,0.4,0.6,0.8,1)",
    )
    ev.add_argument("--seed", type=int, default=0, help="seed of the split, augmentation and training (default 0)")
    ev.add_argument(
        "--quality-maps",
        type=int,
        default=None,
        metavar="N",
        help="measure the run's planner on the first N distinct maps of its stored pairs (default 1000)",
    )
    add_output_options(ev, json="the stored rows' figures", quiet=True)
    ev.set_defaults(func=cmd_evaluate)

    rep = subparsers.add_parser(
        "report",
        help="write the HTML evaluation report of a stored run (every table and figure of the paper)",
        description="Write DIR/index.html (self-contained, relative links), PNG and SVG figures and CSV tables: "
        "example pairs (figs. 1, 2, 5), the four categories (fig. 3), the category distribution (table 4, per run "
        "with --runs), the stored classifier comparison (tables 5, 6, figs. 8, 9), processing time for 100 pairs "
        "(table 7), the planner's quality on the run's maps (both as `vinadv evaluate` stored them) and the run's "
        "configuration; the paper's numbers beside ours when the run is in its setting (the VIN on 28x28 octile "
        "maps, one obstacle added).",
    )
    add_db_argument(rep)
    rep.add_argument(
        "--run", help="the main run to report, id or name (default: the first of --runs, else the latest run)"
    )
    rep.add_argument(
        "--runs",
        help="comma-separated run ids or names to compare in table 4 and the classifier "
        "section (say, one per attack strategy); the first is the main run unless --run names one",
    )
    rep.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    add_output_options(rep, json="what was written and measured", quiet=True)
    rep.set_defaults(func=cmd_report)


def _run_refs(text: str | None) -> list[str] | None:
    """--runs: comma-separated run ids or names (resolved by `Store.resolve_run`)."""
    if text is None:
        return None
    refs = [s.strip() for s in text.split(",") if s.strip()]
    if not refs:
        raise InputError("--runs: no run given (comma-separated run ids or names like 1,2,3)")
    return refs


def cmd_evaluate(args: argparse.Namespace) -> int:
    from vinadv.evaluation.job import EvaluateConfig, run  # scikit-learn behind it: for this command only

    given = {} if args.quality_maps is None else {"quality_maps": args.quality_maps}  # else the config's default
    config = EvaluateConfig(**option_values(args, "db", "run", "classifiers", "setting", "sizes", "seed"), **given)
    result = run(config, progress=shows_progress(args))
    rows, quality, timing = result.rows, result.planner_quality, result.timing

    def text() -> None:
        print(f"run {result.run_id}: {len(rows)} evaluations stored (setting {args.setting}, seed {args.seed})")
        print(
            f"{'classifier':<10} {'training':<10} {'pairs':>6} {'accuracy':>8} {'FP F1':>6} {'AUC':>6} "
            f"{'AP':>6} {'train s':>8} {'s/100':>8}"
        )
        for r in rows:
            if r["train_fraction"] < 1.0:
                continue
            m = r["metrics"]
            print(
                f"{r['classifier']:<10} {r['training']:<10} {r['train_size']:>6} {_f(m.get('accuracy'))} "
                f"{_f(m['per_class']['FP']['f1'], 6)} {_f(m.get('roc_auc'), 6)} {_f(m.get('average_precision'), 6)} "
                f"{_f(m.get('training_s'), 8, 2)} {_f(m.get('prediction_s_per_100'), 8, 4)}"
            )
        print(f"planner quality: {quality['source']}")
        print(
            f"processing time of {timing['pairs']} pairs: rule {timing['rule_s']:.4f} s, "
            f"read from the database {timing['read_s']:.4f} s"
        )
        print(f"write the report: vinadv report --db {result.url} --run {result.run_id} --out DIR")

    return emit(args, result.to_dict(), text)


def _f(value, width: int = 8, digits: int = 3) -> str:
    return f"{'n/a':>{width}}" if value is None else f"{value:>{width}.{digits}f}"


def cmd_report(args: argparse.Namespace) -> int:
    from vinadv.report import build_report

    check_output_folder(args.out, inputs={"--db": db_file(args.db)})  # before the work: not the database, writable
    result = build_report(args.db, args.out, run_id=args.run, runs=_run_refs(args.runs))

    def text() -> None:
        timing = result.timing
        print(f"report of run {result.run_id}: {result.index} ({len(set(result.files))} files)")
        hybrid = timing["hybrid_svm_s"]
        measured = (
            f"{timing['pairs']} stored pairs: rule {timing['rule_s']:.4f} s"
            if timing["pairs"] is not None
            else "processing times not evaluated"
        )
        print(
            measured
            + "".join(f", hybrid+SVM ({setting}, from the evaluation) {s:.4f} s" for setting, s in hybrid.items())
            + (" (paper 0.22 s; manual ~300 s)" if result.not_papers is None else "")
            + (f"; read from the database {timing['read_s']:.4f} s" if timing["pairs"] is not None else "")
            + ("" if result.evaluated else "; no classifier evaluation stored (see `vinadv evaluate`)")
        )

    return emit(args, result.to_dict(), text, json_default=str)
