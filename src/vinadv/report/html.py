"""`vinadv report`: the paper's evaluation of a stored run as one self-contained HTML page, figures and CSV tables.

`write_report(db, out_dir, run_id=None, runs=None)` writes `out_dir/index.html` (relative links only, no script,
no external resource), PNG + SVG figures and CSV tables, and returns the path of `index.html`. Every number on the
page is read from the database (pairs, runs, stored evaluations) or measured while the report is written (the
processing time for 100 pairs, and the VIN's quality when no metrics file ships with its weights). The paper's
numbers are shown beside ours wherever the paper has one.
"""

from __future__ import annotations

import csv
import html
import json
import os
import platform
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import sqlalchemy as sa

from vinadv import __version__
from vinadv.errors import InputError
from vinadv.outfile import atomic_output
from vinadv.report.evaluate import TIMING_REPEATS, median_seconds

#: the paper's numbers (Wang et al., tables 4-7 and section 5.2)
PAPER_TABLE4 = {"UrP": 1632, "FP": 204, "DP": 1076, "UcP": 2088}
PAPER_TRAINING_S = {"svm": 46.0, "cnn": 474.0, "mlp": 105.0}
PAPER_ACCURACY = {"svm": 0.97, "cnn": 0.76, "mlp": 0.68}
PAPER_SVM_ACCURACY = {"imbalanced": 0.91, "balanced": 0.97}
PAPER_PROCESSING_S = {"training": 0.22, "manual": 300.0}
PAPER_ENV = "Intel i7-4510U, 8 GB, Windows 10, Python 2.7"

CATEGORY_ORDER = ("UrP", "FP", "DP", "UcP")
QUICK_EVAL_MAPS = 50
QUICK_EVAL_SEED = 20_240_601

SECTIONS = (
    ("run", "Run and configuration"),
    ("vin", "The VIN's quality"),
    ("examples", "Example map pairs (figs. 1, 2, 5)"),
    ("categories", "The four categories (fig. 3)"),
    ("distribution", "Category distribution (table 4)"),
    ("classifiers", "Classifier comparison (tables 5, 6; figs. 8, 9)"),
    ("timing", "Processing time for 100 pairs (table 7)"),
    ("files", "Files"),
)


@dataclass
class ReportResult:
    """What `build_report` wrote and measured."""

    index: Path
    run_id: int
    runs: list[int]
    files: list[str] = field(default_factory=list)
    timing: dict = field(default_factory=dict)
    vin: dict = field(default_factory=dict)
    evaluated: bool = False

    def to_dict(self) -> dict:
        return {"index": str(self.index), "run_id": self.run_id, "runs": self.runs, "files": self.files,
                "timing": self.timing, "vin": self.vin, "evaluated": self.evaluated}


def write_report(db: str | None, out_dir, run_id: int | None = None, runs: list[int] | None = None) -> Path:
    """Write the report of `run_id` (default: the last of `runs`, else the latest run) to `out_dir`; table 4
    compares `runs` (default: just that run). Returns the path of `index.html`."""
    return build_report(db, out_dir, run_id=run_id, runs=runs).index


def build_report(db: str | None, out_dir, run_id: int | str | None = None,
                 runs: list[int | str] | None = None) -> ReportResult:
    """`write_report`, returning what was written and measured. Runs are ids or names (`Store.resolve_run`)."""
    from vinadv.store import Store

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out}: exists and is not a directory")
    with Store.open(db, readonly=True) as store:
        listed = store.list_runs()
        if not listed:
            raise InputError(f"database {store.url}: no runs stored yet (run `vinadv run` first)")
        known = {int(r["id"]): r for r in listed}
        runs = None if runs is None else [store.resolve_run(r, "--runs") for r in runs]
        run_id = None if run_id is None else store.resolve_run(run_id)
        primary = int(run_id) if run_id is not None else int(runs[-1]) if runs else max(known)
        compare = [int(r) for r in runs] if runs else [primary]
        if primary not in compare:
            compare.append(primary)
        if known[primary]["n_pairs"] == 0:
            raise InputError(f"run {primary} has no stored pairs")
        out.mkdir(parents=True, exist_ok=True)
        builder = _Builder(store, out, primary, compare, known)
        builder.build()
    return builder.result


# ------------------------------------------------------------------------------------------------ helpers

def _esc(value) -> str:
    return html.escape("" if value is None else str(value))


def _num(value, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "—"
    if isinstance(value, (int, np.integer)):
        return f"{int(value):,}"
    return f"{float(value):.{digits}f}"


def _pct(value) -> str:
    return "—" if value is None else f"{100.0 * float(value):.1f}%"


def _seconds(value) -> str:
    if value is None:
        return "—"
    value = float(value)
    if value >= 10:
        return f"{value:,.0f} s"
    if value >= 0.1:
        return f"{value:.2f} s"
    if value >= 1e-3:
        return f"{1e3 * value:.1f} ms"
    return f"{1e6 * value:.0f} µs"


def _table(header: list[str] | None, rows: list[list], caption: str | None = None, cls: str = "") -> str:
    """An HTML table; cells are escaped unless wrapped in `_Raw`."""
    def cell(v):
        return v.text if isinstance(v, _Raw) else _esc(v)

    parts = [f'<table class="{cls}">']
    if caption:
        parts.append(f"<caption>{_esc(caption)}</caption>")
    if header:
        parts.append("<thead><tr>" + "".join(f"<th>{_esc(h)}</th>" for h in header) + "</tr></thead>")
    parts.append("<tbody>")
    for row in rows:
        parts.append("<tr>" + "".join(f"<td>{cell(v)}</td>" for v in row) + "</tr>")
    parts.append("</tbody></table>")
    return "\n".join(parts)


@dataclass
class _Raw:
    text: str


class _Builder:
    def __init__(self, store, out: Path, run_id: int, compare: list[int], known: dict):
        self.store = store
        self.out = out
        self.run_id = run_id
        self.compare = compare
        self.known = known
        self.info = store.run_info(run_id)
        self.sections: dict[str, str] = {}
        self.result = ReportResult(out / "index.html", run_id, compare)

    # ------------------------------------------------------------------------------------------ output
    def figure(self, names: list[str], caption: str, alt: str, width: int | None = None) -> str:
        self.result.files += names
        png = next(n for n in names if n.endswith(".png"))
        svg = next((n for n in names if n.endswith(".svg")), None)
        style = f' style="max-width:{width}px"' if width else ""
        link = f' (<a href="{_esc(svg)}">SVG</a>, <a href="{_esc(png)}">PNG</a>)' if svg else ""
        return (f'<figure><img src="{_esc(png)}" alt="{_esc(alt)}"{style}>'
                f"<figcaption>{_esc(caption)}{link}</figcaption></figure>")

    def csv(self, name: str, header: list[str], rows: list[list]) -> str:
        with atomic_output(self.out / name, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(header)
            writer.writerows([["" if v is None else v for v in row] for row in rows])
        self.result.files.append(name)
        return f'<p class="csv">Table as CSV: <a href="{_esc(name)}">{_esc(name)}</a></p>'

    # ------------------------------------------------------------------------------------------- build
    def build(self) -> None:
        from vinadv.report import figures  # matplotlib only when a report is written

        self.fig = figures
        self.counts = {rid: self.store.label_counts(rid) for rid in self.compare}
        self.sections["run"] = self.section_run()
        self.sections["vin"] = self.section_vin()
        self.sections["examples"], self.sections["categories"] = self.section_examples()
        self.sections["distribution"] = self.section_distribution()
        self.sections["classifiers"] = self.section_classifiers()
        self.sections["timing"] = self.section_timing()
        self.sections["files"] = self.section_files()
        with atomic_output(self.result.index, "w", encoding="utf-8") as fh:
            fh.write(self.page())

    def page(self) -> str:
        title = f"vinadv report: run {self.run_id}" + (f" ({self.info['name']})" if self.info.get("name") else "")
        nav = " · ".join(f'<a href="#{sid}">{_esc(name)}</a>' for sid, name in SECTIONS)
        body = "\n".join(
            f'<section id="{sid}"><h2>{_esc(name)}</h2>\n{self.sections[sid]}\n</section>' for sid, name in SECTIONS
        )
        generated = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
        return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<link rel="icon" href="data:,">
<title>{_esc(title)}</title>
<style>
body {{ font-family: system-ui, -apple-system, "Segoe UI", sans-serif; margin: 0 auto; max-width: 1200px;
       padding: 1em 2em; color: #222; line-height: 1.4; }}
h1 {{ font-size: 1.6em; }} h2 {{ border-bottom: 1px solid #ccc; padding-bottom: .2em; margin-top: 2em; }}
table {{ border-collapse: collapse; margin: .8em 0; font-size: .92em; }}
th, td {{ border: 1px solid #ccc; padding: .25em .6em; text-align: right; }}
th {{ background: #f2f2f2; }} td:first-child, th:first-child {{ text-align: left; }}
caption {{ caption-side: top; text-align: left; font-weight: 600; padding: .3em 0; }}
table.kv td {{ text-align: left; }} table.kv td:first-child {{ font-weight: 600; }}
figure {{ margin: 1em 0; }} figure img {{ max-width: 100%; height: auto; border: 1px solid #eee; }}
figcaption {{ font-size: .9em; color: #555; }}
.paper {{ color: #7a4b00; }} .note {{ background: #fff8e1; border-left: 4px solid #f0b400; padding: .5em 1em; }}
code {{ background: #f4f4f4; padding: 0 .2em; }} nav {{ font-size: .9em; }}
</style>
</head>
<body>
<h1>{_esc(title)}</h1>
<p>Regenerates the evaluation of Wang et al., <em>A Training-based Identification Approach to VIN Adversarial
Examples</em>, on this database. Numbers in <span class="paper">brown</span> columns are the paper's (5,000 pairs,
28x28 maps, {_esc(PAPER_ENV)}); every other number is read from the database or measured while this page was
written. Database: <code>{_esc(self.store.url)}</code>; vinadv {_esc(__version__)}; written {_esc(generated)}.</p>
<nav>{nav}</nav>
{body}
</body>
</html>
"""

    # --------------------------------------------------------------------------------------------- run
    def section_run(self) -> str:
        info = self.info
        n_pairs = self.known[self.run_id]["n_pairs"]
        sources = self.store.label_sources(self.run_id)
        rows = [
            ["run id", info["id"]], ["name", info.get("name") or "—"], ["created (UTC)", info["created"]],
            ["status", info["status"]], ["attack strategy", info.get("attack") or "—"],
            ["labelled by", info.get("classifier") or ", ".join(sources)], ["label sources", ", ".join(sources)],
            ["seed", info.get("seed")], ["stored pairs", f"{n_pairs:,}"],
            ["planner weights (SHA-256)", info.get("weights_checksum") or "—"], ["vinadv version", info["version"]],
        ]
        config = info.get("config") or {}
        config_rows = [[k, json.dumps(v) if isinstance(v, (dict, list)) else v] for k, v in sorted(config.items())]
        timings = info.get("timings") or {}
        timing_rows = [[k, _seconds(v) if isinstance(v, (int, float)) else v] for k, v in timings.items()]
        parts = [_table(None, rows, "run", "kv")]
        parts.append(_table(["option", "value"], config_rows, "configuration", "kv") if config_rows
                     else "<p>No configuration stored with this run.</p>")
        parts.append(_table(["stage", "seconds"], timing_rows, "timings (stored by the run)", "kv") if timing_rows
                     else "<p>No timings stored (the run did not finish?).</p>")
        parts.append(self.csv("run_config.csv", ["key", "value"],
                              [[r[0], r[1]] for r in rows] + [[f"config.{k}", v] for k, v in config_rows]
                              + [[f"timings.{k}", v] for k, v in timings.items()]))
        return "\n".join(parts)

    # --------------------------------------------------------------------------------------------- VIN
    def section_vin(self) -> str:
        from vinadv.store.schema import map_pairs

        with self.store.engine.connect() as conn:
            terms = dict(conn.execute(
                sa.select(map_pairs.c.term_o, sa.func.count()).where(map_pairs.c.run_id == self.run_id)
                .group_by(map_pairs.c.term_o)).all())
        total = sum(terms.values())
        reached = terms.get("goal", 0)
        metrics, source = self.vin_metrics()
        self.result.vin = {"source": source, **{k: metrics.get(k) for k in
                                                ("success_rate", "optimal_rate", "action_accuracy")},
                           "run_original_reached": reached / total if total else None}
        rows = [["success rate (goal reached)", _pct(metrics.get("success_rate"))],
                ["% optimal paths", _pct(metrics.get("optimal_rate"))],
                ["% optimal among reached", _pct(metrics.get("optimal_rate_of_reached"))],
                ["action accuracy (optimal action at every free cell)", _pct(metrics.get("action_accuracy"))],
                ["mean extra path cost (reached)", _num(metrics.get("mean_extra_cost"))],
                ["maps x starts evaluated", f"{_num(metrics.get('maps'))} x {_num(metrics.get('starts_per_map'))}"
                 if metrics else "—"]]
        run_rows = [["original paths of this run reaching the goal", f"{reached:,} of {total:,} "
                     f"({_pct(reached / total if total else None)})"]]
        run_rows += [[f"original paths ended by {k}", f"{v:,}"] for k, v in sorted(terms.items())]
        parts = [f"<p>Source: {_esc(source)}.</p>", _table(["figure", "value"], rows, "planner quality", "kv"),
                 _table(["figure", "value"], run_rows, "on this run's original maps (from the database)", "kv"),
                 self.csv("vin_quality.csv", ["figure", "value"], rows + run_rows)]
        return "\n".join(parts)

    def vin_metrics(self) -> tuple[dict, str]:
        """The VIN's metrics: from a metrics JSON next to its weights, else a quick evaluation now."""
        from vinadv.planners.weights import default_weights_path, weights_checksum

        config = self.info.get("config") or {}
        size = int(config.get("size") or self.store.read_pairs(
            self.run_id, pair_indices=np.asarray(self.store.stored_indices(self.run_id)[:1])).size)
        path = Path(config["weights"]) if config.get("weights") else default_weights_path(size)
        if not path.exists():
            return {}, f"not available: the run's weights file {path} is not on this machine"
        checksum = self.info.get("weights_checksum")
        if checksum and weights_checksum(path) != checksum:
            return {}, f"not available: {path} is not the file the run used (its checksum differs)"
        for candidate in (path.with_suffix(".metrics.json"), path.with_name(path.stem + "_metrics.json"),
                          path.with_name(path.stem + "-metrics.json"), path.with_name(path.name + ".metrics.json"),
                          path.with_suffix(".json")):
            if candidate.exists():
                try:
                    data = json.loads(candidate.read_text())
                except (OSError, ValueError):
                    continue
                found = _find_metrics(data)
                if found:
                    return found, f"metrics file {candidate.name} shipped with the weights {path.name}"
        from vinadv.grid.generator import generate_maps
        from vinadv.planners.evaluation import evaluate_vin
        from vinadv.planners.weights import load_vin

        model = load_vin(path, size=size)
        found = _find_metrics(getattr(model, "record", None) or {})
        if found:
            return found, f"the training record inside the weights file {path.name}"
        maps = generate_maps(QUICK_EVAL_MAPS, size, seed=QUICK_EVAL_SEED,
                             corner_cutting=bool(config.get("corner_cutting", True)))
        start = time.perf_counter()
        metrics = evaluate_vin(model, maps)
        seconds = time.perf_counter() - start
        return metrics, (f"quick evaluation while writing this report: {QUICK_EVAL_MAPS} fresh {size}x{size} maps "
                         f"(seed {QUICK_EVAL_SEED}), {maps.n_starts} starts each, weights {path.name}, "
                         f"{seconds:.1f} s")

    # ---------------------------------------------------------------------------------------- examples
    def _pairs_of(self, label: str, limit: int) -> np.ndarray:
        rows = self.store.page_pairs(self.run_id, label=label, limit=limit)
        return np.array([r["pair_index"] for r in rows], dtype=np.int64)

    def section_examples(self) -> tuple[str, str]:
        fig = self.fig
        chosen = {label: self._pairs_of(label, 2) for label in CATEGORY_ORDER}
        indices = np.concatenate([chosen[label] for label in CATEGORY_ORDER] + [np.zeros(0, np.int64)])
        if len(indices) == 0:  # only invalid pairs
            indices = self._pairs_of("invalid", 4)
        records = self.store.read_pairs(self.run_id, pair_indices=indices)
        order = {int(p): i for i, p in enumerate(records.pair_index)}
        # figs. 1 and 2: a successful attack when there is one (FP, then UrP), else any pair
        lead = next((int(chosen[lab][0]) for lab in ("FP", "UrP", "DP", "UcP") if len(chosen[lab])),
                    int(records.pair_index[0]))
        parts = [
            self.figure(fig.map_pair(records, order[lead], self.out / "fig1_map_pair", with_paths=False),
                        "Fig. 1: a pair of maps, the normal map and the adversarial map (one added obstacle, orange).",
                        "original and adversarial map", 760),
            self.figure(fig.map_pair(records, order[lead], self.out / "fig2_path_pair", with_paths=True),
                        "Fig. 2: the pair of paths the VIN plans on them (original red, adversarial blue dashed).",
                        "original and adversarial path", 760),
        ]
        shown = records.subset(np.array([order[int(p)] for p in indices]))
        parts.append(self.figure(fig.example_pairs(shown, self.out / "fig5_map_pairs"),
                                 f"Fig. 5: examples of map pairs ({len(shown)}: up to two per category), original "
                                 "map and path above, adversarial map with both paths below.", "example map pairs"))
        examples = {label: (records, order[int(chosen[label][0])]) for label in CATEGORY_ORDER if len(chosen[label])}
        missing = [label for label in CATEGORY_ORDER if label not in examples]
        note = (f'<p class="note">This run has no {", ".join(missing)} pair; its column is empty.</p>'
                if missing else "")
        categories = note + self.figure(
            fig.categories(examples, self.out / "fig3_categories"),
            "Fig. 3: the four categories. Rows: original map (red path), adversarial map (blue path), path image "
            "(blue = adversarial path, red = original path drawn on top).", "the four categories", 900)
        return "\n".join(parts), categories

    # ------------------------------------------------------------------------------------ distribution
    def section_distribution(self) -> str:
        header = ["run", "attack strategy", "pairs", *[f"{lab}" for lab in CATEGORY_ORDER], "invalid",
                  "success (UrP+FP) of valid"]
        rows, csv_rows, bars = [], [], []
        for rid in self.compare:
            counts = self.counts[rid]
            info = self.known[rid]
            total = sum(counts.values())
            valid = total - counts["invalid"]
            success = counts["UrP"] + counts["FP"]
            name = f"{rid}" + (f" ({info['name']})" if info.get("name") else "")
            rows.append([name, info.get("attack") or "—", f"{total:,}",
                         *[f"{counts[lab]:,} ({_pct(counts[lab] / total if total else None)})"
                           for lab in (*CATEGORY_ORDER, "invalid")],
                         _pct(success / valid if valid else None)])
            csv_rows.append([rid, info.get("attack"), total, *[counts[lab] for lab in (*CATEGORY_ORDER, "invalid")],
                             success, valid])
            bars.append((f"run {rid} ({info.get('attack') or '—'})", counts))
        paper_total = sum(PAPER_TABLE4.values())
        paper_success = PAPER_TABLE4["UrP"] + PAPER_TABLE4["FP"]
        rows.append([_Raw('<span class="paper">paper</span>'), "Liu et al. rules", f"{paper_total:,}",
                     *[_Raw(f'<span class="paper">{PAPER_TABLE4[lab]:,} ({100 * PAPER_TABLE4[lab] / paper_total:.1f}%)'
                            "</span>") for lab in CATEGORY_ORDER], "—",
                     _Raw(f'<span class="paper">{100 * paper_success / paper_total:.1f}%</span>')])
        csv_rows.append(["paper", "", paper_total, *[PAPER_TABLE4[lab] for lab in CATEGORY_ORDER], "",
                         paper_success, paper_total])
        parts = [
            "<p>Pairs per category (UrP unreached, FP fork, DP detour, UcP unchanged; <em>invalid</em>: the VIN "
            "already fails on the original map, never counted as an attack). "
            + ("One row per compared run (attack strategy)." if len(self.compare) > 1 else "") + "</p>",
            _table(header, rows, "Table 4: the distribution of the categories"),
            self.csv("table4_categories.csv", ["run", "attack", "pairs", *CATEGORY_ORDER, "invalid", "successful",
                                               "valid"], csv_rows),
            self.figure(self.fig.category_bars(bars, PAPER_TABLE4, self.out / "fig_table4_categories"),
                        "Table 4 as bars: share of each category (paper: no invalid category).",
                        "category distribution", 760),
        ]
        return "\n".join(parts)

    # ------------------------------------------------------------------------------------- classifiers
    def latest_evaluation(self) -> tuple[list[dict], int]:
        """The newest stored row of each (classifier, training, fraction), oldest first; and how many rows are
        hidden by newer ones (`vinadv evaluate` may be run again, say for one more classifier)."""
        rows = self.store.read_evaluations(self.run_id)
        latest = {(r["classifier"], r["training"], r["train_fraction"]): r for r in rows}
        shown = sorted(latest.values(), key=lambda r: r["id"])
        return shown, len(rows) - len(shown)

    def section_classifiers(self) -> str:
        rows, hidden = self.latest_evaluation()
        self.evaluation = rows
        if not rows:
            return ('<p class="note">No classifier evaluation is stored for this run. Run '
                    f"<code>vinadv evaluate --db {_esc(self.store.url)} --run {self.run_id}</code> and write the "
                    "report again to get tables 5 and 6 and figures 8 and 9.</p>")
        self.result.evaluated = True
        full = {(r["classifier"], r["training"]): r for r in rows if r["train_fraction"] >= 1.0}
        last = rows[-1]
        m0 = last["metrics"]
        runs_of = sorted({(str(r["created"]), r["setting"], r["seed"]) for r in rows})
        stored = "; ".join(f"{created} UTC, setting {setting}, seed {seed}" for created, setting, seed in runs_of)
        intro = (f"<p>Stored evaluations ({_esc(stored)}; the newest row of each classifier and training set"
                 f"{', ' + str(hidden) + ' older rows not shown' if hidden else ''}): the run's FP/DP pairs labelled "
                 f"by the exact rule (t = {_esc(m0.get('threshold'))}), split 7:3 stratified: training "
                 f"{_esc(_counts_text(m0.get('train_counts')))}, test {_esc(_counts_text(m0.get('test_counts')))} (the real mix). Balanced "
                 "training adds flipped/rotated copies of the minority class, as the paper.</p>")
        kinds = list(dict.fromkeys(r["classifier"] for r in rows))
        # table 5: training time
        t5, t5_csv = [], []
        for kind in kinds:
            r = full.get((kind, "balanced")) or full.get((kind, "none"))
            if r is None:
                continue
            paper = PAPER_TRAINING_S.get(kind)
            if kind == "rule":  # nothing to train
                t5.append([kind, "— (no training)", "—", "—"])
                t5_csv.append([kind, 0, 0.0, None])
                continue
            t5.append([kind, f"{r['train_size']:,}", _seconds(r["metrics"].get("training_s")),
                       _Raw(f'<span class="paper">{_seconds(paper)}</span>') if paper else "—"])
            t5_csv.append([kind, r["train_size"], r["metrics"].get("training_s"), paper])
        # table 6 and the full metrics
        t6, t6_csv, detail, detail_csv = [], [], [], []
        for kind in kinds:
            bal = full.get((kind, "balanced")) or full.get((kind, "none"))
            imb = full.get((kind, "imbalanced"))
            paper = PAPER_ACCURACY.get(kind)
            if bal is not None:
                t6.append([kind, _num(bal["metrics"].get("accuracy")),
                           _num(imb["metrics"].get("accuracy")) if imb else "—",
                           _num(bal["metrics"]["per_class"]["FP"]["f1"]),
                           _Raw(f'<span class="paper">{paper:.2f}</span>') if paper else "—"])
                t6_csv.append([kind, bal["metrics"].get("accuracy"), imb["metrics"].get("accuracy") if imb else None,
                               bal["metrics"]["per_class"]["FP"]["f1"], paper])
            for training in ("balanced", "imbalanced", "none"):
                r = full.get((kind, training))
                if r is None:
                    continue
                m = r["metrics"]
                pc = m["per_class"]
                cm = m["confusion_matrix"]
                five = m.get("five_way") or {}
                detail.append([kind, training, f"{r['train_size']:,}", _num(m.get("accuracy")),
                               _num(pc["DP"]["precision"]), _num(pc["DP"]["recall"]), _num(pc["DP"]["f1"]),
                               _num(pc["FP"]["precision"]), _num(pc["FP"]["recall"]), _num(pc["FP"]["f1"]),
                               _num(m.get("roc_auc")), _num(m.get("average_precision")),
                               f"{cm[0][0]} / {cm[0][1]} / {cm[1][0]} / {cm[1][1]}",
                               _seconds(m.get("training_s")), _seconds(m.get("prediction_s_per_100")),
                               _num(five.get("accuracy")) if five else "—"])
                detail_csv.append([kind, training, r["train_size"], r["test_size"], m.get("accuracy"),
                                   pc["DP"]["precision"], pc["DP"]["recall"], pc["DP"]["f1"],
                                   pc["FP"]["precision"], pc["FP"]["recall"], pc["FP"]["f1"], m.get("roc_auc"),
                                   m.get("average_precision"), cm[0][0], cm[0][1], cm[1][0], cm[1][1],
                                   m.get("training_s"), m.get("prediction_s_per_100"), five.get("accuracy"),
                                   five.get("n")])
        parts = [intro]
        parts.append(_table(["classifier", "training pairs", "training time", "paper (70% of 5,000, 10 epochs)"],
                            t5, "Table 5: training time (balanced training set)"))
        parts.append(self.csv("table5_training_time.csv", ["classifier", "train_size", "training_s", "paper_s"],
                              t5_csv))
        parts.append(_table(["classifier", "test accuracy (balanced training)", "test accuracy (imbalanced)",
                             "FP F1 (balanced)", "paper (balanced)"], t6, "Table 6: test accuracy"))
        parts.append(self.csv("table6_accuracy.csv", ["classifier", "accuracy_balanced", "accuracy_imbalanced",
                                                      "fp_f1_balanced", "paper_accuracy"], t6_csv))
        parts.append(_table(["classifier", "training", "train pairs", "accuracy", "DP P", "DP R", "DP F1", "FP P",
                             "FP R", "FP F1", "ROC AUC", "AP", "confusion DP→DP/DP→FP/FP→DP/FP→FP",
                             "training time", "prediction / 100 pairs", "five-way accuracy"], detail,
                            "All figures on the test split (rule and hybrid also five-way, on every pair they did "
                            "not train on)"))
        parts.append(self.csv("classifier_metrics.csv", [
            "classifier", "training", "train_size", "test_size", "accuracy", "dp_precision", "dp_recall", "dp_f1",
            "fp_precision", "fp_recall", "fp_f1", "roc_auc", "average_precision", "cm_dp_dp", "cm_dp_fp",
            "cm_fp_dp", "cm_fp_fp", "training_s", "prediction_s_per_100", "five_way_accuracy", "five_way_n"],
            detail_csv))
        # fig. 8
        points: dict = {}
        for r in rows:
            if r["training"] == "balanced" and r["classifier"] not in ("hybrid", "rule"):
                points.setdefault(r["classifier"], []).append(
                    (r["train_fraction"], r["train_size"], r["metrics"].get("accuracy")))
        if points:
            parts.append(self.figure(self.fig.accuracy_vs_size(points, self.out / "fig8_accuracy_vs_size"),
                                     "Fig. 8: test accuracy against the size of the (balanced) training set.",
                                     "accuracy vs training set size", 620))
            parts.append(self.csv("fig8_accuracy_vs_size.csv", ["classifier", "fraction", "train_size", "accuracy"],
                                  [[k, f, n, a] for k, v in sorted(points.items()) for f, n, a in sorted(v)]))
        # fig. 9
        curves: dict = {}
        for (kind, training), r in full.items():
            if kind in ("hybrid", "rule") or not r.get("curves"):
                continue
            curves.setdefault(training, {})[kind] = (r["curves"], r["metrics"].get("roc_auc"),
                                                     r["metrics"].get("average_precision"))
        if curves:
            parts.append(self.figure(self.fig.roc_pr_curves(curves, self.out / "fig9_roc_pr"),
                                     "Fig. 9: PR and ROC curves on the test split, imbalanced vs balanced training "
                                     "(AP and AUC in the legends).", "ROC and PR curves"))
            svm = [[training, _num(full[("svm", training)]["metrics"].get("accuracy")),
                    _num(full[("svm", training)]["metrics"].get("roc_auc")),
                    _num(full[("svm", training)]["metrics"].get("average_precision")),
                    _Raw(f'<span class="paper">{PAPER_SVM_ACCURACY[training]:.2f}</span>')]
                   for training in ("imbalanced", "balanced") if ("svm", training) in full]
            if svm:
                parts.append(_table(["SVM training", "accuracy", "ROC AUC", "AP", "paper accuracy"], svm,
                                    "Fig. 9 in numbers (paper: AP and AUC 'relatively low' imbalanced, 'close to 1' "
                                    "balanced)"))
        return "\n".join(parts)

    # ------------------------------------------------------------------------------------------ timing
    def section_timing(self) -> str:
        from vinadv.classify import PathPairBatch, label_batch

        mix = self.timing_pairs()
        t0 = time.perf_counter()
        records = self.store.read_pairs(self.run_id, pair_indices=mix)
        read_s = time.perf_counter() - t0
        read_s = min(read_s, median_seconds(lambda: self.store.read_pairs(self.run_id, pair_indices=mix), 3))
        batch = PathPairBatch.from_arrays(records.path_o_cells, records.path_o_offsets, records.path_a_cells,
                                          records.path_a_offsets, records.goals, records.size)
        rule_s = median_seconds(lambda: label_batch(batch))
        counts = {lab: int(np.sum(records.label == lab)) for lab in ("UrP", "FP", "DP", "UcP", "invalid")}
        timing = {"pairs": len(records), "counts": counts, "read_s": read_s, "rule_s": rule_s}
        hybrid_s, hybrid_note = self.hybrid_timing(batch)
        timing["hybrid_svm_s"] = hybrid_s
        self.result.timing = timing
        scale = 100.0 / max(len(records), 1)
        rows = [
            ["training-based: hybrid (path features + SVM)",
             _seconds(hybrid_s * scale) if hybrid_s is not None else hybrid_note,
             _Raw(f'<span class="paper">{_seconds(PAPER_PROCESSING_S["training"])}</span>')],
            ["exact rule labeller (features + dh/dv rule)", _seconds(rule_s * scale), "—"],
            ["reading the pairs from the database (maps and paths decoded)", _seconds(read_s * scale), "—"],
            ["manual observation", "not measured (people)",
             _Raw(f'<span class="paper">{_seconds(PAPER_PROCESSING_S["manual"])} (approximately)</span>')],
        ]
        stored = [r for r in getattr(self, "evaluation", []) if r["classifier"] in ("hybrid", "rule")
                  and r["training"] in ("balanced", "none") and r["metrics"].get("five_way")]
        for r in stored:
            five = r["metrics"]["five_way"]
            rows.append([f"{r['classifier']} (measured by vinadv evaluate on {five['paper_mix_pairs']} pairs)",
                         _seconds(five["paper_mix_s"] * 100.0 / max(five["paper_mix_pairs"], 1)), "—"])
        machine = f"{platform.machine()}, {os.cpu_count()} CPUs, Python {platform.python_version()}"
        parts = [
            f"<p>{len(records)} stored pairs of run {self.run_id} ({_esc(_counts_text(counts))}), chosen as the paper's: up to 40 "
            "FP/DP pairs and 60 UrP/UcP pairs; classification times are medians of "
            f"{TIMING_REPEATS} repeats measured while this report was written ({_esc(machine)}), with the paths "
            "in memory; training time is not included. Scaled to 100 pairs when the run has fewer.</p>",
            _table(["method", "processing time, 100 pairs (ours)", "paper"], rows, "Table 7: processing time"),
            self.csv("table7_processing_time.csv", ["method", "pairs", "seconds_measured", "seconds_per_100",
                                                    "paper_seconds"], [
                ["hybrid_svm", len(records), hybrid_s, None if hybrid_s is None else hybrid_s * scale,
                 PAPER_PROCESSING_S["training"]],
                ["rule", len(records), rule_s, rule_s * scale, None],
                ["database_read", len(records), read_s, read_s * scale, None],
                ["manual", None, None, None, PAPER_PROCESSING_S["manual"]],
            ]),
        ]
        if hybrid_note and hybrid_s is not None:
            parts.append(f"<p>{_esc(hybrid_note)}</p>")
        return "\n".join(parts)

    def timing_pairs(self) -> np.ndarray:
        from vinadv.store.schema import map_pairs

        with self.store.engine.connect() as conn:
            rows = conn.execute(sa.select(map_pairs.c.pair_index, map_pairs.c.label)
                                .where(map_pairs.c.run_id == self.run_id)).all()
        index = np.array([r[0] for r in rows], dtype=np.int64)
        labels = np.array([r[1] for r in rows], dtype=object)
        rng = np.random.default_rng(0)
        fd = rng.permutation(index[np.isin(labels, ("FP", "DP"))])
        other = rng.permutation(index[np.isin(labels, ("UrP", "UcP"))])
        n_fd = min(40, len(fd))
        n_other = min(100 - n_fd, len(other))
        n_fd = min(100 - n_other, len(fd))
        chosen = np.concatenate([fd[:n_fd], other[:n_other]])
        if len(chosen) == 0:
            chosen = index[:100]
        return np.sort(chosen)

    def hybrid_timing(self, batch) -> tuple[float | None, str]:
        """Seconds for the hybrid + SVM to label `batch`, when an SVM (or hybrid) evaluation is stored: the SVM is
        trained again on that evaluation's training split (same seed and setting)."""
        from vinadv.classify import HybridClassifier, balance_batch, make_fp_classifier
        from vinadv.report.evaluate import load_run_pairs, split_fp_dp

        rows = [r for r in getattr(self, "evaluation", []) if r["classifier"] in ("svm", "hybrid")
                and r["training"] == "balanced" and r["train_fraction"] >= 1.0]
        if not rows:
            return None, "not evaluated (run vinadv evaluate with svm or hybrid)"
        row = rows[0]
        seed = int(row["seed"] or 0)
        data = load_run_pairs(self.store, self.run_id, seed)
        try:
            train, _ = split_fp_dp(data.truth, seed, source=f"run {self.run_id}")
        except InputError as exc:
            return None, str(exc)
        train_batch, labels = balance_batch(data.batch.subset(train), data.truth[train], seed=seed)
        model = HybridClassifier(make_fp_classifier("svm", row["setting"], seed), t=data.t)
        model.fit(train_batch, labels)
        seconds = median_seconds(lambda: model.predict(batch))
        return seconds, (f"Hybrid + SVM ({row['setting']}) trained again for this measurement on the stored "
                         f"evaluation's training split ({len(labels)} pairs, seed {seed}).")

    # ------------------------------------------------------------------------------------------- files
    def section_files(self) -> str:
        items = "".join(f'<li><a href="{_esc(n)}">{_esc(n)}</a></li>' for n in sorted(set(self.result.files)))
        return f"<p>Everything this page shows, as files in the same folder:</p><ul>{items}</ul>"


def _counts_text(counts) -> str:
    return ", ".join(f"{k} {v:,}" for k, v in sorted((counts or {}).items())) or "—"


def _find_metrics(data) -> dict | None:
    """A dict holding `success_rate` and `optimal_rate` inside a metrics/record JSON (top level or nested)."""
    if isinstance(data, dict):
        if "success_rate" in data and "optimal_rate" in data:
            return data
        for value in data.values():
            found = _find_metrics(value)
            if found:
                return found
    elif isinstance(data, list):
        for value in reversed(data):  # the last epoch / latest evaluation first
            found = _find_metrics(value)
            if found:
                return found
    return None
