"""`vinadv.attacks.exact_pairs`: every pair of addable cells, against plain-Python loops over the pairs (the
oracle: its own pair order, reachability and harm from tests.grid.oracle and the classify oracles)."""

import itertools
import math

import numpy as np
import pytest

from tests.classify.oracle import rule_oracle
from tests.classify.test_harm import optimal_path, path_cost
from tests.grid.oracle import reachable
from vinadv.attacks.exact_pairs import exact_pairs, pair_at
from vinadv.attacks.neighbourhood import chebyshev_distance
from vinadv.grid import generate_maps
from vinadv.identify import harm_order, identify
from vinadv.planners.vin.planner import as_planner

SIZE = 8
TOL = 1e-6


@pytest.fixture(scope="module")
def maps():
    # the first holds harmful pairs, the second none
    return generate_maps(3, SIZE, seed=3, n_starts=1).take(np.array([0, 2]))


@pytest.fixture(scope="module")
def planner(model):
    return as_planner(model, SIZE)


def harm_judge(pairs):
    ident = identify(pairs, harm_tol=TOL)
    return ident.harm.harm == "harmful", harm_order(ident.labels, ident.harm.regret_a)


def oracle_order(obstacles, start, goal, path):
    """The candidate cells in search order, by brute force: free, neither start nor goal, goal reachable without it;
    by Chebyshev distance to the path's nearest cell, then row-major."""
    cells = [
        (r, c)
        for r in range(SIZE)
        for c in range(SIZE)
        if not obstacles[r, c] and (r, c) not in (start, goal) and reachable(_with(obstacles, [(r, c)]), start, goal)
    ]
    return sorted(cells, key=lambda cell: (min(max(abs(cell[0] - p[0]), abs(cell[1] - p[1])) for p in path), cell))


def _with(obstacles, cells):
    out = obstacles.copy()
    for cell in cells:
        out[cell] = True
    return out


@pytest.fixture(scope="module")
def oracle(maps, planner):
    """Per map: every valid pair in search order (colex over the ordered cells) with its harm and strength, computed
    one pair at a time. A pair whose path is unchanged is harmless (the path's cost is the same and the optimum
    can only grow): only changed paths are costed."""
    out = []
    for i in range(len(maps)):
        obstacles, start, goal = maps.obstacles[i], tuple(maps.starts[i, 0]), tuple(maps.goals[i])
        plan = planner.plan(obstacles[None], np.array([start]), np.array([goal]))
        original = [tuple(c) for c in plan.paths.cells.tolist()]
        cells = oracle_order(obstacles, start, goal, original)
        pairs = [(cells[a], cells[b]) for b in range(len(cells)) for a in range(b)]
        pairs = [p for p in pairs if reachable(_with(obstacles, p), start, goal)]
        adv = np.array([_with(obstacles, p) for p in pairs]).reshape(-1, SIZE, SIZE)
        paths = planner.plan(adv, np.repeat([start], len(adv), 0), np.repeat([goal], len(adv), 0)).paths
        regret_o = path_cost(original) - path_cost(optimal_path(obstacles.tolist(), start, goal, True))
        rows = []
        for k, pair in enumerate(pairs):
            path = [tuple(c) for c in paths.cells[paths.offsets[k] : paths.offsets[k + 1]].tolist()]
            label = rule_oracle(original, path, goal, round(4 * SIZE / 28))[0]
            if label == "UrP":
                harmful, strength = original[-1] == goal, math.inf
            elif path == original:
                harmful, strength = False, regret_o
            else:
                strength = path_cost(path) - path_cost(optimal_path(adv[k].tolist(), start, goal, True))
                harmful = label != "invalid" and strength > regret_o + TOL
            rows.append((pair, harmful, strength))
        out.append({"cells": cells, "rows": rows})
    return out


def test_pair_at_is_the_colex_order():
    expected = [(i, j) for j in range(60) for i in range(j)]
    i, j = pair_at(np.arange(len(expected)))
    assert list(zip(i.tolist(), j.tolist())) == expected
    # around triangular numbers far out, where a float square root may round across the block's edge
    for j0 in (700, 4096, 10**6 + 3):
        start = j0 * (j0 - 1) // 2
        i, j = pair_at(np.array([start - 1, start, start + j0 - 1]))
        assert (i.tolist(), j.tolist()) == ([j0 - 2, 0, j0 - 1], [j0 - 1, j0, j0])


def test_chebyshev_distance_is_the_brute_force_one():
    rng = np.random.default_rng(0)
    mask = rng.random((3, 7, 7)) < 0.08
    mask[2] = False  # no cell: every distance the side
    got = chebyshev_distance(mask)
    for b, r, c in itertools.product(range(3), range(7), range(7)):
        cells = np.argwhere(mask[b])
        want = min((max(abs(r - x), abs(c - y)) for x, y in cells), default=7)
        assert got[b, r, c] == want


@pytest.mark.parametrize("chunk", [8192, 37])
def test_all_pairs_finds_the_brute_force_counts_and_strongest_pair(maps, planner, oracle, chunk):
    result = exact_pairs(
        maps.obstacles, maps.starts[:, 0], maps.goals, planner, harm_judge, stop_at_harmful=False, chunk=chunk
    )
    assert result.complete.all()
    for i, o in enumerate(oracle):
        n = len(o["cells"])
        assert result.candidate_pairs[i] == n * (n - 1) // 2 == result.tried[i]
        assert result.planned[i] == len(o["rows"])
        assert result.harmful_pairs[i] == sum(h for _, h, _ in o["rows"])
        kept = np.flatnonzero(result.pairs.map_index == i)
        if not o["rows"]:
            assert not len(kept)
            continue
        strengths = [s for _, _, s in o["rows"]]
        best = max(strengths)
        first = next(k for k, s in enumerate(strengths) if s == best or abs(s - best) < 1e-9)
        assert [tuple(c) for c in result.pairs.added[kept[0]].tolist()] == list(o["rows"][first][0])
    assert result.harmful_pairs.sum() > 0  # the test maps hold harmful pairs (else it checks too little)


def test_stopping_gives_the_first_harmful_pair_in_search_order(maps, planner, oracle):
    result = exact_pairs(maps.obstacles, maps.starts[:, 0], maps.goals, planner, harm_judge, chunk=23)
    for i, o in enumerate(oracle):
        harmful = [pair for pair, h, _ in o["rows"] if h]
        assert result.harmful[i] == bool(harmful)
        kept = np.flatnonzero(result.pairs.map_index == i)
        if harmful:
            assert [tuple(c) for c in result.pairs.added[kept[0]].tolist()] == list(harmful[0])
            assert result.tried[i] < result.candidate_pairs[i] or harmful[0] == o["rows"][-1][0]
        else:
            assert not len(kept) and result.complete[i] and result.tried[i] == result.candidate_pairs[i]


def test_only_the_maps_asked_for_are_searched(maps, planner):
    search = np.zeros(len(maps), dtype=bool)
    search[1] = True
    result = exact_pairs(maps.obstacles, maps.starts[:, 0], maps.goals, planner, harm_judge, search=search)
    assert result.searched.tolist() == search.tolist()
    assert (result.candidate_pairs[~search] == 0).all() and set(result.pairs.map_index.tolist()) <= {1}


def test_pairs_that_cut_the_way_are_not_planned_in_any_round(planner):
    # a corridor two cells high: the two cells of one column together cut it, neither alone does
    obstacles = np.ones((1, SIZE, SIZE), dtype=bool)
    obstacles[0, 2:4, 1:7] = False
    starts, goals = np.array([[2, 1]]), np.array([[3, 6]])
    results = [
        exact_pairs(obstacles, starts, goals, planner, harm_judge, stop_at_harmful=False, chunk=chunk)
        for chunk in (1, 8192)  # one pair a round: the rounds of a cutting pair plan nothing
    ]
    for result in results:
        assert result.candidate_pairs[0] == result.tried[0] == 45  # 10 valid cells
        assert result.planned[0] == 45 - 4  # the columns 2 to 5
    assert results[0].harmful_pairs.tolist() == results[1].harmful_pairs.tolist()
    assert results[0].pairs.added.tolist() == results[1].pairs.added.tolist()
