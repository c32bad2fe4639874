"""The report's robustness section: the stored benchmarks of the database as a table (the worst case at one obstacle,
the harmful rate by k, each rate with its Wilson interval), a CSV of every strategy and k read back against the
stored figures and their intervals, and the curves; a
database without benchmarks says how to make one."""

from __future__ import annotations

import csv
import math

import pytest
from tests.report.conftest import SIZE

from vinadv.intervals import rate_interval
from vinadv.planners.vin.weights import load_vin
from vinadv.report.build import report_context
from vinadv.report.render import render_report
from vinadv.report.sections import gather_report
from vinadv.robustness import heldout_maps, robustness, save_robustness
from vinadv.store import Store

pytestmark = pytest.mark.slow


def _benchmarks(url: str, weights: str) -> list[dict]:
    """Two benchmarks stored in `url` (the VIN with two settings); their `to_dict`s."""
    model = load_vin(weights, size=SIZE)
    made = []
    for strategies, k in ((["random", "key-points"], 2), (["near-path"], 3)):
        result = robustness(model, heldout_maps(15, SIZE, seed=3), strategies, max_obstacles=k)
        made.append({**result.to_dict(), "id": save_robustness(result, url)})
    return made


def test_robustness_section_shows_every_stored_benchmark(db_copy, report_weights, tmp_path):
    url, (run_id, _) = db_copy
    made = _benchmarks(url, report_weights)
    out = tmp_path / "rep"
    out.mkdir()
    # the robustness section alone, gathered as `build_report` does (the rest of the page is the other tests')
    with Store.open(url, readonly=True) as store:
        data = gather_report(report_context(store, out, run_id, None), order=["robustness"])
    page = render_report(data, out).read_text()
    section = page.split('<section id="robustness">', 1)[1].split("</section>", 1)[0]
    assert 'id="robustness-table"' in section and "fig_robustness.png" in section
    assert (out / "fig_robustness.png").exists() and (out / "fig_robustness.svg").exists()
    # the comparison table: one row per benchmark, its worst case at k = 1 and its harmful rate at every k
    table = section.split('id="robustness-table"', 1)[1].split("</table>", 1)[0]
    assert table.count("<tr><td><code>vin") == 2 and "harmful, k = 3" in table
    for d in made:
        one = d["overall"][0]
        low, high = rate_interval(one["harmful"], one["valid"])  # its Wilson 95% interval beside it
        assert (
            f'{100 * one["harmful_rate"]:.1f}% <span class="hint">[{100 * low:.1f}, {100 * high:.1f}]</span>' in table
        )
    with open(out / "robustness.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    expected = [
        (d["id"], name, f)
        for d in made
        for name, by_k in (*((n, s["by_obstacles"]) for n, s in d["strategies"].items()), ("worst case", d["overall"]))
        for f in by_k
    ]
    assert len(rows) == len(expected)
    for row, (bid, name, f) in zip(rows, expected):
        assert (int(row["benchmark"]), row["strategy"], int(row["k"])) == (bid, name, f["k"])
        assert int(row["valid"]) == f["valid"] and int(row["harmful"]) == f["harmful"]
        assert math.isclose(float(row["harmful_rate"]), f["harmful_rate"])
        for rate, count in (("harmful_rate", "harmful"), ("paper_success_rate", "broken")):
            low, high = rate_interval(f[count], f["valid"])
            assert math.isclose(float(row[f"{rate}_low"]), low) and math.isclose(float(row[f"{rate}_high"]), high)


def test_a_database_without_benchmarks_says_how_to_make_one(base_report):
    _, _, out = base_report
    page = (out / "index.html").read_text()
    section = page.split('<section id="robustness">', 1)[1].split("</section>", 1)[0]
    assert 'id="robustness-none"' in section and "vinadv robustness" in section
    assert not (out / "robustness.csv").exists()
