"""The runs list's harmful rate, the thumbnails, and the robustness and bench pages, against the records written, the
stored benchmarks and the entry files (plain-Python oracles; the intervals from `vinadv.intervals`)."""

from __future__ import annotations

import json
import re
import shutil
from io import BytesIO
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tests.test_analysis import figures
from tests.viewer.conftest import viewer_for_tests
from vinadv.intervals import rate_interval
from vinadv.plot.palette import PALETTE
from vinadv.plot.thumbnails import thumbnail_scale
from vinadv.store import Store
from vinadv.viewer.app import create_app
from vinadv.viewer.formats import fmt_pct_ci

BENCH = Path(__file__).resolve().parents[2] / "docs" / "results" / "bench"


def test_runs_list_has_each_runs_harmful_rate_with_its_interval(client, db):
    _, runs = db
    html = client.get("/").get_data(as_text=True)
    body = {r["name"]: r for r in client.get("/api/runs").get_json()["runs"]}
    for name, (_, records) in runs.items():
        harm = [h for h in records.harm.tolist()]
        harmful, harmless = harm.count("harmful"), harm.count("harmless")
        run = body[name]
        if harmful + harmless == 0:  # the crafted run stores no harm
            assert run["harmful_rate"] is None and run["harmful_rate_low"] is None
            continue
        low, high = rate_interval(harmful, harmful + harmless)
        assert run["harmful_rate"] == pytest.approx(harmful / (harmful + harmless))
        assert (run["harmful_rate_low"], run["harmful_rate_high"]) == (low, high)
        assert run["harm_counts"]["harmful"] == harmful
        assert fmt_pct_ci(run["harmful_rate"], low, high) in html


def test_grid_thumbnails_are_rendered_in_one_batch_and_cached(app, client, db):
    run_id, records = db[1]["random"]
    html = client.get(f"/runs/{run_id}/pairs?size=8").get_data(as_text=True)
    thumbs = re.findall(r'src="(/thumb/\d+/\d+\.png)"', html)
    assert thumbs == [f"/thumb/{run_id}/{i}.png" for i in records.pair_index[:8]]
    images = app.extensions["vinadv"].images
    misses = images.misses
    scale = thumbnail_scale(records.size)
    for i, url in enumerate(thumbs):
        response = client.get(url)
        assert response.status_code == 200 and response.mimetype == "image/png"
        image = np.asarray(Image.open(BytesIO(response.data)).convert("RGB"))
        assert image.shape == (records.size * scale, records.size * scale, 3)
        r, c = records.goals[i]  # drawn last: its block's inside is the goal's colour whatever lies there
        assert (image[r * scale + 1, c * scale + 1] == PALETTE.goal.rgb).all()
        assert client.get(url, headers={"If-None-Match": response.headers["ETag"]}).status_code == 304
    assert images.misses == misses  # every one was drawn with the page
    # a thumbnail asked for alone (not on a page) is drawn then; an unknown pair is a 404
    assert client.get(f"/thumb/{run_id}/{records.pair_index[-1]}.png").status_code == 200
    assert client.get(f"/thumb/{run_id}/999999.png").status_code == 404
    assert client.get(f"/thumb/{run_id}/1.png?x=1").status_code == 400


def test_robustness_page_lists_each_benchmark_by_k_with_intervals(tmp_path):
    settings = {"n": 10, "size": 8, "maps_seed": 1000, "objective": "harm", "strategies": ["random"]}
    result = {
        "clean": {"maps": 10, "reached": 9, "success_rate": 0.9, "mean_regret": 0.25},
        "strategies": {"random": {"name": "random", "seconds": 1.0, "by_obstacles": [figures(1, 9, 2)]}},
        "overall": [figures(1, 9, 2), figures(2, 9, 7)],
        "seconds": 1.0,
    }
    with Store.open(f"sqlite:///{tmp_path / 'r.db'}") as store:
        client = viewer_for_tests(store).test_client()
        assert "No robustness benchmarks" in client.get("/robustness").get_data(as_text=True)
        first = store.add_robustness("wastar", "ab" * 32, settings, result)
        second = store.add_robustness("optimal", None, {**settings, "edit": "remove"}, {**result, "overall": []})
        html = client.get("/robustness").get_data(as_text=True)
        body = client.get("/api/robustness").get_json()["benchmarks"]
    assert [b["id"] for b in body] == [first, second] and [b["planner"] for b in body] == ["wastar", "optimal"]
    assert [f["k"] for f in body[0]["worst"]] == [1, 2]
    for harmful, broken in ((2, 1), (7, 3)):
        low, high = rate_interval(harmful, 9)
        assert fmt_pct_ci(harmful / 9, low, high) in html
        low, high = rate_interval(broken, 9)
        assert fmt_pct_ci(broken / 9, low, high) in html
    assert fmt_pct_ci(0.9, *rate_interval(9, 10)) in html
    assert html.count(f'class="benchmark-{first}"') == 2 and "no figures stored" in html
    assert '<td rowspan="2">abababababab</td>' in html


def test_bench_page_shows_the_leaderboard_of_the_folder(tmp_path, store):
    folder = tmp_path / "bench"
    folder.mkdir()
    names = ["vin28-quick-v1.vin.json", "vin28-quick-v1.optimal.json", "vin28-quick-v1.gppn.json"]
    for name in names:
        shutil.copy(BENCH / name, folder / name)
    (folder / "broken.json").write_text("{not json", encoding="utf-8")
    client = viewer_for_tests(store).test_client()
    assert client.get("/bench").status_code == 404  # no --bench
    assert "nav-bench" not in client.get("/").get_data(as_text=True)
    app = create_app(store, secret_key="k", bench_dir=folder)
    app.config["TESTING"] = True
    client = app.test_client()
    html = client.get("/bench").get_data(as_text=True)
    assert "nav-bench" in client.get("/").get_data(as_text=True)
    entries = [json.loads((folder / n).read_text(encoding="utf-8")) for n in names]
    # the most robust first: by the worst-case harmful rate at one cell
    order = sorted(entries, key=lambda e: e["worst_case"][0]["harmful_rate"])
    shown = re.findall(r'<td class="planner">([^<]+)</td>', html)
    assert shown == [e["planner"]["name"].replace("_", "-") for e in order]
    for e in entries:
        w = e["worst_case"][0]
        assert fmt_pct_ci(w["harmful_rate"], *rate_interval(w["harmful"], w["valid"])) in html
    assert "broken.json" in html  # the bad file named, the others shown
    suites = client.get("/api/bench").get_json()["suites"]
    assert [r["file"] for rows in suites.values() for r in rows] == [
        n for e in order for n in names if json.loads((folder / n).read_text(encoding="utf-8")) == e
    ]
