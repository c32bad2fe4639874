"""The report fits its run (issue 49): sections chosen by the planner's declared capabilities, quality measured on the
run's own maps, the paper's numbers only beside the paper's VIN, the run's seed, maps file and planner spec in the
header."""

from __future__ import annotations

import csv
import html
import json

import numpy as np
import pytest
from tests.needs import public_data
from tests.report.formats import figures_not_rendered
from tests.report.test_report_baseline import BASELINE

from vinadv.cli import main
from vinadv.grid.mapset import MapSet
from vinadv.pipeline import RunConfig, run_pipeline
from vinadv.planners.classical.astar import AStarPlanner
from vinadv.report import build_report
from vinadv.report.paper import papers_setting
from vinadv.report.sections.run import header_rows, maps_source, run_seed
from vinadv.store import Store
from vinadv.vocabulary import PLANNER_QUALITY


def _rows(path) -> dict[str, str]:
    with open(path, newline="") as fh:
        return {row["figure"]: row["value"] for row in csv.DictReader(fh)}


@pytest.mark.slow  # a run and a whole report (its figures drawn, not rendered: rendering was most of ~20 s)
def test_an_astar_run_on_mp_mazes_gets_a_report_of_its_own(tmp_path, capsys):
    """`vinadv run` of A* on six MP mazes, with `--report`: quality measured on those six maps (against A* planned on
    them here), expansion rows and no action accuracy, no VIN file, no paper numbers, the header complete."""
    maps = tmp_path / "mazes.npz"
    source = public_data("mpd/mazes_032_moore_c8.npz")
    assert main(["maps", "import", "--format", "mpd", str(source), "--out", str(maps), "--starts", "1", "--quiet"]) == 0
    db, out = tmp_path / "mp.db", tmp_path / "report"
    run = ["run", "--maps", str(maps), "--n", "6", "--planner", "astar", "--attack", "near-path", "--seed", "3"]
    with figures_not_rendered():  # what the page says and the tables hold, not the figures' pixels
        assert main([*run, "--db", str(db), "--name", "mp", "--report", str(out), "--no-evaluate", "--quiet"]) == 0
    page = (out / "index.html").read_text()
    quality = _rows(out / "planner_quality.csv")
    assert not (out / "vin_quality.csv").exists()
    # measured on the run's six maps: A* is exact there, and expands what A* expands
    file = MapSet.load(maps).take(slice(0, 6))
    assert (quality["maps"], quality["starts_per_map"]) == ("6", "1")
    assert float(quality["success_rate"]) == float(quality["optimal_rate"]) == 1.0
    astar = AStarPlanner(32, "moore").plan(file.obstacles, file.starts[:, :1], file.goals, True, "moore")
    assert float(quality["search_expansions"]) == np.mean(astar.expansions)
    assert float(quality["search_exp"]) == 0.0 and float(quality["search_opt"]) == 1.0
    assert "action_accuracy" not in quality and "action accuracy" not in page  # A* declares no policy
    assert "Opt (Neural A*'s" in page and "fig_planner_value_map.png" not in page  # expansions, no value maps
    with Store.open(f"sqlite:///{db}") as store:
        stored = store.read_measurement(store.resolve_run("mp"), PLANNER_QUALITY)
        recorded = store.run_info(store.resolve_run("mp"))["config"]["planner_spec"]
    assert stored["capabilities"] == {
        "policy": False,
        "value_maps": False,
        "gradients": False,
        "expansions": True,
        "start_values": False,
    }
    assert "6 distinct maps of run 1's" in stored["source"]
    # no paper numbers: not the paper's VIN, and the page says why
    assert "paper" not in {row["run"] for row in csv.DictReader(open(out / "table4_categories.csv"))}
    assert "1,632" not in page and "0.22 s" not in page and 'class="paper"' not in page
    assert "planner &#39;astar&#39;, not the paper&#39;s VIN; 32x32 maps, not 28x28; moore moves, not octile" in page
    # the header: planner spec, maps file and its SHA-256, seed
    text = html.unescape(page)
    assert recorded == {"config": {"moves": "moore"}, "name": "astar", "size": 32, "weights_sha256": None}
    assert f"<td>planner</td><td>{json.dumps(recorded, sort_keys=True)}</td>" in text
    config = {row[0]: row[1] for row in csv.reader(open(out / "run_config.csv"))}
    assert f"maps file {maps.resolve()} (its first 6 maps" in text
    assert f"<td>maps file SHA-256</td><td>{config['config.maps_sha256']}</td>" in text
    assert "<td>seed</td><td>3</td>" in text


@pytest.mark.slow  # a whole report, as above
def test_a_run_of_the_papers_vin_shows_the_papers_numbers(planning_weights, tmp_path):
    """A VIN on generated 28x28 octile maps is the paper's setting: table 4's and table 7's paper rows are there."""
    url = f"sqlite:///{tmp_path / 'p.db'}"
    config = RunConfig(n=4, size=28, attack="near-path", seed=2, shard_size=4, weights=planning_weights(28))
    run_id = run_pipeline(config, db=url, name="paper", progress=False).run_id
    with Store.open(url) as store:  # a stored comparison (the baseline's rows: nothing trained here)
        store.add_evaluations(run_id, json.loads((BASELINE / "evaluations.json").read_text(encoding="utf-8")))
    with figures_not_rendered():  # the paper's numbers on the page and in the tables, not the figures' pixels
        result = build_report(url, tmp_path / "rep", run_id=run_id)
    assert result.not_papers is None
    page = result.index.read_text()
    with open(tmp_path / "rep" / "table4_categories.csv", newline="") as fh:
        paper = next(r for r in csv.DictReader(fh) if r["run"] == "paper")
    assert [paper[k] for k in ("UrP", "FP", "DP", "UcP")] == ["1632", "204", "1076", "2088"]
    assert "1,632" in page and "300 s" in page and 'Numbers in <span class="paper">brown</span>' in page
    with open(tmp_path / "rep" / "table6_accuracy.csv", newline="") as fh:
        table6 = {(r["classifier"], r["setting"]): r for r in csv.DictReader(fh)}
    with open(tmp_path / "rep" / "table5_training_time.csv", newline="") as fh:
        table5 = {(r["classifier"], r["setting"]): r for r in csv.DictReader(fh)}
    assert (
        float(table6[("svm", "baseline")]["paper_accuracy"]) == 0.97
        and table6[("svm", "tuned")]["paper_accuracy"] == ""
    )
    assert float(table5[("svm", "baseline")]["paper_s"]) == 46.0
    assert "The paper's SVM: AP and AUC" in html.unescape(page)  # fig. 9's paper accuracies
    assert "generated by vinadv&#39;s generator: 4 maps of 28x28, seed 2" in page


def test_the_papers_setting_is_its_vin_on_28x28_octile_maps_with_one_obstacle_added():
    run = {"planner": "vin", "size": 28, "corner_cutting": True, "obstacles": 1, "edit": "add", "shard_size": 1}
    assert papers_setting({"config": run, "moves": "octile"}) is None
    assert papers_setting({"config": None, "moves": "octile"}) is None  # nothing recorded: read as the paper's
    assert papers_setting({"config": {**run, "planner": "vin-robust"}, "moves": "octile"}) == (
        "planner 'vin-robust', not the paper's VIN"
    )
    assert papers_setting({"config": {**run, "planner_spec": {"name": "vin+d4"}}, "moves": "octile"}) == (
        "planner 'vin+d4', not the paper's VIN"
    )
    differs = {**run, "size": 32, "corner_cutting": False, "obstacles": 2, "edit": "remove"}
    assert papers_setting({"config": differs, "moves": "moore"}) == (
        "32x32 maps, not 28x28; moore moves, not octile; no corner cutting; 2 obstacles per pair, not 1; "
        "obstacles removed, not added"
    )
    # a run of `vinadv identify`: the size from its planner's spec, the obstacles from the pairs' parameters
    identified = {"pairs": "p.npz", "planner_spec": {"name": "vin", "size": 16}, "params": {"obstacles": 3}}
    assert papers_setting({"config": identified, "moves": "octile"}) == (
        "16x16 maps, not 28x28; 3 obstacles per pair, not 1"
    )


def test_the_header_says_what_each_kind_of_run_stored():
    """`vinadv run` on a maps file or generated maps, and `vinadv identify` of a pairs file (its seed is the attack's,
    from the file's parameters; its maps file is not recorded)."""
    run = {"shard_size": 1, "attack": "random", "n": 5, "size": 12, "seed": 7, "maps": None, "maps_sha256": None}
    on_file = {**run, "maps": "/data/m.npz", "maps_sha256": "ab" * 32}
    identified = {"pairs": "p.npz", "strategy": "random", "params": {"seed": 9}, "planner_spec": {"name": "astar"}}
    assert maps_source({"config": on_file}) == ("maps file /data/m.npz (its first 5 maps, first start each)", "ab" * 32)
    assert maps_source({"config": run})[0].startswith("generated by vinadv's generator: 5 maps of 12x12, seed 7")
    assert maps_source({"config": identified}) == (
        "the maps of the pairs file p.npz (the maps file they came from is not recorded)",
        None,
    )
    assert run_seed({"seed": 7, "config": run}) == 7
    assert run_seed({"seed": None, "config": identified}) == "9 (the attack's, recorded in the pairs file)"
    assert run_seed({"seed": None, "config": None}) is None
    rows = dict(header_rows({"seed": None, "config": identified, "moves": "octile"}))
    assert rows["planner"] == '{"name": "astar"}' and rows["maps file SHA-256"] == "—"
