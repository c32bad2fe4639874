"""Stages that do not follow movement models other than `octile` yet refuse such maps with one line naming the
model (exit status 2), before any work, instead of computing with octile costs."""

from __future__ import annotations

import pytest

from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import MapSet, generate_maps
from vinadv.planners.evaluation import evaluate_planner
from vinadv.planners.registry import load_planner
from vinadv.planners.testing import planning_vin
from vinadv.planners.training import TrainConfig, train_vin
from vinadv.planners.vin.weights import save_vin


@pytest.fixture(scope="module", params=["moore", "news"])
def maps_file(request, tmp_path_factory):
    path = tmp_path_factory.mktemp("moves") / f"{request.param}.npz"
    generate_maps(4, 8, seed=1, n_starts=2, moves=request.param).save(path)
    return request.param, path


@pytest.mark.parametrize(
    "argv, message",
    [
        (["plan", "--maps", "{maps}", "--planner", "optimal", "--out", "{out}"], "planner 'optimal' plans octile"),
        (
            ["attack", "--maps", "{maps}", "--strategy", "random", "--planner", "optimal", "--out", "{out}"],
            "planner 'optimal' plans octile",
        ),
        (["eval", "--data", "{maps}", "--planner", "optimal"], "planner 'optimal' plans octile"),
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
