"""`vinadv.exact_k2` and `vinadv robustness --exact-k2`: the exact harmful rate at k <= 2 against the union of the
one-cell and pair searches done the plain way (every cell, every pair of cells of each map through the planner, harm
from the classify oracles), the greedy never above it, both modes agreeing, the command."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

from tests.classify.oracle import rule_oracle
from tests.classify.test_harm import optimal_path, path_cost
from tests.grid.oracle import reachable
from vinadv.cli import main
from vinadv.commands.robustness import print_robustness
from vinadv.errors import InputError
from vinadv.exact_k2 import exact_k2
from vinadv.planners.vin.planner import as_planner
from vinadv.planners.vin.weights import save_vin
from vinadv.robustness import heldout_maps, robustness
from vinadv.testing.planners import planning_vin

SIZE = 8
TOL = 1e-6


@pytest.fixture(scope="module")
def planner():
    return as_planner(planning_vin(SIZE, seed=1, noise=0.1), SIZE)


@pytest.fixture(scope="module")
def maps():
    return heldout_maps(4, SIZE, seed=5)


@pytest.fixture(scope="module")
def greedy(planner, maps):
    return robustness(planner, maps, ["key-points", "random"], 2)


@pytest.fixture(scope="module")
def results(planner, maps, greedy):
    return {mode: exact_k2(planner, maps, mode, greedy=greedy) for mode in ("harmful", "regret")}


def _plain(planner, maps, i):
    """(valid, harmed by one cell, harmed by a pair, the largest regret over the pairs) of map i, the plain way."""
    obstacles, start, goal = maps.obstacles[i], tuple(maps.starts[i, 0]), tuple(maps.goals[i])
    free = [(r, c) for r in range(SIZE) for c in range(SIZE) if not obstacles[r, c] and (r, c) not in (start, goal)]
    edits = {1: [], 2: []}
    for k in (1, 2):
        for cells in itertools.combinations(free, k):
            adv = obstacles.copy()
            adv[tuple(np.array(cells).T)] = True
            if reachable(adv, start, goal):
                edits[k].append(adv)
    original = planner.plan(obstacles[None], np.array([start]), np.array([goal])).paths.cells.tolist()
    if [tuple(c) for c in original[-1:]] != [goal] or not edits[1]:
        return False, False, False, math.nan
    regret_o = path_cost(original) - path_cost(optimal_path(obstacles.tolist(), start, goal, True))
    harmed, largest = {}, -math.inf
    for k, advs in edits.items():
        paths = planner.plan(np.array(advs), np.repeat([start], len(advs), 0), np.repeat([goal], len(advs), 0)).paths
        harmed[k] = False
        for j, adv in enumerate(advs):
            path = paths.cells[paths.offsets[j] : paths.offsets[j + 1]].tolist()
            if rule_oracle(original, path, goal, round(4 * SIZE / 28))[0] == "UrP":
                regret = math.inf
            else:
                regret = path_cost(path) - path_cost(optimal_path(adv.tolist(), start, goal, True))
            harmed[k] |= regret > regret_o + TOL
            if k == 2:
                largest = max(largest, regret)
    return True, harmed[1], harmed[2], largest


@pytest.mark.slow  # every cell and pair of four maps through a plain-Python harm: several seconds
def test_the_exact_figures_are_the_plain_searches(planner, maps, results):
    plain = [_plain(planner, maps, i) for i in range(len(maps))]
    for mode, result in results.items():
        assert result.valid.tolist() == [p[0] for p in plain]
        assert result.harmful_k1.tolist() == [p[1] for p in plain]
        # a map one cell harms is not paired; every other valid map is harmed by a pair exactly when some pair harms it
        searched = result.valid & ~result.harmful_k1
        assert result.search.searched.tolist() == searched.tolist()
        assert result.harmful.tolist() == [p[1] or p[2] for p in plain], mode
    regret = results["regret"].regret
    for i in np.flatnonzero(results["regret"].search.searched):
        assert regret[i] == plain[i][3] or abs(regret[i] - plain[i][3]) < 1e-9
    assert results["harmful"].harmful.any() and not results["harmful"].harmful.all()  # the maps test both verdicts


def test_the_greedy_is_never_above_the_exact_search_and_the_modes_agree(results):
    assert results["harmful"].harmful.tolist() == results["regret"].harmful.tolist()
    for result in results.values():
        d = result.to_dict()
        greedy = result.greedy.harmful & result.valid
        assert not (greedy & ~result.harmful).any() and d["greedy"]["greedy_only"] == 0
        assert d["greedy"]["gap"] == int((result.harmful & ~greedy).sum())
        json.dumps(d)  # JSON-able: infinite regrets written as "inf"
    regret = results["regret"]
    searched = regret.search.searched
    assert searched.any() and (regret.regret[searched] >= regret.greedy.regret[searched] - 1e-9).all()


def test_a_greedy_result_of_other_maps_or_one_step_is_refused(planner, maps):
    one_step = robustness(planner, maps, ["random"], 1)
    with pytest.raises(InputError, match="max_obstacles >= 2"):
        exact_k2(planner, maps, greedy=one_step)
    with pytest.raises(InputError, match="harmful|regret"):
        exact_k2(planner, maps, "largest")
    with pytest.raises(InputError, match="has 4 maps, not 2"):
        exact_k2(planner, maps.take(slice(0, 2)), greedy=robustness(planner, maps, ["random"], 2))


def test_the_command_prints_and_gives_json(tmp_path, capsys):
    weights = tmp_path / f"vin{SIZE}.pt"
    save_vin(planning_vin(SIZE, seed=1, noise=0.1), weights)
    argv = ["robustness", "--size", str(SIZE), "--weights", str(weights), "--n", "4", "--seed", "5", "--quiet"]
    argv += ["--strategies", "key-points,random", "--max-obstacles", "2", "--exact-k2"]
    assert main([*argv, "regret", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["exact_k2"]["mode"] == "regret" and out["exact_k2"]["greedy"]["greedy_only"] == 0
    print_robustness(out)
    text = capsys.readouterr().out
    assert "exact harmful rate at k <= 2:" in text and "greedy worst case at k <= 2:" in text
    assert "largest regret over the pairs of" in text
    for bad in (["--max-obstacles", "1"], ["--edit", "remove"]):
        assert main([*argv, "harmful", *bad]) == 2
        assert "--exact-k2" in capsys.readouterr().err
