"""Opt / Exp / Hmean (`vinadv.evaluation.search_metrics`) against values worked out by hand, and on planned maps."""

import json
import math

import numpy as np
import pytest

from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.evaluation.search_metrics import evaluate_search, path_costs, search_metrics, search_rows
from vinadv.grid import generate_maps
from vinadv.grid.paths import PackedPaths
from vinadv.planners.registry import load_planner

COSTS = [5.0, 6.0, 7.0, 3.0]
REACHED = [True, True, False, True]  # row 2 fails: never optimal, whatever its cost
OPTIMAL = [5.0, 5.0, 7.0, 3.0]
EXPANSIONS = [10, 20, 5, 4]
ASTAR = [20, 20, 20, 4]


def test_metrics_of_one_start_per_map_by_hand():
    m = search_metrics(COSTS, REACHED, OPTIMAL, EXPANSIONS, ASTAR)
    assert m["rows"] == 4
    assert m["opt"] == 0.5  # rows 0 and 3
    assert m["exp"] == pytest.approx((0.5 + 0.0 + 0.75 + 0.0) / 4)  # (20-10)/20, 0, (20-5)/20, 0
    assert m["hmean"] == pytest.approx(2 / (1 / 0.5 + 1 / 0.3125))
    assert m["success"] == 0.75
    assert m["cost_ratio"] == pytest.approx((1 + 6 / 5 + 1) / 3)
    assert m["expansions"] == 39 / 4 and m["astar_expansions"] == 64 / 4


def test_several_starts_per_map_average_each_maps_harmonic_mean():
    m = search_metrics(COSTS, REACHED, OPTIMAL, EXPANSIONS, ASTAR, maps=[0, 0, 1, 1])
    map0 = 2 / (1 / 0.5 + 1 / 0.25)  # opt 1/2, exp (0.5 + 0) / 2
    map1 = 2 / (1 / 0.5 + 1 / 0.375)  # opt 1/2, exp (0.75 + 0) / 2
    assert m["hmean"] == pytest.approx((map0 + map1) / 2)
    assert m["opt"] == 0.5 and m["exp"] == pytest.approx(0.3125)  # the means do not depend on the grouping


def test_more_expansions_than_astar_save_nothing_and_zeros_give_a_zero_harmonic_mean():
    m = search_metrics([4.0], [False], [3.0], [30], [10])
    assert m["opt"] == 0 and m["exp"] == 0 and m["hmean"] == pytest.approx(0, abs=1e-9)
    assert m["cost_ratio"] is None and m["success"] == 0


def test_a_planner_without_expansions_has_no_exp_nor_hmean():
    m = search_metrics(COSTS, REACHED, OPTIMAL)
    assert m["exp"] is None and m["hmean"] is None and m["opt"] == 0.5
    assert search_metrics([], [], [])["opt"] is None


def test_bad_inputs_are_refused():
    with pytest.raises(InputError, match="3 costs, 2 reached"):
        search_metrics([1, 2, 3], [True, True], [1, 2, 3])
    with pytest.raises(InputError, match="A\\*'s >= 1"):
        search_metrics([1.0], [True], [1.0], [3], [0])


def test_path_costs_follow_the_movement_model():
    paths = PackedPaths.pack([[(0, 0), (1, 1), (1, 2)], [(3, 3)], [(0, 0), (0, 1), (1, 1)]])
    assert path_costs(paths, "octile").tolist() == pytest.approx([1 + math.sqrt(2), 0, 2])
    assert path_costs(paths, "moore").tolist() == [2, 0, 2]
    assert path_costs(paths, "news").tolist() == [2, 0, 2]


def test_planners_on_generated_maps():
    maps = generate_maps(4, 10, seed=4, n_starts=2)
    astar = evaluate_search(load_planner("astar", 10), maps)
    assert astar["opt"] == 1.0 and astar["exp"] == 0.0 and astar["success"] == 1.0 and astar["cost_ratio"] == 1.0
    assert astar["expansions"] == astar["astar_expansions"] and astar["rows"] == 8
    optimal = evaluate_search(load_planner("optimal", 10), maps)
    assert optimal["opt"] == 1.0 and optimal["exp"] is None
    weighted = evaluate_search(load_planner("wastar:w=4", 10), maps)
    assert weighted["success"] == 1.0 and weighted["cost_ratio"] >= 1.0 and weighted["exp"] >= 0.0
    assert weighted["opt"] == pytest.approx(np.mean(np.isclose(weighted_costs(maps), maps.expert_costs.ravel())))


def test_search_rows_hold_the_values_behind_the_means():
    maps = generate_maps(4, 10, seed=4, n_starts=2)
    rows = search_rows(load_planner("wastar:w=4", 10), maps)
    costs = weighted_costs(maps)
    # oracle: the weighted planner's own paths, planned here, against the expert costs, row by row
    assert rows.costs.tolist() == pytest.approx(costs.tolist()) and rows.maps.tolist() == [0, 0, 1, 1, 2, 2, 3, 3]
    assert rows.cost_ratio.tolist() == pytest.approx((costs / maps.expert_costs.ravel()).tolist())
    reference = load_planner("astar", 10).plan(
        maps.obstacles[rows.maps], maps.starts.reshape(-1, 2), maps.goals[rows.maps]
    )
    assert rows.astar_expansions.tolist() == reference.expansions.tolist()
    assert rows.exp.tolist() == pytest.approx(np.maximum(1 - rows.expansions / rows.astar_expansions, 0).tolist())
    metrics = rows.metrics()
    assert metrics["cost_ratio"] == pytest.approx(rows.cost_ratio.mean()) and metrics["exp"] == pytest.approx(
        rows.exp.mean()
    )
    assert search_rows(load_planner("optimal", 10), maps).exp is None


def weighted_costs(maps):
    result = load_planner("wastar:w=4", 10).plan(maps.obstacles, maps.starts, maps.goals)
    return result.paths.costs()


def test_eval_json_shows_the_search_metrics(capsys):
    assert main(["eval", "--n", "3", "--size", "10", "--starts", "2", "--planner", "wastar:w=2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["planner"] == {"name": "wastar", "size": 10, "config": {"w": 2.0}, "weights_sha256": None}
    # a search planner has no policy: no action accuracy, no gppn protocol (its paths get vinadv's rollout figures)
    assert out["vinadv"]["action_accuracy"] is None and "gppn" not in out
    assert set(out["search"]) >= {"opt", "exp", "hmean", "success", "cost_ratio"} and out["search"]["rows"] == 6
    assert main(["eval", "--n", "3", "--size", "10", "--starts", "2", "--planner", "optimal"]) == 0
    text = capsys.readouterr().out
    assert "search: Opt 100.00%, Exp n/a, Hmean n/a, success 100.00%, cost ratio 1.0000 over 6" in text
