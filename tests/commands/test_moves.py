"""Movement models through the commands: `optimal` plans, is evaluated, benchmarked and attacked on `moore` and
`news` maps (never harmful: it is optimal under the maps' own costs), and the stages that do not follow other
models (planners trained on octile maps, the port's protocol) refuse such maps with one line naming the model (exit
status 2), before any work, instead of computing with octile costs. Training on them: tests/planners/
test_training_moves.py."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from vinadv.attacks.pairs import PairSet
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.evaluation.planner_metrics import evaluate_planner
from vinadv.grid import MapSet, generate_maps
from vinadv.planners.pathset import PathSet
from vinadv.planners.registry import load_planner
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
        (["eval", "--data", "{maps}", "--weights", "{weights}"], "planner 'vin' plans octile moves"),
        (["vin", "eval", "--data", "{maps}", "--weights", "{weights}"], "planner 'vin' plans octile moves"),
        (
            ["vin", "eval", "--data", "{maps}", "--weights", "{weights}", "--protocol", "kentsommer"],
            "planner 'vin' plans octile moves",
        ),
    ],
    ids=["plan", "attack", "eval", "vin-eval", "vin-eval-port"],
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


def test_library_follows_the_model_or_refuses(maps_file):
    moves, path = maps_file
    maps = MapSet.load(path)
    figures = evaluate_planner(load_planner("optimal", 8), maps)  # the control, for the maps' own model
    assert figures["optimal_rate"] == figures["success_rate"] == figures["action_accuracy"] == 1.0
    assert figures["mean_extra_cost"] == 0.0
    with pytest.raises(InputError, match=f"planner 'vin' plans octile moves .*the maps use '{moves}' moves"):
        evaluate_planner(_vin8(path.parent), maps)
    with pytest.raises(InputError, match=f"planner 'vin' plans octile moves .*the maps use '{moves}' moves"):
        load_planner("vin", 28, moves=moves)


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


def _vin8(folder):
    weights = folder / "vin8.pt"
    save_vin(planning_vin(8), weights)
    return load_planner("vin", 8, weights=str(weights))


def test_robustness_follows_the_model_and_optimal_is_never_harmful(maps_file):
    moves, path = maps_file
    maps = MapSet.load(path)
    result = robustness(load_planner("optimal", 8, moves=moves), maps, ["random", "near-path"], 2).to_dict()
    assert result["settings"]["moves"] == moves and result["clean"]["mean_regret"] == 0.0
    for row in result["overall"]:
        assert row["harmful_rate"] in (0.0, None)
    with pytest.raises(InputError, match=f"planner 'vin' plans octile moves .*the maps use '{moves}' moves"):
        robustness(_vin8(path.parent), maps, ["random"])


def test_commands_that_generate_maps_take_moves(tmp_path, capsys):
    assert main(["eval", "--planner", "optimal", "--n", "3", "--size", "8", "--moves", "news", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["generated"]["moves"] == "news" and out["vinadv"]["optimal_rate"] == 1.0
    assert out["gppn"]["percent_optimal"] == out["gppn"]["percent_success"] == 1.0  # NEWS's shortest paths
    line = ["robustness", "--planner", "optimal", "--n", "4", "--size", "8", "--max-obstacles", "1"]
    assert main([*line, "--moves", "moore", "--strategies", "random", "--json", "--quiet"]) == 0
    assert json.loads(capsys.readouterr().out)["settings"]["moves"] == "moore"
    assert main([*line, "--moves", "hex"]) == 2
    assert "--moves 'hex': expected one of octile, moore, news" in capsys.readouterr().err
    assert main(["eval", "--planner", "optimal", "--data", str(tmp_path / "x.npz"), "--moves", "moore"]) == 2
    assert "--moves: only with --n" in capsys.readouterr().err
