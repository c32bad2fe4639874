"""`--planner` on attack, run and identify (transfer), `vinadv eval` in both conventions, and what runs record."""

import json
import shutil

import numpy as np
import pytest

from tests.cli_files import command_line, generated_maps_file
from tests.evaluation.test_protocols import brute_gppn_figures
from vinadv.attacks.pairs import PairSet
from vinadv.cli import main
from vinadv.evaluation import evaluate_planner_quality
from vinadv.grid.mapset import MapSet
from vinadv.identify import replan
from vinadv.pipeline import PLANNER_SPEC
from vinadv.planners.classical.optimal import OptimalPlanner
from vinadv.planners.vin.weights import save_vin
from vinadv.planners.weights import weights_checksum
from vinadv.report.build import report_context
from vinadv.report.render import render_page
from vinadv.report.sections import gather_report
from vinadv.store import Store
from vinadv.testing.planners import planning_vin
from vinadv.viewer.app import create_app

SIZE = 10


@pytest.fixture(scope="module")
def weights(planning_weights):
    return planning_weights(SIZE)


@pytest.fixture(scope="module")
def maps_file(tmp_path_factory):
    return generated_maps_file(tmp_path_factory.mktemp("m"), 25, SIZE, seed=6)


def test_attack_on_the_optimal_planner_is_never_harmful(maps_file, tmp_path, capsys):
    out = tmp_path / "p.npz"
    assert (
        main([*command_line("attack", maps=maps_file, strategy="exhaustive", planner="optimal", out=out), "--json"])
        == 0
    )
    summary = json.loads(capsys.readouterr().out)
    assert summary["planner"]["name"] == "optimal" and summary["pairs"] > 0
    assert summary["harm_counts"]["harmful"] == 0
    pairs = PairSet.load(out)
    assert pairs.params["planner"]["name"] == "optimal"
    again = OptimalPlanner(SIZE).plan(pairs.obstacles_a, pairs.starts, pairs.goals)
    assert again.paths == pairs.path_a


def test_identify_with_another_planner_replans_and_records_both(weights, maps_file, tmp_path, capsys):
    pairs_file = tmp_path / "p.npz"
    attack = command_line("attack", maps=maps_file, strategy="key-points", weights=weights, out=pairs_file)
    assert main([*attack, "--quiet"]) == 0
    capsys.readouterr()  # the attack's summary
    db = str(tmp_path / "t.db")
    assert main(["identify", "--pairs", str(pairs_file), "--db", db, "--planner", "optimal", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["harm_counts"]["harmful"] == 0  # the attacks found on the VIN, tried on a perfect planner
    with Store.open(db, readonly=True) as store:
        info = store.run_info(summary["run_id"])
        stored = store.read_pairs(summary["run_id"])
    assert info["config"]["planner"] == "optimal"
    assert info["config"]["attack_planner"]["name"] == "vin"
    assert info["config"]["attack_planner"]["weights_sha256"] == weights_checksum(weights)
    expected = replan(PairSet.load(pairs_file), OptimalPlanner(SIZE))
    assert stored.path_a == expected.path_a and stored.path_o == expected.path_o


def test_run_records_the_planner_and_resume_refuses_another(weights, tmp_path, capsys):
    db = str(tmp_path / "r.db")
    common = ["run", "--n", "20", "--size", str(SIZE), "--shard-size", "10", "--db", db, "--name", "k", "--quiet"]
    assert main([*common, "--planner", "optimal"]) == 0
    with Store.open(db, readonly=True) as store:
        info = store.run_info(store.find_run("k"))
    assert info["config"]["planner"] == "optimal"
    assert info["config"][PLANNER_SPEC] == OptimalPlanner(SIZE).spec()
    capsys.readouterr()
    before = open(db, "rb").read()
    # the VIN: another planner (--weights alone would be the stored planner's, and optimal takes no weights file)
    assert main([*common, "--resume", "--planner", "vin", "--weights", weights]) == 2
    err = capsys.readouterr().err
    assert "--resume" in err and "planner" in err and "Traceback" not in err
    assert open(db, "rb").read() == before


def test_resume_refuses_the_same_planner_with_other_weights(weights, tmp_path, capsys):
    mine = tmp_path / "w.pt"
    shutil.copy(weights, mine)
    db = str(tmp_path / "r.db")
    common = [*command_line("run", n=20, size=SIZE, shard_size=10, db=db, name="k", weights=mine), "--quiet"]
    assert main(common) == 0
    save_vin(planning_vin(SIZE, seed=3, noise=0.1), mine)  # the same file name, other weights
    capsys.readouterr()
    assert main([*common, "--resume"]) == 2
    assert "weights sha256" in capsys.readouterr().err


def test_eval_gives_both_conventions(maps_file, tmp_path, capsys):
    assert main(["eval", "--planner", "optimal", "--data", maps_file, "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["planner"]["name"] == "optimal"
    assert figures["vinadv"]["success_rate"] == 1.0 and figures["vinadv"]["optimal_rate"] == 1.0
    maps = MapSet.load(maps_file)
    actions = np.argmax(OptimalPlanner(SIZE).logits(maps.obstacles, maps.goals), axis=1)
    suc, opt = brute_gppn_figures(maps, actions)
    assert figures["gppn"]["percent_success"] == pytest.approx(suc)
    assert figures["gppn"]["percent_optimal"] == pytest.approx(opt)
    # by optimal moves: every start of the file in its bucket (the expert path's cells - 1 moves)
    moves = np.array([len(maps.expert[i]) - 1 for i in range(len(maps.expert))])
    rows = figures["vinadv"]["by_length"]
    assert [r["rollouts"] for r in rows] == [
        int(((moves >= lo) & (moves <= hi)).sum()) for lo, hi in (r["moves"] for r in rows)
    ]
    assert sum(r["rollouts"] for r in rows) == len(moves) and all(r["success_rate"] == 1.0 for r in rows)
    assert main(["eval", "--planner", "optimal", "--data", maps_file]) == 0
    assert f"by optimal moves  {rows[0]['moves'][0]}-{rows[0]['moves'][1]}: 100.00% of" in capsys.readouterr().out


def test_bad_planner_exits_2(maps_file, tmp_path, capsys):
    for argv in (
        ["attack", "--maps", maps_file, "--strategy", "random", "--out", str(tmp_path / "p.npz")],
        ["run", "--n", "5", "--size", str(SIZE), "--db", str(tmp_path / "x.db")],
        ["eval", "--data", maps_file],
    ):
        assert main([*argv, "--planner", "nonesuch", "--quiet"]) == 2
        assert "unknown planner 'nonesuch'" in capsys.readouterr().err
    assert main(["eval", "--data", maps_file, "--planner", "optimal", "--weights", "w.pt"]) == 2
    assert "takes no weights" in capsys.readouterr().err


@pytest.mark.slow
def test_report_and_viewer_show_the_runs_planner(tmp_path):
    db = str(tmp_path / "r.db")
    run = command_line("run", n=20, size=SIZE, shard_size=10, db=db, planner="optimal", attack="key-points")
    assert main([*run, "--quiet"]) == 0
    with Store.open(db) as store:  # the evaluation stage's planner quality, which the report shows
        evaluate_planner_quality(store, store.list_runs()[-1]["id"])
    with Store.open(db, readonly=True) as store:  # the sections that show the planner (the figures: tests/report)
        data = gather_report(report_context(store, tmp_path, None, None), order=["run", "planner"])
    html = render_page(data)
    assert "<td>planner</td><td>optimal</td>" in html
    assert "planner &#39;optimal&#39;, " in html and "on the first 20 distinct maps" in html  # its quality, on its maps
    with Store.open(db, readonly=True) as store:
        runs = create_app(store).test_client().get("/api/runs").get_json()["runs"]
    assert [r["planner"] for r in runs] == ["optimal"]
