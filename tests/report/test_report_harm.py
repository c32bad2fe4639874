"""The report's harm section: the label x harm table, the regret changes and their histogram against plain-Python
counts of the stored rows; the examples are really harmless FP / harmful DP pairs (the first by pair index), their
expert paths and costs as a plain-Python Dijkstra finds them; a run stored without harm, and a version-1
database, still get a report whose harm section says harm is not available."""

from __future__ import annotations

import csv
import hashlib
import math
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import sqlalchemy as sa
from tests.classify.test_harm import optimal_path, path_cost
from tests.report.formats import figures_not_rendered
from tests.report.test_report import _check_complete
from tests.store.oracle import parse_map, parse_path
from tests.store.test_store_harm import HARM_COLUMNS, HARM_INDEX

from vinadv.pipeline import RunConfig, run_pipeline
from vinadv.report import write_report
from vinadv.report.build import report_context
from vinadv.report.render import render_report
from vinadv.report.sections import gather_report
from vinadv.report.sections.harm import HARM_EXAMPLES_SHOWN
from vinadv.store import Store

pytestmark = pytest.mark.slow

TOL = 1e-6  # the runs' harm tolerance (the default)
HARMS = ("harmful", "harmless", "invalid")
FILES = (
    "harm_label_x_harm.csv",
    "harm_regret_changes.csv",
    "harm_regret_histogram.csv",
    "fig_harm_regret.png",
    "fig_harm_harmless_FP.png",
    "fig_harm_harmful_DP.png",
)


def _sql(url: str, query: str, **params) -> list:
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        result = conn.execute(sa.text(query), params)
        rows = result.all() if result.returns_rows else []
    engine.dispose()
    return rows


def _csv(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _harm_only(url: str, run_id: int, out: Path):
    """The harm section alone, gathered and rendered into `out` (the whole report: the last two tests)."""
    out.mkdir(parents=True, exist_ok=True)
    with Store.open(url, readonly=True) as store:
        data = gather_report(report_context(store, out, run_id, None), order=["harm"])
    render_report(data, out)
    return data.sections["harm"]


def _section(page: str) -> str:
    return page.split('<section id="harm">', 1)[1].split("</section>", 1)[0]


@pytest.fixture(scope="module")
def saliency_harm(base_db, tmp_path_factory):
    """The harm section of the base database's saliency run, gathered and rendered once for the two tests that
    read it (the report only reads the database): (URL, run id, report folder, the section's data)."""
    path, (saliency, _) = base_db
    url = f"sqlite:///{path}"
    out = tmp_path_factory.mktemp("harm")
    with figures_not_rendered():  # the files written and linked; their pixels are the report tests' of the figures
        return url, saliency, out, _harm_only(url, saliency, out)


def test_label_x_harm_and_regret_changes_match_the_stored_rows(saliency_harm):
    url, saliency, out, _ = saliency_harm
    rows = _sql(url, "SELECT label, harm, regret_o, regret_a FROM map_pairs WHERE run_id = :r", r=saliency)
    counts = Counter((label, harm) for label, harm, _, _ in rows)
    page = _section((out / "index.html").read_text())
    for name in FILES:
        assert (out / name).is_file() and f'="{name}"' in page, name
    table = {row["label"]: row for row in _csv(out / "harm_label_x_harm.csv")}
    assert set(table) == {"UrP", "FP", "DP", "UcP", "invalid"}
    for label, row in table.items():
        total = sum(counts[(label, h)] for h in HARMS)
        assert [int(row[h]) for h in HARMS] == [counts[(label, h)] for h in HARMS]
        assert int(row["pairs"]) == total
        cells = "".join(
            f"<td>{counts[(label, h)]:,} ({100 * counts[(label, h)] / total:.1f}%)</td>"
            if total
            else f"<td>{counts[(label, h)]:,} (—)</td>"
            for h in HARMS
        )
        assert f"<tr><td>{label}</td>{cells}<td>{total:,}</td></tr>" in page
    assert counts[("FP", "harmless")] and counts[("DP", "harmful")]  # the run has both kinds of example
    valid = sum(n for (_, harm), n in counts.items() if harm != "invalid")
    success = sum(n for (label, harm), n in counts.items() if label in ("UrP", "FP"))
    assert f"<strong>{100 * success / valid:.1f}%</strong>" in page
    assert f"<strong>{100 * sum(n for (_, h), n in counts.items() if h == 'harmful') / valid:.1f}%</strong>" in page
    # the regret changes of the FP and DP pairs, plain Python against the summary and every histogram bin
    changes = {row["label"]: row for row in _csv(out / "harm_regret_changes.csv")}
    bins = _csv(out / "harm_regret_histogram.csv")
    for label in ("FP", "DP"):
        mine = [(harm, ra - ro) for lab, harm, ro, ra in rows if lab == label and ro is not None and ra is not None]
        deltas = [d for _, d in mine]
        row = changes[label]
        assert int(row["pairs"]) == len(mine) == counts[(label, "harmful")] + counts[(label, "harmless")]
        assert int(row["harmful"]) == sum(h == "harmful" for h, _ in mine) == counts[(label, "harmful")]
        assert int(row["improved"]) == sum(d < -TOL for d in deltas)
        assert int(row["same"]) == sum(abs(d) <= TOL for d in deltas)
        assert int(row["added"]) == sum(d > TOL for d in deltas) == counts[(label, "harmful")]  # tol only: rtol 0
        assert math.isclose(float(row["mean_change"]), sum(deltas) / len(deltas), abs_tol=1e-6)
        assert math.isclose(float(row["largest_change"]), max(deltas), abs_tol=1e-6)
        mine_bins = [b for b in bins if b["label"] == label]
        assert any(float(b["change_above"]) == TOL for b in mine_bins)  # the tolerance is a bin edge
        for b in mine_bins:
            lo, hi = float(b["change_above"]), float(b["change_at_most"])
            for harm in ("harmful", "harmless"):
                assert int(b[harm]) == sum(h == harm and lo < d <= hi for h, d in mine), (label, lo, hi, harm)
        assert sum(int(b["harmful"]) + int(b["harmless"]) for b in mine_bins) == len(mine)


def test_examples_are_harmless_fp_and_harmful_dp_pairs_with_their_expert_paths(saliency_harm):
    url, saliency, out, data = saliency_harm
    assert list(data.examples) == ["harmless FP", "harmful DP"] and list(data.example_figures) == list(data.examples)
    for kind, shown in data.examples.items():
        harm, label = kind.split()
        first = _sql(
            url,
            "SELECT pair_index FROM map_pairs WHERE run_id = :r AND label = :l AND harm = :h ORDER BY pair_index",
            r=saliency,
            l=label,
            h=harm,
        )[:HARM_EXAMPLES_SHOWN]
        assert [e.pair_index for e in shown] == [p for (p,) in first] and shown
        for e in shown:
            map_o, map_a, path_o, path_a, start, goal, stored_label, stored_harm, opt_o, opt_a = _sql(
                url,
                "SELECT map_o, map_a, path_o, path_a, start, goal, label, harm, opt_cost_o, opt_cost_a "
                "FROM map_pairs WHERE run_id = :r AND pair_index = :p",
                r=saliency,
                p=e.pair_index,
            )[0]
            assert (stored_label, stored_harm) == (e.label, e.harm) == (label, harm)
            start, goal = (tuple(int(v) for v in cell.split(",")) for cell in (start, goal))
            expert_o = optimal_path(parse_map(map_o), start, goal, True)  # the runs cut corners (the default)
            expert_a = optimal_path(parse_map(map_a), start, goal, True)
            assert e.expert_path_o == tuple(expert_o) and e.expert_path_a == tuple(expert_a)
            for oracle, mine, stored in (
                (path_cost(expert_o), e.expert_cost_o, opt_o),
                (path_cost(expert_a), e.expert_cost_a, opt_a),
            ):
                assert math.isclose(oracle, mine, abs_tol=1e-9) and math.isclose(oracle, stored, abs_tol=1e-9)
            planner_o, planner_a = parse_path(path_o), parse_path(path_a)
            assert planner_o[-1] == planner_a[-1] == goal  # FP and DP: both paths reach the goal
            regret_o = path_cost(planner_o) - path_cost(expert_o)
            regret_a = path_cost(planner_a) - path_cost(expert_a)
            assert math.isclose(regret_o, e.regret_o, abs_tol=1e-9) and math.isclose(regret_a, e.regret_a, abs_tol=1e-9)
            assert (regret_a > regret_o + TOL) == (harm == "harmful")
    page = _section((out / "index.html").read_text())
    for kind, shown in data.examples.items():
        harm, label = kind.split()
        for e in shown:
            assert f"<li>pair {e.pair_index} ({label}, {harm}" in page


def _drop_harm(url: str, run_id: int, below: int | None = None) -> None:
    """Empty the harm columns of the run's pairs (those with a pair index below `below`, if given), as a vinadv
    from before harm left them."""
    where = "" if below is None else f" AND pair_index < {int(below)}"
    _sql(
        url, f"UPDATE map_pairs SET {', '.join(f'{c} = NULL' for c in HARM_COLUMNS)} WHERE run_id = :r{where}", r=run_id
    )


def test_a_run_stored_without_harm_still_renders(db_copy, tmp_path, unrendered):
    url, (saliency, near_path) = db_copy
    _drop_harm(url, saliency)
    out = write_report(url, tmp_path / "old", run_id=saliency).parent
    page = _check_complete(out, evaluated=False, harm=False, rendered=False)
    harm = _section(page)
    assert 'id="harm-unavailable"' in harm and "Harm is not available for run" in harm
    assert "<table" not in harm and not any((out / name).exists() for name in FILES)
    # part of a run without harm (a run resumed by a newer vinadv): a column for them, rates over the others
    _drop_harm(url, near_path, below=30)
    out = tmp_path / "part"
    _harm_only(url, near_path, out)
    missing = _sql(
        url, "SELECT label, COUNT(*) FROM map_pairs WHERE run_id = :r AND harm IS NULL GROUP BY label", r=near_path
    )
    table = {row["label"]: row for row in _csv(out / "harm_label_x_harm.csv")}
    assert sum(n for _, n in missing) > 0
    for label, row in table.items():
        assert int(row["not computed"]) == dict(missing).get(label, 0)
    assert f"{sum(n for _, n in missing)} of the run's" in _section((out / "index.html").read_text())


def test_a_version_1_database_gets_a_report_and_stays_as_it_was(db_copy, tmp_path, unrendered):
    url, (saliency, _) = db_copy
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        HARM_INDEX.drop(conn)
        for name in HARM_COLUMNS:
            conn.execute(sa.text(f"ALTER TABLE map_pairs DROP COLUMN {name}"))
        conn.execute(sa.text("UPDATE vinadv_meta SET value = '1' WHERE key = 'schema_version'"))
    with engine.connect() as conn:
        conn.exec_driver_sql("PRAGMA wal_checkpoint(TRUNCATE)")
    engine.dispose()
    path = Path(url.removeprefix("sqlite:///"))
    wal = path.with_name(path.name + "-wal")
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    out = write_report(url, tmp_path / "v1", run_id=saliency).parent
    assert 'id="harm-unavailable"' in _section((out / "index.html").read_text())
    # opened read-only: the file as it was, nothing written ahead (SQLite may leave an empty log of a reader)
    assert hashlib.sha256(path.read_bytes()).hexdigest() == digest and (not wal.exists() or not wal.stat().st_size)


def test_a_moore_run_reports_its_model_and_recomputes_expert_paths_with_it(sqlite_url, tmp_path, unrendered):
    """The run table names the model; the harm examples' expert paths are the model's (a plain Dijkstra of
    `moore`, tests.classify.test_harm), their costs the stored optimal costs."""
    config = RunConfig(n=12, size=9, seed=3, shard_size=12, planner="optimal", attack="exhaustive", per_map=0)
    run_id = run_pipeline(RunConfig(**{**config.to_dict(), "moves": "moore"}), db=sqlite_url, progress=False).run_id
    out = tmp_path / "r"
    out.mkdir()
    with Store.open(sqlite_url, create=False) as store:
        data = gather_report(report_context(store, out, run_id, None), order=["run", "harm"])
    assert ("movement model", "moore") in data.sections["run"].rows
    shown = data.sections["harm"].examples["harmless FP"]
    assert shown  # the control forks onto other optimal routes: harmless forks to show
    for ex in shown:
        with Store.open(sqlite_url, create=False) as store:
            rec = store.read_pairs(run_id, pair_indices=np.array([ex.pair_index]))
        want = optimal_path(rec.obstacles_o[0].tolist(), tuple(rec.starts[0]), tuple(rec.goals[0]), True, "moore")
        assert list(ex.expert_path_o) == want and path_cost(want, "moore") == pytest.approx(ex.opt_cost_o)
