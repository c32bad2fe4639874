"""Gather: every number, table and figure of the report as plain data, one function per section.

Each `gather_*` function takes the report's `Context` (an open `Store`, the output folder, the main run and the
runs to compare) and returns its section's dataclass; it reads the database only through `Store` methods and
computes through `vinadv.report.evaluate` and `vinadv.report.figures` (which write the PNG/SVG files into the
output folder). No section reads another's result, so they can be gathered in any order. Numbers stay numbers
(formatting is the templates' job); `Table`s are what the CSV files hold.
"""

from __future__ import annotations

import json
import os
import platform
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vinadv.report import paper
from vinadv.report.evaluate import TIMING_REPEATS, batch_of, median_seconds
from vinadv.vocabulary import STRENGTH_ORDER

ALL_LABELS = STRENGTH_ORDER
#: the four valid categories, in the paper's fig. 3 and table 4 order
CATEGORY_ORDER = STRENGTH_ORDER[:-1]
#: the label source of the exact rule labeller; any other source is a trained classifier
RULE_SOURCE = "rule"


@dataclass(frozen=True)
class Figure:
    """A figure written as PNG and SVG: file names (relative to the report folder), caption, alt text."""

    files: tuple[str, ...]
    caption: str
    alt: str
    width: int | None = None

    @property
    def png(self) -> str:
        return next(n for n in self.files if n.endswith(".png"))

    @property
    def svg(self) -> str | None:
        return next((n for n in self.files if n.endswith(".svg")), None)


@dataclass(frozen=True)
class Table:
    """A CSV file of the report: its name, header and rows of raw values (None: empty cell)."""

    name: str
    header: tuple[str, ...]
    rows: list[list]

    @property
    def records(self) -> list[dict]:
        """The rows as {column: value} dicts."""
        return [dict(zip(self.header, row)) for row in self.rows]


@dataclass
class Context:
    """What every section reads: `store` (open), `out` (the report folder), `run_id` (the main run), `compare`
    (the runs of table 4 and of the classifier section, main run first), `runs` ({id: `Store.list_runs` row})."""

    store: object
    out: Path
    run_id: int
    compare: list[int]
    runs: dict[int, dict]

    def prefix(self, run_id: int) -> str:
        """File-name prefix of a run's own tables and figures: none for the main run, `runK_` for the others."""
        return "" if run_id == self.run_id else f"run{run_id}_"


# ------------------------------------------------------------------------------------------------------ run

@dataclass
class RunData:
    rows: list[tuple[str, object]]
    config: list[tuple[str, object]]
    timings: list[tuple[str, object]]
    table: Table


def gather_run(ctx: Context) -> RunData:
    info = ctx.store.run_info(ctx.run_id)
    sources = ctx.store.label_sources(ctx.run_id)
    rows = [
        ("run id", info["id"]), ("name", info.get("name")), ("created (UTC)", info["created"]),
        ("status", info["status"]), ("attack strategy", info.get("attack")),
        ("labelled by", info.get("classifier") or ", ".join(sources)), ("label sources", ", ".join(sources)),
        ("seed", info.get("seed")), ("stored pairs", int(ctx.runs[ctx.run_id]["n_pairs"])),
        ("planner weights (SHA-256)", info.get("weights_checksum")), ("vinadv version", info["version"]),
    ]
    config = [(k, json.dumps(v) if isinstance(v, (dict, list)) else v)
              for k, v in sorted((info.get("config") or {}).items())]
    timings = list((info.get("timings") or {}).items())
    table = Table("run_config.csv", ("key", "value"),
                  [[k, v] for k, v in rows] + [[f"config.{k}", v] for k, v in config]
                  + [[f"timings.{k}", v] for k, v in timings])
    return RunData(rows=rows, config=config, timings=timings, table=table)


# ------------------------------------------------------------------------------------------------------ VIN

@dataclass
class VinData:
    source: str
    metrics: dict
    terminations: dict[str, int]
    reached: int
    total: int
    table: Table


def gather_vin(ctx: Context) -> VinData:
    from vinadv.report.evaluate import vin_quality

    info = ctx.store.run_info(ctx.run_id)
    config = info.get("config") or {}
    size = int(config.get("size") or _first_pairs(ctx, ctx.run_id, 1).size)
    metrics, source = vin_quality(config, info.get("weights_checksum"), size)
    terms = ctx.store.termination_counts(ctx.run_id, "o")
    total, reached = sum(terms.values()), terms.get("goal", 0)
    keys = ("success_rate", "optimal_rate", "optimal_rate_of_reached", "action_accuracy", "mean_extra_cost",
            "maps", "starts_per_map")
    table = Table("vin_quality.csv", ("figure", "value"),
                  [[k, metrics.get(k)] for k in keys]
                  + [["run_original_paths", total], ["run_original_paths_reaching_goal", reached]]
                  + [[f"run_original_paths_ended_by_{k}", v] for k, v in terms.items()])
    return VinData(source=source, metrics=metrics, terminations=terms, reached=reached, total=total, table=table)


def _first_pairs(ctx: Context, run_id: int, k: int):
    index, _ = ctx.store.pair_labels(run_id)
    return ctx.store.read_pairs(run_id, pair_indices=index[:k])


# ------------------------------------------------------------------------------------------------- examples

@dataclass(frozen=True)
class ExamplePair:
    """One pair shown in a figure: its label and the rule's distances (`dh`, `dv`, threshold `t`); `deciding`:
    which distance makes an FP pair a fork (`dh`, `dv` or `dh and dv`), None for the other labels."""

    pair_index: int
    label: str
    dh: int
    dv: int
    t: int

    @property
    def deciding(self) -> str | None:
        if self.label != "FP":
            return None
        over = [name for name, d in (("dh", self.dh), ("dv", self.dv)) if d > self.t]
        return " and ".join(over) or None


@dataclass
class ExamplesData:
    fig1: Figure
    fig2: Figure
    fig5: Figure
    pairs: list[ExamplePair]
    t: int


@dataclass
class CategoriesData:
    figure: Figure
    pairs: list[ExamplePair]
    missing: list[str]


def _examples(ctx: Context):
    """Up to two stored pairs per category of the main run (the first by pair index), read with their rule
    distances: `(records, chosen {label: pair indices}, ExamplePairs in records order)`."""
    from vinadv.classify import label_batch

    chosen = {label: np.array([r["pair_index"] for r in ctx.store.page_pairs(ctx.run_id, label=label, limit=2)],
                              dtype=np.int64) for label in CATEGORY_ORDER}
    indices = np.concatenate([chosen[label] for label in CATEGORY_ORDER])
    if len(indices) == 0:  # only invalid pairs
        indices = np.array([r["pair_index"] for r in ctx.store.page_pairs(ctx.run_id, label="invalid", limit=4)],
                           dtype=np.int64)
    records = ctx.store.read_pairs(ctx.run_id, pair_indices=indices)
    rule = label_batch(batch_of(records))  # the exact distances, whatever labelled the run
    pairs = [ExamplePair(pair_index=int(p), label=str(lab), dh=int(dh), dv=int(dv), t=int(rule.t))
             for p, lab, dh, dv in zip(records.pair_index, records.label, rule.dh, rule.dv)]
    return records, chosen, pairs


def gather_examples(ctx: Context) -> ExamplesData:
    from vinadv.report import figures

    records, chosen, pairs = _examples(ctx)
    position = {p.pair_index: i for i, p in enumerate(pairs)}
    # figs. 1 and 2: a successful attack when there is one (FP, then UrP), else any pair
    lead = next((int(chosen[lab][0]) for lab in ("FP", "UrP", "DP", "UcP") if len(chosen[lab])),
                pairs[0].pair_index)
    i = position[lead]
    fig1 = Figure(tuple(figures.map_pair(records, i, ctx.out / "fig1_map_pair", with_paths=False)),
                  "Fig. 1: a pair of maps, the normal map and the adversarial map (one added obstacle, orange).",
                  "original and adversarial map", 760)
    fig2 = Figure(tuple(figures.map_pair(records, i, ctx.out / "fig2_path_pair", with_paths=True,
                                         distances=pairs[i])),
                  "Fig. 2: the pair of paths the VIN plans on them (original red, adversarial blue dashed).",
                  "original and adversarial path", 760)
    fig5 = Figure(tuple(figures.example_pairs(records, ctx.out / "fig5_map_pairs", distances=pairs)),
                  f"Fig. 5: examples of map pairs ({len(pairs)}: up to two per category), original map and path "
                  "above, adversarial map with both paths below.", "example map pairs")
    return ExamplesData(fig1=fig1, fig2=fig2, fig5=fig5, pairs=pairs, t=pairs[0].t)


def gather_categories(ctx: Context) -> CategoriesData:
    from vinadv.report import figures

    records, chosen, pairs = _examples(ctx)
    position = {p.pair_index: i for i, p in enumerate(pairs)}
    shown = {label: position[int(chosen[label][0])] for label in CATEGORY_ORDER if len(chosen[label])}
    figure = Figure(tuple(figures.categories({label: (records, i) for label, i in shown.items()},
                                             ctx.out / "fig3_categories",
                                             distances={label: pairs[i] for label, i in shown.items()})),
                    "Fig. 3: the four categories. Rows: original map (red path), adversarial map (blue path), path "
                    "image (blue = adversarial path, red = original path drawn on top).", "the four categories", 900)
    return CategoriesData(figure=figure, pairs=[pairs[i] for i in shown.values()],
                          missing=[label for label in CATEGORY_ORDER if label not in shown])


# --------------------------------------------------------------------------------------------- distribution

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
    paper: dict[str, int]
    table: Table
    figure: Figure


def gather_distribution(ctx: Context) -> DistributionData:
    from vinadv.report import figures

    rows = []
    for rid in ctx.compare:
        info = ctx.runs[rid]
        sources = ctx.store.label_sources(rid)
        rows.append(RunCounts(run_id=rid, name=info.get("name"), attack=info.get("attack"),
                              labelled_by=", ".join(sources) or (info.get("classifier") or RULE_SOURCE),
                              by_model=any(s != RULE_SOURCE for s in sources),
                              counts={lab: int(ctx.store.label_counts(rid).get(lab, 0)) for lab in ALL_LABELS}))
    table = Table("table4_categories.csv",
                  ("run", "attack", "labelled_by", "pairs", *ALL_LABELS, "successful", "valid"),
                  [[r.run_id, r.attack, r.labelled_by, r.total, *[r.counts[lab] for lab in ALL_LABELS], r.success,
                    r.valid] for r in rows]
                  + [["paper", "", "Liu et al. rules", sum(paper.TABLE4.values()),
                      *[paper.TABLE4[lab] for lab in CATEGORY_ORDER], None,
                      paper.TABLE4["UrP"] + paper.TABLE4["FP"], sum(paper.TABLE4.values())]])
    bars = [(f"run {r.run_id} ({r.attack or '—'})" + (" †" if r.by_model else ""), r.counts) for r in rows]
    figure = Figure(tuple(figures.category_bars(bars, paper.TABLE4, ctx.out / "fig_table4_categories")),
                    "Table 4 as bars: share of each category (paper: no invalid category).",
                    "category distribution", 760)
    return DistributionData(runs=rows, paper=dict(paper.TABLE4), table=table, figure=figure)


# -------------------------------------------------------------------------------------------- classifiers

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

    @property
    def tables(self) -> list[Table]:
        return [t for t in (self.table5, self.table6, self.detail, self.fig8_table) if t is not None]


@dataclass
class ClassifiersData:
    evaluations: list[RunEvaluation]
    missing: list[tuple[int, str]]  # (run id, why no comparison is shown)
    url: str


def gather_classifiers(ctx: Context) -> ClassifiersData:
    evaluations, missing = [], []
    for rid in ctx.compare:
        rows = ctx.store.read_evaluations(rid)
        if rows:
            evaluations.append(_run_evaluation(ctx, rid, rows))
            continue
        counts = ctx.store.label_counts(rid)
        if counts.get("FP", 0) < 2 or counts.get("DP", 0) < 2:
            why = (f"run {rid} has {counts.get('FP', 0)} FP and {counts.get('DP', 0)} DP pairs; the comparison "
                   "needs at least 2 of each (a larger --n, or another attack strategy)")
        else:
            why = "no classifier evaluation is stored for this run"
        missing.append((rid, why))
    return ClassifiersData(evaluations=evaluations, missing=missing, url=ctx.store.url)


def _run_evaluation(ctx: Context, rid: int, stored: list[dict]) -> RunEvaluation:
    from vinadv.report import figures

    latest = {(r["classifier"], r["setting"], r["training"], r["train_fraction"]): r for r in stored}
    rows = sorted(latest.values(), key=lambda r: r["id"])
    prefix = ctx.prefix(rid)
    settings = [s for s in ("baseline", "tuned") if any(r["setting"] == s for r in rows)]
    results = []
    for setting in settings:
        full = {(r["classifier"], r["training"]): r for r in rows
                if r["setting"] == setting and r["train_fraction"] >= 1.0}
        curves: dict = {}
        for (kind, training), r in full.items():
            if kind not in ("hybrid", "rule") and r.get("curves"):
                curves.setdefault(training, {})[kind] = (r["curves"], r["metrics"].get("roc_auc"),
                                                         r["metrics"].get("average_precision"))
        fig9 = None
        if curves:
            fig9 = Figure(tuple(figures.roc_pr_curves(curves, ctx.out / f"{prefix}fig9_roc_pr_{setting}")),
                          f"Fig. 9 ({setting}): PR and ROC curves on the test split, imbalanced vs balanced training "
                          "(AP and AUC in the legends).", f"ROC and PR curves, {setting}")
        results.append(SettingResult(setting=setting, full=full, fig9=fig9))
    points: dict = {}
    for r in rows:
        if r["training"] == "balanced" and r["classifier"] not in ("hybrid", "rule"):
            points.setdefault((r["classifier"], r["setting"]), []).append(
                (r["train_fraction"], r["train_size"], r["metrics"].get("accuracy")))
    fig8 = None
    if points:
        fig8 = Figure(tuple(figures.accuracy_vs_size(points, ctx.out / f"{prefix}fig8_accuracy_vs_size")),
                      "Fig. 8: test accuracy against the size of the (balanced) training set; solid lines the "
                      "paper's baseline setting, dashed lines the tuned one.", "accuracy vs training set size", 680)
    classifiers = list(dict.fromkeys(r["classifier"] for r in rows))
    newest = rows[-1]["metrics"]
    return RunEvaluation(
        run_id=rid, main=rid == ctx.run_id,
        batches=sorted({(str(r["created"]), r["setting"], r["seed"]) for r in rows}),
        hidden=len(stored) - len(rows), threshold=newest.get("threshold"),
        train_counts=newest.get("train_counts") or {}, test_counts=newest.get("test_counts") or {},
        epochs={r["classifier"]: r["metrics"]["epochs"] for r in rows if r["metrics"].get("epochs") is not None},
        classifiers=classifiers, settings=results, fig8=fig8,
        **_classifier_tables(classifiers, results, rows, points, prefix))


def _classifier_tables(classifiers: list[str], settings: list[SettingResult], rows: list[dict], points: dict,
                       prefix: str) -> dict[str, Table | None]:
    table5, table6, detail = [], [], []
    for kind in classifiers:
        for s in settings:
            bal = s.full.get((kind, "balanced")) or s.full.get((kind, "none"))
            imb = s.full.get((kind, "imbalanced"))
            if bal is None:
                continue
            table5.append([kind, s.setting, bal["train_size"], bal["metrics"].get("training_s"),
                           paper.TRAINING_S.get(kind) if s.setting == "baseline" else None])
            table6.append([kind, s.setting, bal["metrics"].get("accuracy"),
                           imb["metrics"].get("accuracy") if imb else None, bal["metrics"]["per_class"]["FP"]["f1"],
                           paper.ACCURACY.get(kind) if s.setting == "baseline" else None])
    for r in rows:
        if r["train_fraction"] < 1.0:
            continue
        m = r["metrics"]
        pc, cm, five = m["per_class"], m["confusion_matrix"], m.get("five_way") or {}
        detail.append([r["classifier"], r["setting"], r["training"], r["train_size"], r["test_size"],
                       m.get("accuracy"), pc["DP"]["precision"], pc["DP"]["recall"], pc["DP"]["f1"],
                       pc["FP"]["precision"], pc["FP"]["recall"], pc["FP"]["f1"], m.get("roc_auc"),
                       m.get("average_precision"), cm[0][0], cm[0][1], cm[1][0], cm[1][1], m.get("training_s"),
                       m.get("prediction_s_per_100"), five.get("accuracy"), five.get("n"), m.get("epochs")])
    return {
        "table5": Table(f"{prefix}table5_training_time.csv",
                        ("classifier", "setting", "train_size", "training_s", "paper_s"), table5),
        "table6": Table(f"{prefix}table6_accuracy.csv",
                        ("classifier", "setting", "accuracy_balanced", "accuracy_imbalanced", "fp_f1_balanced",
                         "paper_accuracy"), table6),
        "detail": Table(f"{prefix}classifier_metrics.csv", (
            "classifier", "setting", "training", "train_size", "test_size", "accuracy", "dp_precision", "dp_recall",
            "dp_f1", "fp_precision", "fp_recall", "fp_f1", "roc_auc", "average_precision", "cm_dp_dp", "cm_dp_fp",
            "cm_fp_dp", "cm_fp_fp", "training_s", "prediction_s_per_100", "five_way_accuracy", "five_way_n",
            "epochs"), detail),
        "fig8_table": Table(f"{prefix}fig8_accuracy_vs_size.csv",
                            ("classifier", "setting", "fraction", "train_size", "accuracy"),
                            [[kind, setting, f, n, a] for (kind, setting), v in sorted(points.items())
                             for f, n, a in sorted(v)]) if points else None,
    }


# ------------------------------------------------------------------------------------------------ timing

@dataclass
class TimingData:
    run_id: int
    pairs: int
    counts: dict[str, int]
    read_s: float
    rule_s: float
    hybrid: list[tuple[str, int, float]]  # (setting, pairs, seconds) measured by the stored evaluation
    machine: str
    repeats: int
    table: Table

    @property
    def scale(self) -> float:
        """Factor from `pairs` to 100 pairs."""
        return 100.0 / max(self.pairs, 1)


def timing_pairs(index: np.ndarray, labels: np.ndarray, seed: int = 0) -> np.ndarray:
    """The paper's 100-pair mix of a run, from all its stored pairs (`index`, `labels`): up to 40 FP/DP pairs and
    60 UrP/UcP pairs (the rest from the other group when one is short), sorted pair indices."""
    from vinadv.report.evaluate import paper_mix

    chosen = paper_mix(labels, np.flatnonzero(np.isin(labels, ("FP", "DP"))), seed)
    return np.sort(index[chosen]) if len(chosen) else index[:100]


def gather_timing(ctx: Context) -> TimingData:
    from vinadv.classify import label_batch

    mix = timing_pairs(*ctx.store.pair_labels(ctx.run_id))
    read_s = median_seconds(lambda: ctx.store.read_pairs(ctx.run_id, pair_indices=mix), 3)
    records = ctx.store.read_pairs(ctx.run_id, pair_indices=mix)
    batch = batch_of(records)
    rule_s = median_seconds(lambda: label_batch(batch))
    counts = {lab: int(np.sum(records.label == lab)) for lab in ALL_LABELS}
    latest = {r["setting"]: r for r in ctx.store.read_evaluations(ctx.run_id)
              if r["classifier"] == "hybrid" and r["training"] == "balanced" and r["train_fraction"] >= 1.0
              and (r["metrics"].get("five_way") or {}).get("paper_mix_pairs")}
    hybrid = [(setting, int(r["metrics"]["five_way"]["paper_mix_pairs"]),
               float(r["metrics"]["five_way"]["paper_mix_s"]))
              for setting, r in sorted(latest.items())]
    n = len(records)
    scale = 100.0 / max(n, 1)
    table = Table("table7_processing_time.csv", ("method", "pairs", "seconds_measured", "seconds_per_100",
                                                 "paper_seconds"),
                  [*[[f"hybrid_svm_{setting}", k, s, s * 100.0 / max(k, 1),
                      paper.PROCESSING_S["training"] if setting == "baseline" else None] for setting, k, s in hybrid],
                   ["rule", n, rule_s, rule_s * scale, None],
                   ["database_read", n, read_s, read_s * scale, None],
                   ["manual", None, None, None, paper.PROCESSING_S["manual"]]])
    machine = f"{platform.machine()}, {os.cpu_count()} CPUs, Python {platform.python_version()}"
    return TimingData(run_id=ctx.run_id, pairs=n, counts=counts, read_s=read_s, rule_s=rule_s, hybrid=hybrid,
                      machine=machine, repeats=TIMING_REPEATS, table=table)


# ------------------------------------------------------------------------------------------------ report

@dataclass
class ReportData:
    """Every section's data, and the page's header facts."""

    run_id: int
    run_name: str | None
    compare: list[int]
    url: str
    version: str
    generated: str
    sections: dict[str, object] = field(default_factory=dict)

    def tables(self) -> list[Table]:
        found = []
        for data in self.sections.values():
            found += [v for v in vars(data).values() if isinstance(v, Table)]
            for ev in getattr(data, "evaluations", []):
                found += ev.tables
        return found

    def figures(self) -> list[Figure]:
        found = []
        for data in self.sections.values():
            found += [v for v in vars(data).values() if isinstance(v, Figure)]
            for ev in getattr(data, "evaluations", []):
                found += [f for f in (ev.fig8, *(s.fig9 for s in ev.settings)) if f is not None]
        return found

    def files(self) -> list[str]:
        return sorted({*(t.name for t in self.tables()), *(n for f in self.figures() for n in f.files)})


#: the page's sections in order: (id, heading, gather function)
SECTIONS = (
    ("run", "Run and configuration", gather_run),
    ("vin", "The VIN's quality", gather_vin),
    ("examples", "Example map pairs (figs. 1, 2, 5)", gather_examples),
    ("categories", "The four categories (fig. 3)", gather_categories),
    ("distribution", "Category distribution (table 4)", gather_distribution),
    ("classifiers", "Classifier comparison (tables 5, 6; figs. 8, 9)", gather_classifiers),
    ("timing", "Processing time for 100 pairs (table 7)", gather_timing),
)


def gather_report(ctx: Context, order: list[str] | None = None) -> ReportData:
    """Gather every section (in `order` of section ids, default the page's: any order gives the same data)."""
    from vinadv import __version__

    gatherers = {sid: fn for sid, _, fn in SECTIONS}
    info = ctx.runs[ctx.run_id]
    data = ReportData(run_id=ctx.run_id, run_name=info.get("name"), compare=list(ctx.compare), url=ctx.store.url,
                      version=__version__, generated=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()))
    for sid in order or list(gatherers):
        data.sections[sid] = gatherers[sid](ctx)
    data.sections = {sid: data.sections[sid] for sid in gatherers if sid in data.sections}
    return data
