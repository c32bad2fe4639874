"""TransPath's own metrics (their `eval.py`): the expansions ratio and cost ratio against their vanilla A* on the hard
tasks, checked by hand on small rows, against a plain restatement on the six example tasks (their vanilla A* as the
literal search with every correction factor 1), and printed by `vinadv eval` beside Opt / Exp / Hmean."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from tests.interop.formats.test_transpath import example_files
from tests.planners.transpath.literal import example_tasks, literal_search
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.evaluation.search_metrics import (
    HARDNESS,
    evaluate_search,
    octile_distances,
    transpath_ratios,
    vanilla_transpath,
)
from vinadv.grid import generate_maps
from vinadv.interop.formats import read_maps
from vinadv.planners.registry import load_planner


def test_the_ratios_by_hand():
    # row 0: vanilla cost 11 >= 1.05 * 10, kept; row 1: vanilla cost 10.4 < 10.5, left out; row 2: kept, the planner
    # does not reach (its expansions count, its cost does not); row 3: vanilla did not reach, left out
    r = transpath_ratios(
        costs=[12.0, 10.4, 0.0, 5.0],
        reached=[True, True, False, True],
        expansions=[20, 5, 30, 1],
        vanilla_costs=[11.0, 10.4, 22.0, 0.0],
        vanilla_reached=[True, True, True, False],
        vanilla_expansions=[40, 50, 60, 1],
        octile_start=[10.0, 10.0, 20.0, 3.0],
    )
    assert (r["rows"], r["kept"], r["unreached"], r["hardness"]) == (4, 2, 1, HARDNESS)
    assert r["expansions_ratio"] == pytest.approx((20 / 40 + 30 / 60) / 2)
    assert r["cost_ratio"] == pytest.approx(12 / 11)
    assert (r["expansions"], r["vanilla_expansions"]) == (25.0, 50.0)
    none = transpath_ratios([1.0], [True], [1], [1.0], [True], [1], [1.0])  # cost = octile: not hard, none kept
    assert none["kept"] == 0 and none["expansions_ratio"] is None and none["cost_ratio"] is None
    assert octile_distances(np.array([[0, 0], [5, 1]]), np.array([[3, 1], [5, 1]])) == pytest.approx(
        [math.sqrt(2) + 2, 0]
    )
    with pytest.raises(InputError, match="every array"):
        transpath_ratios([1.0], [True], [1], [1.0, 2.0], [True], [1], [1.0])


def _cost(path) -> float:
    p = np.asarray(path)
    steps = np.abs(np.diff(p, axis=0))
    return float(sum(math.sqrt(2) if a and b else 1.0 for a, b in steps))


@pytest.fixture(scope="module")
def examples():
    return read_maps(example_files(), "transpath")[0]


def test_their_vanilla_astar_is_the_literal_search_with_factors_one(examples):
    obstacles, starts, goals, _ = example_tasks()
    vanilla = vanilla_transpath(obstacles, starts, goals)
    for i in range(6):
        path, expanded, reached, _ = literal_search(torch.ones(64, 64), ~obstacles[i], starts[i], goals[i], "cf")
        assert reached and vanilla.reached[i]
        assert (vanilla.paths[i] == np.array(path)).all() and (vanilla.expanded[i] == expanded).all()


@pytest.mark.parametrize("name", ["transpath-cf", "transpath-focal"])
def test_the_ratios_on_the_six_examples_are_their_plain_restatement(examples, name):
    torch.set_num_threads(1)
    planner = load_planner(name, 64)
    found = evaluate_search(planner, examples, theirs=True)
    result = planner.plan(examples.obstacles, examples.starts, examples.goals, True)
    vanilla = vanilla_transpath(examples.obstacles, examples.starts[:, 0], examples.goals)
    exp_ratios, cost_ratios = [], []
    for i in range(6):
        v_cost = _cost(vanilla.paths[i])
        (dr, dc) = np.abs(examples.starts[i, 0] - examples.goals[i])
        if v_cost >= 1.05 * (min(dr, dc) * math.sqrt(2) + abs(dr - dc)):  # their hardness limit
            exp_ratios.append(result.expanded[i].sum() / vanilla.expanded[i].sum())
            cost_ratios.append(_cost(result.paths[i]) / v_cost)
    theirs = found["transpath"]
    assert theirs["kept"] == len(exp_ratios) == 5  # one of the six is within 1.05 of the octile heuristic
    assert theirs["expansions_ratio"] == pytest.approx(np.mean(exp_ratios), rel=1e-12)
    assert theirs["cost_ratio"] == pytest.approx(np.mean(cost_ratios), rel=1e-12)
    assert theirs["expansions_ratio"] < 1  # the learned heuristics expand fewer cells than their vanilla A*
    assert found["opt"] is not None and found["exp"] is not None  # vinadv's beside them


def test_other_search_planners_get_no_ratios_and_a_policy_planner_cannot_have_them(examples):
    assert "transpath" not in evaluate_search(load_planner("astar", 64), examples)
    with pytest.raises(InputError, match="search planner on octile maps"):
        evaluate_search(load_planner("vin", 28), generate_maps(2, 28, 5, 1), theirs=True)


def test_eval_prints_both_labelled_blocks(tmp_path, capsys):
    maps = str(tmp_path / "tp.npz")
    assert main(["maps", "import", "--format", "transpath", *example_files(), "--out", maps, "--quiet"]) == 0
    assert main(["eval", "--planner", "transpath-cf", "--data", maps, "--threads", "1", "--quiet"]) == 0
    out = capsys.readouterr().out
    search = next(line for line in out.splitlines() if line.startswith("  search: "))
    theirs = next(line for line in out.splitlines() if line.startswith("  transpath: "))
    assert "Opt " in search and "Exp " in search and "Hmean " in search and "against vinadv's exact A*" in search
    assert "expansions ratio 0." in theirs and "cost ratio 1." in theirs
    assert "against their vanilla A* (f = 0.5 g + 0.501 h, h octile) on the 5 of 6 rows" in theirs
