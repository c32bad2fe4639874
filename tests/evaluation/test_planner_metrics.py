"""Evaluation figures on hand-built maps and hand-set VINs whose policy is known cell by cell."""

import math

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.grid.oracle import brute_distances, legal
from vinadv.evaluation.planner_metrics import LENGTH_BUCKET, action_accuracy_counts, evaluate_vin, rollout_metrics
from vinadv.grid.mapset import MapSet
from vinadv.grid.shortest_paths import expert_paths
from vinadv.planners.result import COLLISION, GOAL, LOOP, PlanResult
from vinadv.planners.vin import VIN, VINConfig
from vinadv.vocabulary import TERMINATIONS

N_, S_, E_, W_ = 0, 1, 2, 3
SQ2 = math.sqrt(2)


def constant_vin(action: int, k: int = 10) -> VIN:
    """A VIN whose logits are 1 for `action` and 0 for the others at every cell: q channel 0 is 1 everywhere."""
    model = VIN(VINConfig(k=k))
    with torch.no_grad():
        for p in model.parameters():
            p.zero_()
        model.h.bias[0] = 1.0
        model.r.weight[0, 0] = 1.0
        model.q.weight[0, 0, 1, 1] = 1.0
        model.fc.weight[action, 0] = 1.0
    return model


def east_until_wall_vin(k: int = 10) -> VIN:
    """East while the cell to the east is free, west when it is an obstacle (so it turns back and loops)."""
    model = VIN(VINConfig(k=k))
    with torch.no_grad():
        for p in model.parameters():
            p.zero_()
        model.h.weight[0, 0, 1, 2] = 1.0  # obstacle channel, east neighbour
        model.h.bias[0] = -0.5  # r = +0.5 with an obstacle east, -0.5 without
        model.r.weight[0, 0] = 1.0
        model.q.weight[0, 0, 1, 1] = 1.0
        model.fc.weight[E_, 0] = -1.0
        model.fc.weight[W_, 0] = 1.0
    return model


def make_maps(size, cases):
    """cases: list of (extra obstacle cells, goal, start); one start per map, border obstacles."""
    obstacles = np.zeros((len(cases), size, size), dtype=bool)
    obstacles[:, 0, :] = obstacles[:, -1, :] = obstacles[:, :, 0] = obstacles[:, :, -1] = True
    for i, (cells, _, _) in enumerate(cases):
        for r, c in cells:
            obstacles[i, r, c] = True
    goals = np.array([g for _, g, _ in cases], dtype=np.int64)
    starts = np.array([[s] for _, _, s in cases], dtype=np.int64)
    costs, paths = expert_paths(obstacles, goals, starts)
    return MapSet(
        obstacles=obstacles, goals=goals, starts=starts, expert_costs=costs, expert=paths, corner_cutting=True, seed=-1
    )


def test_rollout_metrics_on_hand_built_paths():
    paths = [
        np.array([(1, 1), (1, 2), (1, 3)]),  # reached, optimal: cost 2
        np.array([(1, 1), (2, 2), (2, 3), (1, 4)]),  # reached, cost 2 sqrt2 + 1 where 3 was optimal
        np.array([(3, 3), (3, 4)]),  # collision
        np.array([(4, 4), (4, 5), (5, 5)]),  # loop
    ]
    result = PlanResult.from_paths(paths, np.array([GOAL, GOAL, COLLISION, LOOP]))
    m = rollout_metrics(result, np.array([2.0, 3.0, 5.0, 6.0]))
    assert m["rollouts"] == 4
    assert m["success_rate"] == 0.5
    assert m["optimal_rate"] == 0.25 and m["optimal_rate_of_reached"] == 0.5
    assert m["mean_extra_cost"] == pytest.approx((2 * SQ2 + 1 - 3) / 2)
    assert m["mean_extra_cost_relative"] == pytest.approx((2 * SQ2 + 1 - 3) / 3 / 2)
    assert m["terminations"] == {"goal": 2, "collision": 1, "loop": 1, "step_limit": 0}


def test_constant_east_policy_reaches_collides_and_hits_the_step_limit():
    maps = make_maps(
        10,
        [
            ([], (3, 6), (3, 2)),  # goal straight east: reached in 4 moves, optimal
            ([(5, 5)], (7, 7), (5, 2)),  # obstacle ahead: (5,2) (5,3) (5,4), then collision
            ([], (3, 3), (2, 2)),  # goal one diagonal move away: L = 1, limit 2 moves, then step_limit
            ([], (2, 4), (2, 8)),  # goal west: the first move east hits the border
        ],
    )
    m = evaluate_vin(constant_vin(E_), maps)
    assert m["terminations"] == {"goal": 1, "collision": 2, "loop": 0, "step_limit": 1}
    assert m["success_rate"] == 0.25 and m["optimal_rate"] == 0.25 and m["mean_extra_cost"] == 0.0
    # optimal moves 4, 5 (two rows, five columns), 1 and 4: buckets 0-4 (three rollouts) and 5-9 (one)
    assert m["by_length"] == [
        {
            "moves": [0, 4],
            "rollouts": 3,
            "success_rate": 1 / 3,
            "optimal_rate": 1 / 3,
            "terminations": {"goal": 1, "collision": 1, "loop": 0, "step_limit": 1},
        },
        {
            "moves": [5, 9],
            "rollouts": 1,
            "success_rate": 0.0,
            "optimal_rate": 0.0,
            "terminations": {"goal": 0, "collision": 1, "loop": 0, "step_limit": 0},
        },
    ]
    # action accuracy by brute force: the share of free, reachable, non-goal cells where E is optimal
    hits = cells = 0
    for i in range(len(maps)):
        obs = maps.obstacles[i].tolist()
        goal = tuple(maps.goals[i])
        best = brute_distances(obs, goal)
        for (r, c), (cost, _) in best.items():
            if obs[r][c] or (r, c) == goal or not math.isfinite(cost):
                continue
            cells += 1
            hits += legal(obs, r, c, E_) and abs(best[(r, c + 1)][0] + 1 - cost) < 1e-9
    assert m["action_cells"] == cells and m["action_accuracy"] == pytest.approx(hits / cells)


def test_turning_back_is_a_loop():
    maps = make_maps(8, [([(3, 4)], (6, 6), (3, 1))])  # E, E to (3,3), obstacle east: W back to (3,2) = loop
    m = evaluate_vin(east_until_wall_vin(), maps)
    assert m["terminations"]["loop"] == 1 and m["success_rate"] == 0.0 and math.isnan(m["mean_extra_cost"])


def test_ties_go_to_the_lowest_action_index():
    model = constant_vin(E_)
    with torch.no_grad():
        model.fc.weight.zero_()  # every logit 0: argmax is action 0 (N)
    maps = make_maps(8, [([], (1, 3), (4, 3))])  # goal due north: N is optimal on that column
    correct, cells = action_accuracy_counts(model, maps.obstacles, maps.goals)
    best = brute_distances(maps.obstacles[0].tolist(), (1, 3))
    want = sum(
        1
        for (r, c), (cost, _) in best.items()
        if not maps.obstacles[0, r, c]
        and (r, c) != (1, 3)
        and math.isfinite(cost)
        and legal(maps.obstacles[0].tolist(), r, c, N_)
        and abs(best[(r - 1, c)][0] + 1 - cost) < 1e-9
    )
    assert correct == want and cells == 35
    m = evaluate_vin(model, maps)
    assert m["success_rate"] == 1.0 and m["optimal_rate"] == 1.0


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 3), st.integers(0, 40), st.booleans(), st.booleans()), max_size=40))
def test_by_length_against_a_plain_count(rows):
    """`by_length` against a per-path Python count: (termination, optimal moves, optimal cost?, kept?) per path."""
    paths = [np.array([(0, 0), (0, 1)]) for _ in rows]  # cost 1 each
    result = PlanResult.from_paths(paths, np.array([t for t, *_ in rows], dtype=np.int8))
    costs = np.array([1.0 if opt else 2.0 for _, _, opt, _ in rows])
    moves = np.array([m for _, m, _, _ in rows], dtype=np.int64)
    mask = np.array([keep for *_, keep in rows], dtype=bool)
    got = rollout_metrics(result, costs, mask, moves)["by_length"]
    want = {}
    for t, m, opt, keep in rows:
        if keep:
            row = want.setdefault(m // LENGTH_BUCKET, {"n": 0, "ok": 0, "opt": 0, "ends": [0, 0, 0, 0]})
            row["n"] += 1
            row["ok"] += t == GOAL
            row["opt"] += t == GOAL and opt
            row["ends"][t] += 1
    assert [r["moves"][0] // LENGTH_BUCKET for r in got] == sorted(want)
    for r in got:
        w = want[r["moves"][0] // LENGTH_BUCKET]
        assert r["moves"][1] - r["moves"][0] == LENGTH_BUCKET - 1
        assert r["rollouts"] == w["n"] and r["terminations"] == dict(zip(TERMINATIONS, w["ends"]))
        assert r["success_rate"] == pytest.approx(w["ok"] / w["n"])
        assert r["optimal_rate"] == pytest.approx(w["opt"] / w["n"])
    assert "by_length" not in rollout_metrics(result, costs, mask)
