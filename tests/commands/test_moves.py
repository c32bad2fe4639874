"""Movement models through the commands: `optimal` plans and is attacked on `moore` and `news` maps (never harmful:
it is optimal under the maps' own costs), and the stages that do not follow other models yet refuse such maps with
one line naming the model (exit status 2), before any work, instead of computing with octile costs."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from vinadv.attacks.pairs import PairSet
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import MapSet, generate_maps
from vinadv.planners.evaluation import evaluate_planner
from vinadv.planners.pathset import PathSet
from vinadv.planners.registry import load_planner
from vinadv.planners.training import TrainConfig, train_vin
from vinadv.planners.vin.weights import save_vin
from vinadv.robustness import robustness
from vinadv.testing.planners import planning_vin


@pytest.fixture(scope="module", params=["moore", "news"])
def maps_file(request, tmp_path_factory):
    path = tmp_path_factory.mktemp("moves") / f"{request.param}.npz"
    generate_maps(4, 8, seed=1, n_starts=2, moves=request.param).save(path)
    return request.param, path


@pytest.mark.parametrize(
    "argv, message",
    [
        (["plan", "--maps", "{maps}", "--weights", "{weights}", "--out", "{out}"], "planner 'vin' plans octile moves"),
        (
            ["attack", "--maps", "{maps}", "--strategy", "random", "--weights", "{weights}", "--out", "{out}"],
            "planner 'vin' plans octile moves",
        ),
        (["eval", "--data", "{maps}", "--planner", "optimal"], "planner evaluation follows 'octile'"),
        (["vin", "eval", "--data", "{maps}", "--weights", "{weights}"], "the vinadv protocol follows 'octile'"),
        (["vin", "train", "--data", "{maps}", "--out", "{out}", "--epochs", "1"], "training follows 'octile'"),
    ],
    ids=["plan", "attack", "eval", "vin-eval", "vin-train"],
)
def test_commands_refuse_other_movement_models(maps_file, argv, message, tmp_path, capsys):
    moves, path = maps_file
    weights = tmp_path / "w.pt"
    if "{weights}" in argv:
        save_vin(planning_vin(8), weights)
    out = tmp_path / "out.npz"
    args = [a.format(maps=path, out=out, weights=weights) for a in argv]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err and f"'{moves}' moves" in err, err
    assert not out.exists()


def test_library_refuses_too(maps_file):
    moves, path = maps_file
    maps = MapSet.load(path)
    with pytest.raises(InputError, match=f"the maps use '{moves}' moves: planner evaluation follows 'octile'"):
        evaluate_planner(load_planner("optimal", 8), maps)
    with pytest.raises(InputError, match=f"planner 'vin' plans octile moves .*the maps use '{moves}' moves"):
        load_planner("vin", 28, moves=moves)
    with pytest.raises(InputError, match=f"the maps use '{moves}' moves: training follows 'octile'"):
        train_vin(maps, TrainConfig(epochs=1), progress=False)


@pytest.mark.parametrize("moves", ["octile", "moore", "news"])
def test_optimal_plans_and_is_never_harmful_on_every_movement_model(moves, tmp_path, capsys):
    maps_path, paths, pairs = tmp_path / "m.npz", tmp_path / "p.npz", tmp_path / "pairs.npz"
    argv = ["maps", "generate", "--n", "12", "--size", "10", "--seed", "3", "--starts", "2", "--moves", moves]
    assert main([*argv, "--out", str(maps_path), "--quiet"]) == 0
    maps = MapSet.load(maps_path)
    assert main(["plan", "--maps", str(maps_path), "--planner", "optimal", "--out", str(paths), "--quiet"]) == 0
    planned = PathSet.load(paths)
    assert planned.moves == moves and planned.reached.all() and planned.paths == maps.expert
    step = 1.0 if moves != "octile" else math.sqrt(2)
    moved = [np.abs(np.diff(p, axis=0)) for p in planned.paths.unpack()]
    costs = [float(sum(step if d.sum() == 2 else 1.0 for d in m)) for m in moved]
    np.testing.assert_allclose(costs, maps.expert_costs.reshape(-1), atol=1e-9)
    capsys.readouterr()
    attack = ["attack", "--maps", str(maps_path), "--planner", "optimal", "--strategy", "exhaustive", "--per-map", "0"]
    assert main([*attack, "--out", str(pairs), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["pairs"] > 50 and summary["harmful"] == 0 and summary["harm_counts"]["harmless"] == summary["pairs"]
    assert summary["planner"]["config"].get("moves", "octile") == moves
    assert PairSet.load(pairs).moves == moves
    if moves == "news":
        assert all(m.sum(axis=1).max(initial=1) == 1 for m in moved)  # straight moves only


def test_robustness_refuses_other_movement_models(maps_file):
    moves, path = maps_file
    with pytest.raises(InputError, match=f"the maps use '{moves}' moves: the robustness benchmark follows 'octile'"):
        robustness(load_planner("optimal", 8, moves=moves), MapSet.load(path), ["random"])
