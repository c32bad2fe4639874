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
        ("run id", info["id"]),
        ("name", info.get("name")),
        ("created (UTC)", info["created"]),
        ("status", info["status"]),
        ("attack strategy", info.get("attack")),
        ("labelled by", info.get("classifier") or ", ".join(sources)),
        ("label sources", ", ".join(sources)),
        ("seed", info.get("seed")),
        ("stored pairs", int(ctx.runs[ctx.run_id]["n_pairs"])),
        ("planner", (info.get("config") or {}).get("planner") or "vin"),
        ("attacks found on planner (transfer)", ((info.get("config") or {}).get("attack_planner") or {}).get("name")),
        ("planner weights (SHA-256)", info.get("weights_checksum")),
        ("vinadv version", info["version"]),
    ]
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
    from vinadv.report.evaluate import planner_quality

    info = ctx.store.run_info(ctx.run_id)
    config = info.get("config") or {}
    size = int(config.get("size") or _first_pairs(ctx, ctx.run_id, 1).size)
    metrics, source = planner_quality(config, info.get("weights_checksum"), size)
    terms = ctx.store.termination_counts(ctx.run_id, "o")
    total, reached = sum(terms.values()), terms.get("goal", 0)
    keys = (
        "success_rate",
        "optimal_rate",
        "optimal_rate_of_reached",
        "action_accuracy",
        "mean_extra_cost",
        "maps",
        "starts_per_map",
    )
    table = Table(
        "vin_quality.csv",
        ("figure", "value"),
        [[k, metrics.get(k)] for k in keys]
        + [["run_original_paths", total], ["run_original_paths_reaching_goal", reached]]
        + [[f"run_original_paths_ended_by_{k}", v] for k, v in terms.items()],
    )
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

    chosen = {
        label: np.array(
            [r["pair_index"] for r in ctx.store.page_pairs(ctx.run_id, label=label, limit=2)], dtype=np.int64
        )
        for label in CATEGORY_ORDER
    }
    indices = np.concatenate([chosen[label] for label in CATEGORY_ORDER])
    if len(indices) == 0:  # only invalid pairs
        indices = np.array(
            [r["pair_index"] for r in ctx.store.page_pairs(ctx.run_id, label="invalid", limit=4)], dtype=np.int64
        )
    records = ctx.store.read_pairs(ctx.run_id, pair_indices=indices)
    rule = label_batch(batch_of(records))  # the exact distances, whatever labelled the run
    pairs = [
        ExamplePair(pair_index=int(p), label=str(lab), dh=int(dh), dv=int(dv), t=int(rule.t))
        for p, lab, dh, dv in zip(records.pair_index, records.label, rule.dh, rule.dv)
    ]
    return records, chosen, pairs


def gather_examples(ctx: Context) -> ExamplesData:
    from vinadv.report import figures

    records, chosen, pairs = _examples(ctx)
    position = {p.pair_index: i for i, p in enumerate(pairs)}
    # figs. 1 and 2: a successful attack when there is one (FP, then UrP), else any pair
    lead = next((int(chosen[lab][0]) for lab in ("FP", "UrP", "DP", "UcP") if len(chosen[lab])), pairs[0].pair_index)
    i = position[lead]
    fig1 = Figure(
        tuple(figures.map_pair(records, i, ctx.out / "fig1_map_pair", with_paths=False)),
        "Fig. 1: a pair of maps, the normal map and the adversarial map ("
        + ("one added obstacle" if records.n_added == 1 else f"{records.n_added} added obstacles")
        + ", orange).",
        "original and adversarial map",
        760,
    )
    fig2 = Figure(
        tuple(figures.map_pair(records, i, ctx.out / "fig2_path_pair", with_paths=True, distances=pairs[i])),
        "Fig. 2: the pair of paths the VIN plans on them (original red, adversarial blue dashed).",
        "original and adversarial path",
        760,
    )
    fig5 = Figure(
        tuple(figures.example_pairs(records, ctx.out / "fig5_map_pairs", distances=pairs)),
        f"Fig. 5: examples of map pairs ({len(pairs)}: up to two per category), original map and path "
        "above, adversarial map with both paths below.",
        "example map pairs",
    )
    return ExamplesData(fig1=fig1, fig2=fig2, fig5=fig5, pairs=pairs, t=pairs[0].t)


def gather_categories(ctx: Context) -> CategoriesData:
    from vinadv.report import figures

    records, chosen, pairs = _examples(ctx)
    position = {p.pair_index: i for i, p in enumerate(pairs)}
    shown = {label: position[int(chosen[label][0])] for label in CATEGORY_ORDER if len(chosen[label])}
    figure = Figure(
        tuple(
            figures.categories(
                {label: (records, i) for label, i in shown.items()},
                ctx.out / "fig3_categories",
                distances={label: pairs[i] for label, i in shown.items()},
            )
        ),
        "Fig. 3: the four categories. Rows: original map (red path), adversarial map (blue path), path "
        "image (blue = adversarial path, red = original path drawn on top).",
        "the four categories",
        900,
    )
    return CategoriesData(
        figure=figure,
        pairs=[pairs[i] for i in shown.values()],
        missing=[label for label in CATEGORY_ORDER if label not in shown],
    )


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
        rows.append(
            RunCounts(
                run_id=rid,
                name=info.get("name"),
                attack=info.get("attack"),
                labelled_by=", ".join(sources) or (info.get("classifier") or RULE_SOURCE),
                by_model=any(s != RULE_SOURCE for s in sources),
                counts={lab: int(ctx.store.label_counts(rid).get(lab, 0)) for lab in ALL_LABELS},
            )
        )
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
        ],
    )
    bars = [(f"run {r.run_id} ({r.attack or '—'})" + (" †" if r.by_model else ""), r.counts) for r in rows]
    figure = Figure(
        tuple(figures.category_bars(bars, paper.TABLE4, ctx.out / "fig_table4_categories")),
        "Table 4 as bars: share of each category (paper: no invalid category).",
        "category distribution",
        760,
    )
    return DistributionData(runs=rows, paper=dict(paper.TABLE4), table=table, figure=figure)


# ------------------------------------------------------------------------------------------------- harm

#: the example kinds of the harm section, `(label, harm)`: a fork the planner was right to take, a detour that hurt
HARM_EXAMPLES = (("FP", "harmless"), ("DP", "harmful"))
#: pairs shown per example kind
HARM_EXAMPLES_SHOWN = 4
#: the labels of the regret histogram (both paths reach the goal, so both regrets exist)
REGRET_LABELS = ("FP", "DP")
#: at most this many histogram bins: the bin width is the smallest of `_BIN_WIDTHS` that keeps to it
_MAX_BINS = 40
_BIN_WIDTHS = (0.05, 0.1, 0.125, 0.25, 0.5, 1.0, 2.0, 2.5, 5.0, 10.0, 20.0, 25.0, 50.0, 100.0)
NOT_COMPUTED = "not computed"


@dataclass(frozen=True)
class HarmExample:
    """One pair of the harm examples: its stored label, harm and costs (cost units) and the expert (optimal,
    DESIGN.md tie-break) paths recomputed for the figure, `((row, col), ...)` on each map, with their costs."""

    pair_index: int
    label: str
    harm: str
    expert_label: str | None
    cost_o: float
    opt_cost_o: float
    regret_o: float
    cost_a: float
    opt_cost_a: float
    regret_a: float
    expert_path_o: tuple[tuple[int, int], ...]
    expert_path_a: tuple[tuple[int, int], ...]
    expert_cost_o: float
    expert_cost_a: float

    @property
    def change(self) -> float:
        """`regret_a - regret_o`: the regret the attack added."""
        return self.regret_a - self.regret_o


@dataclass(frozen=True)
class RegretChanges:
    """The regret change `regret_a - regret_o` of one label's pairs (those with both regrets): how many pairs are
    harmful / harmless, how many lost (`improved`, change < -tol), kept (`same`, |change| <= tol) or added
    regret (`added`, change > tol), the mean and the largest change."""

    label: str
    pairs: int
    harmful: int
    harmless: int
    improved: int
    same: int
    added: int
    mean: float | None
    largest: float | None


@dataclass
class HarmData:
    """The harm section of the main run. `available`: some pair of the run has harm stored (a run stored before
    vinadv computed harm has none: then every other field is empty). `counts`: {label: {harm: pairs}}, every label
    and harm value (and `NOT_COMPUTED` where some pairs lack harm); `rates`: the paper's success rate and the
    harmful rate, both over the valid pairs with harm; `tol`, `rtol`: the run's harm tolerances."""

    run_id: int
    available: bool
    total: int
    not_computed: int
    harms: tuple[str, ...]
    counts: dict[str, dict[str, int]]
    rates: dict[str, float | None]
    tol: float
    rtol: float
    table: Table | None = None
    changes: list[RegretChanges] = field(default_factory=list)
    changes_table: Table | None = None
    histogram: Figure | None = None
    histogram_table: Table | None = None
    examples: dict[str, list[HarmExample]] = field(default_factory=dict)  # {"harmless FP": [...], ...}
    example_figures: dict[str, Figure] = field(default_factory=dict)  # the same keys, kinds with pairs only

    def row_total(self, label: str) -> int:
        return sum(self.counts[label].values())


def change_bins(values: np.ndarray, tol: float) -> np.ndarray:
    """Histogram bin edges for regret changes `values` (at least one): an edge at `tol`, so the bins
    `(edges[k], edges[k + 1]]` never mix changes above and below it, a round width keeping to `_MAX_BINS`, the
    first edge below the smallest value and the last at or above the largest (0 always inside)."""
    lo, hi = min(float(values.min()), 0.0), max(float(values.max()), 0.0)
    width = next((w for w in _BIN_WIDTHS if (hi - lo) / w <= _MAX_BINS - 2), None)
    if width is None:
        width = _BIN_WIDTHS[-1] * 10 ** np.ceil(np.log10((hi - lo) / (_MAX_BINS - 2) / _BIN_WIDTHS[-1]))
    first = int(np.ceil((lo - tol) / width)) - 1
    last = max(int(np.ceil((hi - tol) / width)), first + 1)
    return tol + np.round(width * np.arange(first, last + 1), 9)  # round: 0.3, not 0.30000000000000004


def gather_harm(ctx: Context) -> HarmData:
    from vinadv.classify.harm import DEFAULT_TOL, harm_summary
    from vinadv.vocabulary import HARMS, SUCCESS_LABELS

    config = ctx.store.run_info(ctx.run_id).get("config") or {}
    tol, rtol = float(config.get("harm_tolerance", DEFAULT_TOL)), float(config.get("harm_rtol", 0.0))
    stored = ctx.store.harm_counts(ctx.run_id)
    not_computed = sum(row.get(None, 0) for row in stored.values())
    total = sum(sum(row.values()) for row in stored.values())
    harms = HARMS + ((NOT_COMPUTED,) if not_computed else ())
    counts = {
        label: {h: int(stored.get(label, {}).get(None if h == NOT_COMPUTED else h, 0)) for h in harms}
        for label in ALL_LABELS
    }
    available = not_computed < total
    summary = harm_summary(counts)
    valid = summary["harm_counts"]["harmful"] + summary["harm_counts"]["harmless"]
    success = sum(counts[label]["harmful"] + counts[label]["harmless"] for label in SUCCESS_LABELS)
    data = HarmData(
        run_id=ctx.run_id,
        available=available,
        total=total,
        not_computed=not_computed,
        harms=harms,
        counts=counts,
        rates={"success": success / valid if valid else None, "harmful": summary["harmful_rate"]},
        tol=tol,
        rtol=rtol,
    )
    if not available:
        return data
    data.table = Table(
        "harm_label_x_harm.csv",
        ("label", *harms, "pairs", "harmful_share"),
        [
            [
                label,
                *(counts[label][h] for h in harms),
                data.row_total(label),
                counts[label]["harmful"] / data.row_total(label) if data.row_total(label) else None,
            ]
            for label in ALL_LABELS
        ],
    )
    _harm_regrets(ctx, data)
    _harm_examples(ctx, data, bool(config.get("corner_cutting", True)))
    return data


def _harm_regrets(ctx: Context, data: HarmData) -> None:
    """The regret change summary and histogram of the FP and DP pairs, from one GROUP BY (`Store.regret_changes`)."""
    from vinadv.report import figures

    groups = ctx.store.regret_changes(ctx.run_id, REGRET_LABELS)
    for label in REGRET_LABELS:
        parts = {harm: groups[(label, harm)] for harm in ("harmful", "harmless") if (label, harm) in groups}
        values = np.concatenate([v for v, _ in parts.values()]) if parts else np.zeros(0)
        weights = np.concatenate([k for _, k in parts.values()]) if parts else np.zeros(0, np.int64)
        n = int(weights.sum())
        data.changes.append(
            RegretChanges(
                label=label,
                pairs=n,
                harmful=int(parts["harmful"][1].sum()) if "harmful" in parts else 0,
                harmless=int(parts["harmless"][1].sum()) if "harmless" in parts else 0,
                improved=int(weights[values < -data.tol].sum()),
                same=int(weights[np.abs(values) <= data.tol].sum()),
                added=int(weights[values > data.tol].sum()),
                mean=float(np.dot(values, weights) / n) if n else None,
                largest=float(values.max()) if n else None,
            )
        )
    data.changes_table = Table(
        "harm_regret_changes.csv",
        ("label", "pairs", "harmful", "harmless", "improved", "same", "added", "mean_change", "largest_change"),
        [
            [c.label, c.pairs, c.harmful, c.harmless, c.improved, c.same, c.added, c.mean, c.largest]
            for c in data.changes
        ],
    )
    if not groups:
        return
    edges = change_bins(np.concatenate([v for v, _ in groups.values()]), data.tol)
    binned = {
        label: {
            harm: np.bincount(
                np.searchsorted(edges, values, side="left") - 1, weights=k, minlength=len(edges) - 1
            ).astype(np.int64)
            for (lab, harm), (values, k) in groups.items()
            if lab == label
        }
        for label in REGRET_LABELS
    }
    data.histogram_table = Table(
        "harm_regret_histogram.csv",
        ("label", "change_above", "change_at_most", "harmful", "harmless"),
        [
            [
                label,
                float(edges[b]),
                float(edges[b + 1]),
                *(int(binned[label][h][b]) if h in binned[label] else 0 for h in ("harmful", "harmless")),
            ]
            for label in REGRET_LABELS
            for b in range(len(edges) - 1)
        ],
    )
    rel = f" + {data.rtol:g} x opt_cost_a" if data.rtol else ""
    data.histogram = Figure(
        tuple(figures.regret_histogram(edges, binned, data.tol, ctx.out / "fig_harm_regret")),
        "The regret the attack added, regret_a - regret_o (cost units; 1 = one orthogonal move), of the FP and DP "
        "pairs: how much further from the optimal cost the adversarial path is than the original path was. A pair "
        f"is harmful when it is over the tolerance{rel} (dashed line), harmless at 0 (the planner moved onto "
        "another route as close to optimal as before) or below (the attack even brought it closer to optimal). "
        "Bars stacked by the stored harm; counts on a log scale.",
        "regret change histogram",
        880,
    )


def _harm_examples(ctx: Context, data: HarmData, corner_cutting: bool) -> None:
    """Up to `HARM_EXAMPLES_SHOWN` pairs of each `HARM_EXAMPLES` kind (the first by pair index), their expert
    paths recomputed on both maps (`grid.shortest_paths.expert_paths`: the few pairs shown, nothing stored)."""
    from vinadv.grid.shortest_paths import expert_paths
    from vinadv.report import figures

    for label, harm in HARM_EXAMPLES:
        kind = f"{harm} {label}"
        chosen = [
            r["pair_index"] for r in ctx.store.page_pairs(ctx.run_id, label=label, harm=harm, limit=HARM_EXAMPLES_SHOWN)
        ]
        data.examples[kind] = []
        if not chosen:
            continue
        records = ctx.store.read_pairs(ctx.run_id, pair_indices=np.array(chosen, dtype=np.int64))
        starts = records.starts[:, None, :]
        cost_o, paths_o = expert_paths(records.obstacles_o, records.goals, starts, corner_cutting)
        cost_a, paths_a = expert_paths(records.obstacles_a, records.goals, starts, corner_cutting)
        shown = [
            HarmExample(
                pair_index=int(records.pair_index[i]),
                label=str(records.label[i]),
                harm=str(records.harm[i]),
                expert_label=records.expert_label[i],
                **{
                    name: float(getattr(records, name)[i])
                    for name in ("cost_o", "opt_cost_o", "regret_o", "cost_a", "opt_cost_a", "regret_a")
                },
                expert_path_o=tuple(map(tuple, paths_o[i].tolist())),
                expert_path_a=tuple(map(tuple, paths_a[i].tolist())),
                expert_cost_o=float(cost_o[i, 0]),
                expert_cost_a=float(cost_a[i, 0]),
            )
            for i in range(len(records))
        ]
        data.examples[kind] = shown
        what = (
            "forks the paper counts as successful attacks, yet the adversarial path is no further from optimal "
            "than the original"
            if harm == "harmless"
            else "detours the paper counts as failed attacks, yet the adversarial path is further from optimal than "
            "the original"
        )
        figure = Figure(
            tuple(figures.harm_pairs(records, shown, ctx.out / f"fig_harm_{harm}_{label}")),
            f"{harm.capitalize()} {label} pairs ({len(shown)}, the first by pair index): {what}. "
            "Each pair: the original map with the planner's path (red) and the expert, optimal path "
            "(green, seen where the two differ), next to the adversarial map with the planner's path "
            "(blue, dashed), the expert path on that map and the added obstacle (orange).",
            kind,
            900,
        )
        data.example_figures[kind] = figure


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
            why = (
                f"run {rid} has {counts.get('FP', 0)} FP and {counts.get('DP', 0)} DP pairs; the comparison "
                "needs at least 2 of each (a larger --n, or another attack strategy)"
            )
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
        **_classifier_tables(classifiers, results, rows, points, prefix),
    )


def _classifier_tables(
    classifiers: list[str], settings: list[SettingResult], rows: list[dict], points: dict, prefix: str
) -> dict[str, Table | None]:
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
                    paper.TRAINING_S.get(kind) if s.setting == "baseline" else None,
                ]
            )
            table6.append(
                [
                    kind,
                    s.setting,
                    bal["metrics"].get("accuracy"),
                    imb["metrics"].get("accuracy") if imb else None,
                    bal["metrics"]["per_class"]["FP"]["f1"],
                    paper.ACCURACY.get(kind) if s.setting == "baseline" else None,
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
            ("classifier", "setting", "train_size", "training_s", "paper_s"),
            table5,
        ),
        "table6": Table(
            f"{prefix}table6_accuracy.csv",
            ("classifier", "setting", "accuracy_balanced", "accuracy_imbalanced", "fp_f1_balanced", "paper_accuracy"),
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
    n = len(records)
    scale = 100.0 / max(n, 1)
    table = Table(
        "table7_processing_time.csv",
        ("method", "pairs", "seconds_measured", "seconds_per_100", "paper_seconds"),
        [
            *[
                [
                    f"hybrid_svm_{setting}",
                    k,
                    s,
                    s * 100.0 / max(k, 1),
                    paper.PROCESSING_S["training"] if setting == "baseline" else None,
                ]
                for setting, k, s in hybrid
            ],
            ["rule", n, rule_s, rule_s * scale, None],
            ["database_read", n, read_s, read_s * scale, None],
            ["manual", None, None, None, paper.PROCESSING_S["manual"]],
        ],
    )
    machine = f"{platform.machine()}, {os.cpu_count()} CPUs, Python {platform.python_version()}"
    return TimingData(
        run_id=ctx.run_id,
        pairs=n,
        counts=counts,
        read_s=read_s,
        rule_s=rule_s,
        hybrid=hybrid,
        machine=machine,
        repeats=TIMING_REPEATS,
        table=table,
    )


# -------------------------------------------------------------------------------------------- robustness

#: the worst case over the strategies, as `vinadv.robustness.WORST_CASE` names it (not imported: no torch here)
WORST_CASE = "worst case"


@dataclass(frozen=True)
class Benchmark:
    """One stored robustness benchmark (`vinadv robustness`): what was measured and its figures, as stored
    (`worst`: the worst case by k, `by_strategy`: {strategy: figures by k}; figures as `Figures.to_dict`)."""

    id: int | None
    created: str
    planner: str
    weights: str | None
    n: int
    size: int
    maps_seed: int
    objective: str
    strategies: tuple[str, ...]
    clean_success: float | None
    clean_regret: float | None
    worst: list[dict]
    by_strategy: dict[str, list[dict]]
    seconds: dict[str, float]

    @property
    def name(self) -> str:
        """The benchmark in a legend: planner, weights (first 8 hex digits) and id."""
        weights = f" {self.weights[:8]}" if self.weights else ""
        return f"{self.planner}{weights}" + (f" (#{self.id})" if self.id is not None else "")


@dataclass
class RobustnessData:
    """The robustness benchmarks of the database, oldest first (none: `benchmarks` empty, nothing else)."""

    benchmarks: list[Benchmark]
    table: Table | None = None
    figure: Figure | None = None

    @property
    def max_k(self) -> int:
        return max([0] + [len(b.worst) for b in self.benchmarks])


def robustness_section(rows: list[dict], out: Path) -> RobustnessData:
    """The robustness section of `rows`, robustness benchmarks as `Store.read_robustness` returns them (`id` None for
    one not stored): the comparison table, its CSV (every strategy and the worst case at every k) and the curves."""
    from vinadv.report import figures

    benchmarks = []
    for row in rows:
        result, settings = row["result"], row["settings"]
        benchmarks.append(
            Benchmark(
                id=row.get("id"),
                created=str(row.get("created") or ""),
                planner=str(row["planner"]),
                weights=row.get("weights_checksum"),
                n=int(settings["n"]),
                size=int(settings["size"]),
                maps_seed=int(settings["maps_seed"]),
                objective=str(settings["objective"]),
                strategies=tuple(settings["strategies"]),
                clean_success=result["clean"]["success_rate"],
                clean_regret=result["clean"]["mean_regret"],
                worst=list(result["overall"]),
                by_strategy={name: s["by_obstacles"] for name, s in result["strategies"].items()},
                seconds={
                    **{name: s["seconds"] for name, s in result["strategies"].items()},
                    "total": result["seconds"],
                },
            )
        )
    data = RobustnessData(benchmarks=benchmarks)
    if not benchmarks:
        return data
    keys = ("valid", "broken", "paper_success_rate", "harmful", "harmful_rate", "reached", "mean_regret")
    data.table = Table(
        "robustness.csv",
        (
            "benchmark",
            "planner",
            "weights_sha256",
            "maps",
            "size",
            "maps_seed",
            "objective",
            "clean_success",
            "strategy",
            "k",
            *keys,
            "seconds",
        ),
        [
            [
                b.id,
                b.planner,
                b.weights,
                b.n,
                b.size,
                b.maps_seed,
                b.objective,
                b.clean_success,
                name,
                f["k"],
                *(f[key] for key in keys),
                b.seconds.get(name, b.seconds["total"]),
            ]
            for b in benchmarks
            for name, by_k in (*b.by_strategy.items(), (WORST_CASE, b.worst))
            for f in by_k
        ],
    )
    data.figure = Figure(
        tuple(figures.robustness_curves([(b.name, b.worst) for b in benchmarks], out / "fig_robustness")),
        "Robustness curves: the share of valid maps that k added obstacles make harmful (left) or break by the "
        "paper's definition, UrP or FP (right), worst case over the strategies of each benchmark.",
        "robustness curves",
        880,
    )
    return data


def gather_robustness(ctx: Context) -> RobustnessData:
    return robustness_section(ctx.store.read_robustness(), ctx.out)


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
            found += [
                f for v in vars(data).values() if isinstance(v, dict) for f in v.values() if isinstance(f, Figure)
            ]
            for ev in getattr(data, "evaluations", []):
                found += [f for f in (ev.fig8, *(s.fig9 for s in ev.settings)) if f is not None]
        return found

    def files(self) -> list[str]:
        return sorted({*(t.name for t in self.tables()), *(n for f in self.figures() for n in f.files)})


#: the page's sections in order: (id, heading, gather function)
SECTIONS = (
    ("run", "Run and configuration", gather_run),
    ("vin", "The planner's quality", gather_vin),
    ("examples", "Example map pairs (figs. 1, 2, 5)", gather_examples),
    ("categories", "The four categories (fig. 3)", gather_categories),
    ("distribution", "Category distribution (table 4)", gather_distribution),
    ("harm", "Harm: worse paths, or only different ones?", gather_harm),
    ("classifiers", "Classifier comparison (tables 5, 6; figs. 8, 9)", gather_classifiers),
    ("robustness", "Robustness benchmarks", gather_robustness),
    ("timing", "Processing time for 100 pairs (table 7)", gather_timing),
)


def gather_report(ctx: Context, order: list[str] | None = None) -> ReportData:
    """Gather every section (in `order` of section ids, default the page's: any order gives the same data)."""
    from vinadv import __version__

    gatherers = {sid: fn for sid, _, fn in SECTIONS}
    info = ctx.runs[ctx.run_id]
    data = ReportData(
        run_id=ctx.run_id,
        run_name=info.get("name"),
        compare=list(ctx.compare),
        url=ctx.store.url,
        version=__version__,
        generated=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
    )
    for sid in order or list(gatherers):
        data.sections[sid] = gatherers[sid](ctx)
    data.sections = {sid: data.sections[sid] for sid in gatherers if sid in data.sections}
    return data
