"""`--edit remove` on `vinadv attack`, `run` and `robustness` (DESIGN.md "Obstacle removal"): the pairs made free
obstacle cells (checked against the maps), the optimal control is never harmed, and the store, the report's run
section and the viewer say so."""

from __future__ import annotations

import json

import pytest

from vinadv.attacks.pairs import PairSet
from vinadv.attacks.validity import removable_cells
from vinadv.cli import main
from vinadv.grid.mapset import MapSet
from vinadv.report.sections.run import run_edit
from vinadv.store import Store
from vinadv.viewer.app import create_app


@pytest.fixture(scope="module")
def maps_file(tmp_path_factory):
    out = tmp_path_factory.mktemp("edit") / "maps.npz"
    assert main(["maps", "generate", "--n", "6", "--size", "10", "--seed", "2", "--out", str(out), "--quiet"]) == 0
    return out


def test_attack_removes(maps_file, tmp_path, capsys):
    out = tmp_path / "pairs.npz"
    argv = ["attack", "--maps", str(maps_file), "--strategy", "exhaustive", "--per-map", "0", "--planner", "optimal"]
    assert main([*argv, "--edit", "remove", "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    pairs, maps = PairSet.load(out), MapSet.load(maps_file)
    # every removable cell of every map, once, each freed
    assert len(pairs) == removable_cells(maps.obstacles, maps.starts[:, 0], maps.goals).sum() > 0
    assert set(pairs.edit) == {"remove"} and summary["edit"] == "remove" and summary["params"]["edit"] == "remove"
    assert summary["harm_counts"]["harmful"] == 0  # a freed cell never harms the optimal planner
    assert (pairs.obstacles_a.sum(axis=(1, 2)) == pairs.obstacles_o.sum(axis=(1, 2)) - 1).all()


def test_run_stores_the_edit_and_the_report_and_viewer_show_it(tmp_path):
    db = f"sqlite:///{tmp_path / 'r.db'}"
    argv = ["run", "--n", "4", "--size", "8", "--shard-size", "2", "--planner", "optimal", "--attack", "random"]
    assert main([*argv, "--edit", "remove", "--db", db, "--name", "rm", "--quiet"]) == 0
    assert main([*argv, "--db", db, "--name", "add", "--quiet"]) == 0
    with Store.open(db, readonly=True) as store:
        removed, added = store.resolve_run("rm"), store.resolve_run("add")
        assert set(store.read_pairs(removed).edit) == {"remove"} and set(store.read_pairs(added).edit) == {"add"}
        assert run_edit(store.run_info(removed)["config"]) == "remove"
        config = store.run_info(added)["config"]
        assert run_edit(config) == "add" and config["edit"] == "add"  # writers write every field
        app = create_app(store, secret_key="k")
        app.config["TESTING"] = True
        client = app.test_client()
        index = int(store.read_pairs(removed).pair_index[0])
        assert "removed obstacle" in client.get(f"/pairs/{removed}/{index}").get_data(as_text=True)
        index = int(store.read_pairs(added).pair_index[0])
        assert "added obstacle" in client.get(f"/pairs/{added}/{index}").get_data(as_text=True)


def test_robustness_removes(tmp_path, capsys):
    argv = ["robustness", "--planner", "optimal", "--n", "5", "--size", "10", "--max-obstacles", "2"]
    assert main([*argv, "--edit", "remove", "--strategies", "random,key-points", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["settings"]["edit"] == "remove"
    assert all(f["harmful"] == 0 and f["valid"] > 0 for f in out["overall"])
    assert main([*argv, "--strategies", "random", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["settings"]["edit"] == "add"


def test_edit_is_validated(maps_file, tmp_path, capsys):
    argv = ["attack", "--maps", str(maps_file), "--strategy", "random", "--out", str(tmp_path / "p.npz")]
    with pytest.raises(SystemExit) as exit_:
        main([*argv, "--edit", "swap"])
    assert exit_.value.code == 2
    assert "--edit" in capsys.readouterr().err and not (tmp_path / "p.npz").exists()
