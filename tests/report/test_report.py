"""`vinadv report` and `vinadv evaluate`: every section and file, numbers against direct SQL, one-go `run --report`
(with its classifier comparison), the main run of `--runs`, runs labelled by a classifier."""

from __future__ import annotations

import csv
import json
import math
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest
import sqlalchemy as sa
from tests.cli_files import command_line
from tests.report.conftest import SIZE

from vinadv.cli import main
from vinadv.report.build import report_context
from vinadv.report.render import PAGE_SECTIONS, render_report
from vinadv.report.sections import gather_report
from vinadv.store import Store

pytestmark = pytest.mark.slow

FIGURES = ("fig1_map_pair", "fig2_path_pair", "fig3_categories", "fig5_map_pairs", "fig_table4_categories")
TABLES = ("run_config.csv", "planner_quality.csv", "table4_categories.csv", "table7_processing_time.csv", "style.css")
HARM_TABLES = ("harm_label_x_harm.csv", "harm_regret_changes.csv")  # written where the run has harm
EVAL_FIGURES = ("fig8_accuracy_vs_size", "fig9_roc_pr_baseline")
EVAL_TABLES = ("table5_training_time.csv", "table6_accuracy.csv", "classifier_metrics.csv", "fig8_accuracy_vs_size.csv")


class _Links(HTMLParser):
    def __init__(self):
        super().__init__()
        self.links, self.ids = [], []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag in ("img", "a", "link") and (attrs.get("src") or attrs.get("href")):
            self.links.append(attrs.get("src") or attrs.get("href"))
        if "id" in attrs:
            self.ids.append(attrs["id"])


def _parse(index: Path) -> _Links:
    parser = _Links()
    parser.feed(index.read_text(encoding="utf-8"))
    return parser


def _rows(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _sql(url: str, query: str, **params):
    with sa.create_engine(url).connect() as conn:
        return conn.execute(sa.text(query), params).all()


def _check_complete(out: Path, evaluated: bool, harm: bool = True, rendered: bool = True) -> str:
    """The page of the report in `out`: its sections in order, every link to a file there, every figure (PNG and SVG)
    and table written and linked; with `rendered`, the figures real PNG and SVG files (not from a test that takes
    `unrendered`, whose figure files are empty)."""
    index = out / "index.html"
    parsed = _parse(index)
    assert [sid for sid, _ in PAGE_SECTIONS] == [i for i in parsed.ids if i in dict(PAGE_SECTIONS)]
    for link in parsed.links:  # relative links only, every one to a file that exists
        if link.startswith("#") or link.startswith("data:"):
            continue
        assert "://" not in link and not link.startswith("/"), link
        assert (out / link).is_file(), f"missing {link}"
    figures = [f"{f}.{ext}" for f in FIGURES + EVAL_FIGURES * evaluated for ext in ("png", "svg")]
    tables = list(TABLES) + list(HARM_TABLES * harm) + list(EVAL_TABLES * evaluated)
    for name in figures + tables:
        assert (out / name).is_file(), name
        assert (out / name).stat().st_size > 0 or (name in figures and not rendered), f"{name} is empty"
        assert name in parsed.links, f"{name} not linked from the page"
    if rendered:
        assert (out / "fig3_categories.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (out / "fig3_categories.svg").read_text().lstrip().startswith("<?xml")
    return index.read_text(encoding="utf-8")


def test_report_of_two_runs_has_every_section_and_matches_the_database(base_report):
    url, (saliency, near_path), out = base_report
    page = _check_complete(out, evaluated=False)
    assert f"Run {saliency}: no classifier evaluation is stored" in page
    assert f"vinadv evaluate --db {url} --run {saliency}" in page
    # table 4 against direct counts, per run (one row per attack strategy)
    table4 = {row["run"]: row for row in _rows(out / "table4_categories.csv")}
    for run_id, attack in ((saliency, "saliency"), (near_path, "near-path")):
        counts = dict(_sql(url, "SELECT label, COUNT(*) FROM map_pairs WHERE run_id = :r GROUP BY label", r=run_id))
        row = table4[str(run_id)]
        assert row["attack"] == attack and row["labelled_by"] == "rule"
        for label in ("UrP", "FP", "DP", "UcP", "invalid"):
            assert int(row[label]) == counts.get(label, 0)
        assert int(row["pairs"]) == sum(counts.values())
        assert (
            int(row["successful"])
            == _sql(url, "SELECT COUNT(*) FROM map_pairs WHERE run_id = :r AND attack", r=run_id)[0][0]
        )
        total = sum(counts.values())
        assert f"{counts.get('DP', 0):,} ({100 * counts.get('DP', 0) / total:.1f}%)" in page
    # a VIN on 12x12 maps is not the paper's setting: none of the paper's numbers, and the page says why
    # (every paper number is marked `class="paper"`; the page's measured times may read "0.22 s" as table 7's does)
    assert "paper" not in table4 and "1,632" not in page and 'class="paper"' not in page
    assert "this run differs (12x12 maps, not 28x28)" in page
    # planner section: the run's original paths reaching the goal, against SQL
    reached = _sql(url, "SELECT COUNT(*) FROM map_pairs WHERE run_id = :r AND term_o = 'goal'", r=saliency)[0][0]
    total = _sql(url, "SELECT COUNT(*) FROM map_pairs WHERE run_id = :r", r=saliency)[0][0]
    vin = {row["figure"]: row["value"] for row in _rows(out / "planner_quality.csv")}
    assert (int(vin["run_original_paths_reaching_goal"]), int(vin["run_original_paths"])) == (reached, total)
    assert f"{reached:,} of {total:,}" in page
    assert re.search(r"success rate \(goal reached\)</td><td>\d+\.\d%", page)  # measured on the run's maps
    assert "action accuracy" in page and "action_accuracy" in vin  # the VIN has a policy
    assert "Opt (" not in page and not any(k.startswith("search_") for k in vin)  # and no expansions
    # table 7: the paper's mix (40 FP/DP + 60 UrP/UcP, as many as the run has), sized from SQL
    fd = _sql(url, "SELECT COUNT(*) FROM map_pairs WHERE run_id = :r AND label IN ('FP','DP')", r=saliency)[0][0]
    other = _sql(url, "SELECT COUNT(*) FROM map_pairs WHERE run_id = :r AND label IN ('UrP','UcP')", r=saliency)[0][0]
    n_other = min(100 - min(40, fd), other)
    expected_pairs = min(100 - n_other, fd) + n_other
    table7 = {row["method"]: row for row in _rows(out / "table7_processing_time.csv")}
    assert int(table7["rule"]["pairs"]) == expected_pairs and float(table7["rule"]["seconds_measured"]) > 0
    assert not any(m.startswith("hybrid") for m in table7)  # not evaluated: nothing to time
    assert "not evaluated (no stored hybrid evaluation)" in page
    assert "manual" not in table7 and "paper_seconds" not in next(iter(table7.values()))
    # run configuration from the runs table
    config = json.loads(_sql(url, "SELECT config FROM runs WHERE id = :r", r=saliency)[0][0])
    conf = {row["key"]: row["value"] for row in _rows(out / "run_config.csv")}
    assert conf["config.attack"] == "saliency" and int(conf["config.n"]) == config["n"] == 80


def test_evaluate_stores_rows_that_the_report_shows(evaluated):
    url, (saliency, _), out = evaluated
    rows = _sql(
        url,
        "SELECT classifier, training, train_fraction, train_size, test_size, metrics, curves "
        "FROM evaluations WHERE run_id = :r ORDER BY id",
        r=saliency,
    )
    jobs = sorted((r[0], r[1], r[2]) for r in rows)
    assert jobs == sorted(
        [
            ("svm", "balanced", 1.0),
            ("svm", "imbalanced", 1.0),
            ("svm", "balanced", 0.5),
            ("hausdorff", "balanced", 1.0),
            ("hausdorff", "imbalanced", 1.0),
            ("hausdorff", "balanced", 0.5),
            ("rule", "none", 1.0),
            ("hybrid", "balanced", 1.0),
            ("hybrid", "imbalanced", 1.0),
        ]
    )
    n_fp = _sql(url, "SELECT COUNT(*) FROM map_pairs WHERE run_id = :r AND label = 'FP'", r=saliency)[0][0]
    n_dp = _sql(url, "SELECT COUNT(*) FROM map_pairs WHERE run_id = :r AND label = 'DP'", r=saliency)[0][0]
    # 7:3 stratified: scikit-learn puts ceil(0.3 n) pairs in the test split, classes in proportion
    test_size = math.ceil(0.3 * (n_fp + n_dp))
    for classifier, training, fraction, train_size, size, metrics, curves in rows:
        metrics = json.loads(metrics) if isinstance(metrics, str) else metrics
        assert size == test_size
        cm = metrics["confusion_matrix"]
        assert sum(map(sum, cm)) == test_size
        assert metrics["accuracy"] == pytest.approx((cm[0][0] + cm[1][1]) / test_size)
        counts = metrics["train_counts"]
        if fraction == 1.0:
            assert counts["FP"] + counts["DP"] == n_fp + n_dp - test_size
            assert curves is not None
        if training == "balanced":  # augmentation: both classes as large as the larger one
            assert train_size == 2 * max(counts.values())
        elif training == "imbalanced":
            assert train_size == counts["FP"] + counts["DP"]
        if classifier == "rule":  # the rule is the truth, and trains on nothing
            assert train_size == 0
            assert metrics["accuracy"] == 1.0 and metrics["five_way"]["accuracy"] == 1.0
            assert metrics["roc_auc"] == 1.0
    page = _check_complete(out, evaluated=True)
    assert "No classifier evaluation" not in page
    stored = {(r[0], r[1]): json.loads(r[5]) if isinstance(r[5], str) else r[5] for r in rows if r[2] == 1.0}
    table6 = {(row["classifier"], row["setting"]): row for row in _rows(out / "table6_accuracy.csv")}
    svm = table6[("svm", "baseline")]
    assert float(svm["accuracy_balanced"]) == pytest.approx(stored[("svm", "balanced")]["accuracy"])
    assert float(svm["accuracy_imbalanced"]) == pytest.approx(stored[("svm", "imbalanced")]["accuracy"])
    assert "paper_accuracy" not in svm  # a 12x12 run: not the paper's setting
    table5 = {(row["classifier"], row["setting"]): row for row in _rows(out / "table5_training_time.csv")}
    assert "paper_s" not in table5[("svm", "baseline")]
    assert float(table5[("hausdorff", "baseline")]["training_s"]) == pytest.approx(
        stored[("hausdorff", "balanced")]["training_s"]
    )
    fig8 = _rows(out / "fig8_accuracy_vs_size.csv")
    assert sorted((r["classifier"], r["setting"], float(r["fraction"])) for r in fig8) == [
        ("hausdorff", "baseline", 0.5),
        ("hausdorff", "baseline", 1.0),
        ("svm", "baseline", 0.5),
        ("svm", "baseline", 1.0),
    ]
    table7 = {row["method"]: row for row in _rows(out / "table7_processing_time.csv")}
    # the hybrid's time for 100 pairs: the stored evaluation's measurement on the paper's mix
    five = stored[("hybrid", "balanced")]["five_way"]
    assert float(table7["hybrid_svm_baseline"]["seconds_measured"]) == pytest.approx(five["paper_mix_s"])
    assert int(table7["hybrid_svm_baseline"]["pairs"]) == five["paper_mix_pairs"]
    assert "paper_seconds" not in table7["hybrid_svm_baseline"]
    assert f"{stored[('svm', 'balanced')]['roc_auc']:.3f}" in page


def test_run_with_report_runs_the_comparison_in_both_settings(report_weights, tmp_path, capsys, unrendered):
    db = f"sqlite:///{tmp_path / 'one.db'}"
    out = tmp_path / "rep"
    run = command_line(
        "run", n=80, size=SIZE, attack="saliency", seed=4, shard_size=80, weights=report_weights, db=db, report=out
    )
    assert main([*run, "--json", "--quiet"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["report"] == str(out) and summary["comparison"] == "stored"
    page = _check_complete(out, evaluated=True, rendered=False)
    assert f"vinadv report: run {summary['run_id']}" in page
    assert {row["run"]: int(row["pairs"]) for row in _rows(out / "table4_categories.csv")}[
        str(summary["run_id"])
    ] == summary["pairs"]
    # every classifier in the paper's setting and ours, the networks with their epochs capped (the page says so)
    stored = _sql(db, "SELECT DISTINCT classifier, setting FROM evaluations WHERE run_id = :r", r=summary["run_id"])
    # (the distances and the rule have no setting: compared once)
    expected = {(k, "baseline") for k in ("svm", "cnn", "mlp", "hausdorff", "frechet", "dtw", "hybrid", "rule")}
    expected |= {(k, "tuned") for k in ("svm", "cnn", "mlp", "hybrid")}
    assert set(stored) == expected and len(stored) == len(expected)
    assert {(row["classifier"], row["setting"]) for row in _rows(out / "table6_accuracy.csv")} == expected
    for setting in ("baseline", "tuned"):
        assert (out / f"fig9_roc_pr_{setting}.png").is_file()
    epochs = {row["classifier"]: int(row["epochs"]) for row in _rows(out / "classifier_metrics.csv") if row["epochs"]}
    assert set(epochs) == {"cnn", "mlp"} and max(epochs.values()) < 10
    assert "fewer epochs than the paper" in page


def test_run_with_report_and_no_evaluate_skips_the_comparison(report_weights, tmp_path, capsys, unrendered):
    db = f"sqlite:///{tmp_path / 'two.db'}"
    out = tmp_path / "rep"
    run = command_line("run", n=30, size=SIZE, attack="key-points", weights=report_weights, db=db, report=out)
    assert main([*run, "--no-evaluate", "--json", "--quiet"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["comparison"] == "skipped"
    _check_complete(out, evaluated=False, rendered=False)
    assert _sql(db, "SELECT COUNT(*) FROM evaluations")[0][0] == 0
    assert main(["run", "--n", "30", "--size", str(SIZE), "--db", db, "--no-evaluate"]) == 2
    assert "--no-evaluate" in capsys.readouterr().err


def test_main_run_is_the_first_of_runs_and_each_runs_evaluation_is_shown(evaluated, tmp_path, unrendered):
    url, (saliency, near_path), _ = evaluated
    out = tmp_path / "cmp"
    assert main(["report", "--db", url, "--runs", f"{near_path},{saliency}", "--out", str(out), "--quiet"]) == 0
    page = _check_complete(out, evaluated=False, rendered=False)
    assert f"vinadv report: run {near_path} (near-path)" in page
    # the main run has no comparison; the other's stored one is shown, its files prefixed with its id
    prefix = f"run{saliency}_"
    links = _parse(out / "index.html").links
    for name in (
        "table5_training_time.csv",
        "table6_accuracy.csv",
        "classifier_metrics.csv",
        "fig9_roc_pr_baseline.png",
        "fig8_accuracy_vs_size.png",
    ):
        assert prefix + name in links and (out / (prefix + name)).is_file()
    assert not (out / "table6_accuracy.csv").exists()
    stored = _sql(
        url,
        "SELECT metrics FROM evaluations WHERE run_id = :r AND classifier = 'svm' AND training = "
        "'balanced' AND train_fraction = 1.0",
        r=saliency,
    )[0][0]
    stored = json.loads(stored) if isinstance(stored, str) else stored
    table6 = {(row["classifier"], row["setting"]): row for row in _rows(out / f"{prefix}table6_accuracy.csv")}
    assert float(table6[("svm", "baseline")]["accuracy_balanced"]) == pytest.approx(stored["accuracy"])
    assert f"Run {saliency}</h3>" in page and f"Run {near_path}:" in page
    # table 4: the main run first
    assert [row["run"] for row in _rows(out / "table4_categories.csv")] == [str(near_path), str(saliency)]
    # --run names the main run whatever the order of --runs
    out2 = tmp_path / "cmp2"
    assert (
        main(
            [
                "report",
                "--db",
                url,
                "--run",
                str(saliency),
                "--runs",
                f"{near_path},{saliency}",
                "--out",
                str(out2),
                "--quiet",
            ]
        )
        == 0
    )
    assert f"vinadv report: run {saliency} (saliency)" in (out2 / "index.html").read_text()
    assert (out2 / "table6_accuracy.csv").is_file()
    assert [row["run"] for row in _rows(out2 / "table4_categories.csv")] == [str(saliency), str(near_path)]


def test_a_run_labelled_by_a_classifier_is_marked_in_table4(db_copy, tmp_path):
    url, (saliency, near_path) = db_copy
    with Store.open(url) as store:
        records = store.read_pairs(saliency)
        records.label_source[:] = "svm-model"
        model_run = store.create_run("by-model", attack="saliency", classifier="svm-model")
        store.write_pairs(model_run, records)
    # table 4's section alone (the whole report's figures are the other tests'): gathered as `build_report` does
    out = tmp_path / "rep"
    out.mkdir()
    with Store.open(url, readonly=True) as store:
        data = gather_report(report_context(store, out, None, [saliency, model_run]), order=["distribution"])
    index = render_report(data, out)
    table4 = {row["run"]: row for row in _rows(out / "table4_categories.csv")}
    assert table4[str(saliency)]["labelled_by"] == "rule"
    assert table4[str(model_run)]["labelled_by"] == "svm-model"
    page = index.read_text()
    table = page[page.index("Table 4: the distribution") :]
    table = table[: table.index("</table>")]
    marked = {int(row.split(" ", 1)[0]) for row in table.split("<tr><td>")[2:] if "†" in row}
    assert marked == {model_run}
    assert "labelled by a trained classifier, not the exact rule" in page


def test_bad_input_exits_2_with_a_message(db_copy, tmp_path, capsys):
    url, (saliency, near_path) = db_copy
    assert main(["report", "--db", url, "--run", "99", "--out", str(tmp_path / "r")]) == 2
    assert "no run 99" in capsys.readouterr().err
    assert main(["report", "--db", url, "--runs", "1,x", "--out", str(tmp_path / "r")]) == 2
    assert "--runs" in capsys.readouterr().err
    assert main(["evaluate", "--db", url, "--run", str(saliency), "--classifiers", "svm,knn"]) == 2
    assert "knn" in capsys.readouterr().err
    assert main(["evaluate", "--db", url, "--run", str(saliency), "--sizes", "0,1"]) == 2
    assert "--sizes" in capsys.readouterr().err
    fp = _sql(url, "SELECT COUNT(*) FROM map_pairs WHERE run_id = :r AND label = 'FP'", r=near_path)[0][0]
    if fp < 2:  # the near-path run has too few forks to split
        assert main(["evaluate", "--db", url, "--run", str(near_path), "--classifiers", "rule", "--quiet"]) == 2
        assert "at least 2" in capsys.readouterr().err
    assert main(["report", "--db", str(tmp_path / "none.db"), "--out", str(tmp_path / "r")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert _sql(url, "SELECT COUNT(*) FROM evaluations")[0][0] == 0
