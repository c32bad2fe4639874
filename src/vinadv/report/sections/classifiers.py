"""Classifier comparison (tables 5, 6; figs. 8, 9)."""

from __future__ import annotations

from dataclasses import dataclass

from vinadv.report import paper
from vinadv.report.data import Context, Figure, Table


@dataclass
class SettingResult:
    """One setting's (baseline or tuned) stored results of one run: `full` {(classifier, training): row} at the
    full training set, `fig9` the PR/ROC curves (None when no curve is stored)."""

    setting: str
    full: dict[tuple[str, str], dict]
    fig9: Figure | None


@dataclass
class RunEvaluation:
    """The stored comparison of one run (its newest row per classifier, setting, training and fraction)."""

    run_id: int
    main: bool
    batches: list[tuple[str, str, object]]  # (created, setting, seed) of each stored `vinadv evaluate`
    hidden: int
    threshold: int | None
    train_counts: dict
    test_counts: dict
    epochs: dict[str, int]  # {"cnn": 3, ...}: the networks' epochs, where stored
    classifiers: list[str]
    settings: list[SettingResult]
    fig8: Figure | None
    table5: Table
    table6: Table
    detail: Table
    fig8_table: Table | None
    #: the paper's numbers shown beside this run's: it is in the paper's setting (`Context.not_papers`)
    papers: bool = True

    def tables(self) -> list[Table]:
        return [t for t in (self.table5, self.table6, self.detail, self.fig8_table) if t is not None]

    def figures(self) -> list[Figure]:
        return [f for f in (self.fig8, *(s.fig9 for s in self.settings)) if f is not None]


@dataclass
class ClassifiersData:
    evaluations: list[RunEvaluation]
    missing: list[tuple[int, str]]  # (run id, why no comparison is shown)
    url: str

    def tables(self) -> list[Table]:
        return [t for ev in self.evaluations for t in ev.tables()]

    def figures(self) -> list[Figure]:
        return [f for ev in self.evaluations for f in ev.figures()]


def gather(ctx: Context) -> ClassifiersData:
    evaluations, missing = [], []
    for rid in ctx.compare:
        rows = ctx.store.read_evaluations(rid)
        if rows:
            evaluations.append(_run_evaluation(ctx, rid, rows))
            continue
        counts = ctx.store.label_counts(rid)
        if counts.get("FP", 0) < 2 or counts.get("DP", 0) < 2:
            why = (
                f"run {rid} has {counts.get('FP', 0)} FP and {counts.get('DP', 0)} DP pairs; the comparison "
                "needs at least 2 of each (a larger --n, or another attack strategy)"
            )
        else:
            why = "no classifier evaluation is stored for this run"
        missing.append((rid, why))
    return ClassifiersData(evaluations=evaluations, missing=missing, url=ctx.store.url)


def _run_evaluation(ctx: Context, rid: int, stored: list[dict]) -> RunEvaluation:
    from vinadv.report import figures  # noqa: PLC0415 (Matplotlib: drawn when gathered)

    latest = {(r["classifier"], r["setting"], r["training"], r["train_fraction"]): r for r in stored}
    rows = sorted(latest.values(), key=lambda r: r["id"])
    prefix = ctx.prefix(rid)
    settings = [s for s in ("baseline", "tuned") if any(r["setting"] == s for r in rows)]
    results = []
    for setting in settings:
        full = {
            (r["classifier"], r["training"]): r for r in rows if r["setting"] == setting and r["train_fraction"] >= 1.0
        }
        curves: dict = {}
        for (kind, training), r in full.items():
            if kind not in ("hybrid", "rule") and r.get("curves"):
                curves.setdefault(training, {})[kind] = (
                    r["curves"],
                    r["metrics"].get("roc_auc"),
                    r["metrics"].get("average_precision"),
                )
        fig9 = None
        if curves:
            fig9 = Figure(
                tuple(figures.roc_pr_curves(curves, ctx.out / f"{prefix}fig9_roc_pr_{setting}")),
                f"Fig. 9 ({setting}): PR and ROC curves on the test split, imbalanced vs balanced training "
                "(AP and AUC in the legends).",
                f"ROC and PR curves, {setting}",
            )
        results.append(SettingResult(setting=setting, full=full, fig9=fig9))
    points: dict = {}
    for r in rows:
        if r["training"] == "balanced" and r["classifier"] not in ("hybrid", "rule"):
            points.setdefault((r["classifier"], r["setting"]), []).append(
                (r["train_fraction"], r["train_size"], r["metrics"].get("accuracy"))
            )
    fig8 = None
    if points:
        fig8 = Figure(
            tuple(figures.accuracy_vs_size(points, ctx.out / f"{prefix}fig8_accuracy_vs_size")),
            "Fig. 8: test accuracy against the size of the (balanced) training set; solid lines the "
            "paper's baseline setting, dashed lines the tuned one.",
            "accuracy vs training set size",
            680,
        )
    classifiers = list(dict.fromkeys(r["classifier"] for r in rows))
    newest = rows[-1]["metrics"]
    papers = ctx.not_papers(rid) is None
    return RunEvaluation(
        run_id=rid,
        main=rid == ctx.run_id,
        batches=sorted({(str(r["created"]), r["setting"], r["seed"]) for r in rows}),
        hidden=len(stored) - len(rows),
        threshold=newest.get("threshold"),
        train_counts=newest.get("train_counts") or {},
        test_counts=newest.get("test_counts") or {},
        epochs={r["classifier"]: r["metrics"]["epochs"] for r in rows if r["metrics"].get("epochs") is not None},
        classifiers=classifiers,
        settings=results,
        fig8=fig8,
        papers=papers,
        **_classifier_tables(classifiers, results, rows, points, prefix, papers),
    )


def _classifier_tables(
    classifiers: list[str], settings: list[SettingResult], rows: list[dict], points: dict, prefix: str, papers: bool
) -> dict[str, Table | None]:
    """Tables 5 and 6, the detail and fig. 8's points; tables 5 and 6 with the paper's column only with `papers`."""
    table5, table6, detail = [], [], []
    for kind in classifiers:
        for s in settings:
            bal = s.full.get((kind, "balanced")) or s.full.get((kind, "none"))
            imb = s.full.get((kind, "imbalanced"))
            if bal is None:
                continue
            table5.append(
                [
                    kind,
                    s.setting,
                    bal["train_size"],
                    bal["metrics"].get("training_s"),
                    *([paper.TRAINING_S.get(kind) if s.setting == "baseline" else None] if papers else []),
                ]
            )
            table6.append(
                [
                    kind,
                    s.setting,
                    bal["metrics"].get("accuracy"),
                    imb["metrics"].get("accuracy") if imb else None,
                    bal["metrics"]["per_class"]["FP"]["f1"],
                    *([paper.ACCURACY.get(kind) if s.setting == "baseline" else None] if papers else []),
                ]
            )
    for r in rows:
        if r["train_fraction"] < 1.0:
            continue
        m = r["metrics"]
        pc, cm, five = m["per_class"], m["confusion_matrix"], m.get("five_way") or {}
        detail.append(
            [
                r["classifier"],
                r["setting"],
                r["training"],
                r["train_size"],
                r["test_size"],
                m.get("accuracy"),
                pc["DP"]["precision"],
                pc["DP"]["recall"],
                pc["DP"]["f1"],
                pc["FP"]["precision"],
                pc["FP"]["recall"],
                pc["FP"]["f1"],
                m.get("roc_auc"),
                m.get("average_precision"),
                cm[0][0],
                cm[0][1],
                cm[1][0],
                cm[1][1],
                m.get("training_s"),
                m.get("prediction_s_per_100"),
                five.get("accuracy"),
                five.get("n"),
                m.get("epochs"),
            ]
        )
    return {
        "table5": Table(
            f"{prefix}table5_training_time.csv",
            ("classifier", "setting", "train_size", "training_s", *(("paper_s",) if papers else ())),
            table5,
        ),
        "table6": Table(
            f"{prefix}table6_accuracy.csv",
            (
                "classifier",
                "setting",
                "accuracy_balanced",
                "accuracy_imbalanced",
                "fp_f1_balanced",
                *(("paper_accuracy",) if papers else ()),
            ),
            table6,
        ),
        "detail": Table(
            f"{prefix}classifier_metrics.csv",
            (
                "classifier",
                "setting",
                "training",
                "train_size",
                "test_size",
                "accuracy",
                "dp_precision",
                "dp_recall",
                "dp_f1",
                "fp_precision",
                "fp_recall",
                "fp_f1",
                "roc_auc",
                "average_precision",
                "cm_dp_dp",
                "cm_dp_fp",
                "cm_fp_dp",
                "cm_fp_fp",
                "training_s",
                "prediction_s_per_100",
                "five_way_accuracy",
                "five_way_n",
                "epochs",
            ),
            detail,
        ),
        "fig8_table": Table(
            f"{prefix}fig8_accuracy_vs_size.csv",
            ("classifier", "setting", "fraction", "train_size", "accuracy"),
            [[kind, setting, f, n, a] for (kind, setting), v in sorted(points.items()) for f, n, a in sorted(v)],
        )
        if points
        else None,
    }
