"""A search planner (the shipped example, breadth-first search) through every command that takes `--planner`: plan,
attack, identify, run, robustness and eval, end to end on small maps; `--maps FILE` on run and robustness, and the
wrong files it refuses before anything is written."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tests.cli_files import command_line, generated_maps_file
from tests.planners.test_user_search import bfs_moves
from vinadv.attacks.pairs import PairSet
from vinadv.cli import main
from vinadv.grid import generate_maps
from vinadv.grid.mapset import MapSet
from vinadv.planners.pathset import PathSet
from vinadv.planners.registry import load_planner
from vinadv.store import Store

SPEC = f"{Path(__file__).resolve().parents[2] / 'examples' / 'my_search_planner.py'}:make"
SIZE = 8


@pytest.fixture(scope="module")
def maps_file(tmp_path_factory):
    return generated_maps_file(tmp_path_factory.mktemp("m"), 8, SIZE, seed=11, n_starts=2)


def cost(path) -> float:
    """A path's octile cost, by hand."""
    return sum(math.sqrt(2) if a[0] != b[0] and a[1] != b[1] else 1.0 for a, b in zip(path, path[1:]))


def run_json(capsys, argv) -> dict:
    capsys.readouterr()
    assert main([*argv, "--json"]) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


def test_plan_writes_the_search_planner_s_fewest_move_paths(maps_file, tmp_path, capsys):
    out = tmp_path / "p.npz"
    summary = run_json(capsys, ["plan", "--maps", maps_file, "--out", str(out), "--planner", SPEC])
    assert summary["planner"]["name"] == SPEC and summary["paths"] == 16
    paths, maps = PathSet.load(out), MapSet.load(maps_file)
    for row in range(16):
        m, s = divmod(row, 2)
        fewest, _ = bfs_moves(maps.obstacles[m].tolist(), maps.starts[m, s], maps.goals[m])
        assert len(paths.paths[row]) - 1 == fewest


def test_eval_gives_a_search_planner_its_path_figures(maps_file, capsys):
    figures = run_json(capsys, ["eval", "--planner", SPEC, "--data", maps_file])
    assert set(figures) >= {"planner", "vinadv", "search"} and "gppn" not in figures  # no policy: no gppn protocol
    ours = figures["vinadv"]
    maps = MapSet.load(maps_file)
    # oracle: plain-Python costs of the planner's own paths against the expert costs
    result = load_planner(SPEC, SIZE).plan(maps.obstacles, maps.starts, maps.goals)
    costs = np.array([cost(result.paths[i].tolist()) for i in range(16)])
    expert = maps.expert_costs.reshape(-1)
    assert ours["success_rate"] == 1.0 and ours["action_accuracy"] is None and ours["action_cells"] == 0
    assert ours["optimal_rate"] == pytest.approx(np.mean(np.abs(costs - expert) < 1e-9))
    found = figures["search"]  # the search protocol: the same paths' cost ratio, and the cells expanded
    assert found["success"] == 1.0 and found["rows"] == 16
    assert found["cost_ratio"] == pytest.approx(np.mean(np.where(expert > 0, costs / np.maximum(expert, 1e-12), 1)))
    assert found["expansions"] == pytest.approx(result.expansions.mean())
    capsys.readouterr()
    assert main(["eval", "--planner", SPEC, "--data", maps_file, "--quiet"]) == 0
    text = capsys.readouterr()
    assert text.err == "" and "search: Opt" in text.out  # --quiet: the result, no progress bar
    for protocol in ("gppn", "kentsommer", "all"):
        assert main(["eval", "--planner", SPEC, "--data", maps_file, "--protocol", protocol]) == 2
        assert "needs a policy planner" in capsys.readouterr().err


def test_eval_protocol_option_is_checked_before_the_maps_are_read(tmp_path, capsys):
    missing = str(tmp_path / "none.npz")
    for bad, message in (
        ("vinadv,nope", "protocol 'nope': choose from vinadv, gppn, kentsommer, search or all"),
        ("gppn,gppn", "a protocol named twice"),
    ):
        assert main(["eval", "--data", missing, "--protocol", bad]) == 2
        assert message in capsys.readouterr().err
    assert main(["eval", "--data", missing, "--prior", "0"]) == 2
    assert "--prior applies to --protocol kentsommer only" in capsys.readouterr().err


def test_eval_kentsommer_protocol_takes_a_vin_only(maps_file, capsys):
    assert main(["eval", "--planner", "optimal", "--data", maps_file, "--protocol", "kentsommer"]) == 2
    assert "the kentsommer protocol measures a VIN" in capsys.readouterr().err


@pytest.mark.slow  # over a second on the 2-core machine
def test_attack_and_identify_on_a_search_planner(maps_file, tmp_path, capsys):
    pairs_file, db = tmp_path / "a.npz", str(tmp_path / "i.db")
    summary = run_json(
        capsys, ["attack", "--maps", maps_file, "--strategy", "saliency", "--planner", SPEC, "--out", str(pairs_file)]
    )
    assert summary["pairs"] > 0 and summary["ranked_as"] == "key-points"
    pairs = PairSet.load(pairs_file)
    assert pairs.params["planner"]["name"] == SPEC and pairs.params["ranked_as"] == "key-points"
    ident = run_json(capsys, ["identify", "--pairs", str(pairs_file), "--db", db, "--planner", SPEC])
    with Store.open(db) as store:
        stored = store.read_pairs(ident["run_id"])
        config = store.run_info(ident["run_id"])["config"]
    assert len(stored) == len(pairs) and config["planner"] == SPEC
    assert stored.path_a == pairs.path_a  # planned again by the same planner: the same paths


@pytest.mark.slow  # over a second on the 2-core machine
def test_run_on_a_search_planner_and_on_a_maps_file(maps_file, tmp_path, capsys):
    db = str(tmp_path / "r.db")
    generated = run_json(capsys, command_line("run", n=6, size=SIZE, db=db, planner=SPEC, attack="key-points"))
    assert generated["maps"] == 6 and generated["planner"]["name"] == SPEC
    from_file = run_json(
        capsys, command_line("run", maps=maps_file, n=5, shard_size=2, db=db, planner=SPEC, attack="random", name="f")
    )
    assert from_file["maps"] == 5
    maps = MapSet.load(maps_file)
    with Store.open(db) as store:
        info = store.run_info(from_file["run_id"])
        stored = store.read_pairs(from_file["run_id"])
    assert info["config"]["maps"] == str(Path(maps_file).resolve()) and len(info["config"]["maps_sha256"]) == 64
    assert info["config"]["size"] == SIZE and info["config"]["n"] == 5
    # the pairs are made on the file's maps, first start of each, in map order
    index = stored.pair_index  # per_map 1: the map's index in the file
    assert np.array_equal(stored.obstacles_o, maps.obstacles[index])
    assert np.array_equal(stored.starts, maps.starts[index, 0]) and np.array_equal(stored.goals, maps.goals[index])
    # resuming takes the same maps: fewer of them is other settings
    again = command_line("run", maps=maps_file, n=4, shard_size=2, db=db, planner=SPEC, attack="random", name="f")
    assert main([*again, "--resume", "--quiet"]) == 2
    assert "other settings (n)" in capsys.readouterr().err


def test_robustness_on_a_search_planner_from_a_maps_file(maps_file, capsys):
    out = run_json(
        capsys,
        command_line("robustness", maps=maps_file, planner=SPEC, max_obstacles=1, strategies="saliency,random"),
    )
    assert out["settings"]["maps"] == str(Path(maps_file).resolve()) and out["settings"]["n"] == 8
    strategies = out["strategies"]
    assert strategies["saliency"]["ranked_as"] == "key-points" and strategies["random"]["ranked_as"] is None
    assert out["clean"]["maps"] == 8 and out["clean"]["success_rate"] == 1.0


def _wrong_files(tmp_path, maps_file):
    pairs = tmp_path / "pairs.npz"
    moore = tmp_path / "moore.npz"
    generate_maps(2, SIZE, seed=1, n_starts=1, moves="moore").save(moore)
    broken = tmp_path / "broken.npz"
    broken.write_bytes(b"not a zip file")
    np.savez(pairs, format=np.array("vinadv.pairs/2"))
    return [
        ([str(tmp_path / "missing.npz")], "no such file"),
        ([str(broken)], "broken.npz"),
        ([str(pairs)], "pairs.npz"),
        ([str(moore)], "'moore' moves"),
        ([maps_file, "--n", "9"], "holds 8 maps"),
        ([maps_file, "--size", str(SIZE)], "--size: with --maps the maps file says it"),
    ]


@pytest.mark.parametrize("command", ["run", "robustness"])
def test_wrong_maps_files_are_refused_before_anything_is_written(command, maps_file, tmp_path, capsys):
    db, report = tmp_path / "out.db", tmp_path / "report"
    for args, message in _wrong_files(tmp_path, maps_file):
        line = [command, "--maps", *args, "--db", str(db), "--planner", SPEC, "--quiet"]
        if command == "robustness":
            line += ["--report", str(report)]
        assert main(line) == 2, args
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
        assert not db.exists() and not report.exists()


@pytest.mark.slow  # over a second on the 2-core machine
def test_the_built_in_search_planners_through_robustness_and_run(tmp_path, capsys):
    # exact A*: a perfect planner re-routes optimally, so no strategy ever finds a harmful pair
    out = run_json(
        capsys,
        command_line(
            "robustness", n=12, size=SIZE, planner="astar", max_obstacles=1, strategies="key-points,saliency,random"
        ),
    )
    assert out["planner"]["name"] == "astar" and out["clean"]["success_rate"] == 1.0
    assert all(s["by_obstacles"][0]["harmful_rate"] == 0.0 for s in out["strategies"].values())
    assert out["strategies"]["saliency"]["ranked_as"] == "key-points"
    db = str(tmp_path / "w.db")
    summary = run_json(capsys, command_line("run", n=6, size=SIZE, db=db, planner="wastar:w=2", attack="near-path"))
    with Store.open(db) as store:
        config = store.run_info(summary["run_id"])["config"]
    assert config["planner"] == "wastar:w=2" and config["planner_spec"]["config"] == {"w": 2.0}
