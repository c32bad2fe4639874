"""The engine against the reference planner (re-running the PyTorch VIN at every step) and hand-built cases."""

import ast
import pathlib

import numpy as np
import pytest
import torch

import vinadv
from vinadv.errors import InputError
from vinadv.grid import generate_maps, shortest_distances
from vinadv.planners.vin import VIN, VINConfig, make_input
from vinadv.planners.vin.engine import TERMINATIONS, action_maps, plan_batch, plan_maps
from vinadv.planners.vin.reference import plan_reference
from vinadv.testing.planners import exact_vin, planning_vin, random_vin

E, W = 2, 3


def assert_same(a, b):
    assert a.paths == b.paths
    np.testing.assert_array_equal(a.termination, b.termination)
    np.testing.assert_array_equal(a.reached, b.reached)


@pytest.mark.parametrize("make", [planning_vin, random_vin], ids=["planning", "default-init"])
@pytest.mark.parametrize("corner_cutting", [True, False])
def test_identical_to_reference_16(make, corner_cutting):
    # the reference re-runs the VIN at every step, so its time grows with the maps: 12 (a full chunk of 8 and a
    # partial one) already end in a collision, a loop and the step limit with either model
    maps = generate_maps(12, 16, seed=3, n_starts=1, corner_cutting=corner_cutting)
    model = make(16, seed=1)
    args = (maps.obstacles, maps.starts[:, 0], maps.goals, model, corner_cutting)
    fast, ref = plan_batch(*args, chunk_size=8), plan_reference(*args)
    assert_same(fast, ref)
    assert {"collision", "loop", "step_limit"} <= set(ref.termination_names)


def test_identical_to_reference_28_all_endings():
    # 10 maps whose paths end in each of the four ways (checked below): the reference's cost is one VIN forward
    # per step, so few maps that cover the endings beat many that repeat them
    maps = generate_maps(10, 28, seed=24, n_starts=1)
    model = planning_vin(28, seed=1)
    args = (maps.obstacles, maps.starts[:, 0], maps.goals, model)
    fast, ref = plan_batch(*args), plan_reference(*args)
    assert_same(fast, ref)
    assert set(ref.termination_names) == set(TERMINATIONS)


@pytest.mark.slow
@pytest.mark.parametrize("size", [9, 13])
def test_identical_to_reference_odd_sizes(size):
    # the value iteration runs two rows at a time: an odd N leaves one padding row that must stay 0; 12 maps of two
    # starts end at the goal, in a loop and in a collision at both sizes
    maps = generate_maps(12, size, seed=11, n_starts=2)
    model = planning_vin(size, seed=4)
    fast = plan_maps(maps.obstacles, maps.goals, maps.starts, model)
    idx = np.repeat(np.arange(len(maps)), 2)
    ref = plan_reference(maps.obstacles[idx], maps.starts.reshape(-1, 2), maps.goals[idx], model)
    assert_same(fast, ref)
    assert {"goal", "loop", "collision"} <= set(ref.termination_names)
    actions = action_maps(model, maps.obstacles, maps.goals)
    with torch.no_grad():
        logits = model.action_logits(make_input(maps.obstacles, maps.goals)).numpy()
    decided = actions >= 0
    np.testing.assert_array_equal(actions[decided], np.argmax(logits, axis=-1)[decided])


def test_action_maps_match_torch_argmax_where_decided():
    maps = generate_maps(50, 16, seed=5, n_starts=1)
    model = planning_vin(16, seed=2)
    actions = action_maps(model, maps.obstacles, maps.goals)
    with torch.no_grad():
        logits = model.action_logits(make_input(maps.obstacles, maps.goals)).numpy()
    decided = actions >= 0
    assert decided.mean() > 0.99
    np.testing.assert_array_equal(actions[decided], np.argmax(logits, axis=-1)[decided])


def test_several_starts_share_a_value_map():
    maps = generate_maps(10, 16, seed=6, n_starts=3)
    model = planning_vin(16, seed=3)
    multi = plan_maps(maps.obstacles, maps.goals, maps.starts, model)
    one = plan_batch(
        np.repeat(maps.obstacles, 3, axis=0), maps.starts.reshape(-1, 2), np.repeat(maps.goals, 3, axis=0), model
    )
    assert_same(multi, one)


def hand_vin(west_when_blocked: bool) -> VIN:
    """Policy: E on every free cell; with `west_when_blocked`, W where the east neighbour is an obstacle."""
    model = VIN(VINConfig(k=3))
    with torch.no_grad():
        for p in model.parameters():
            p.zero_()
        model.h.weight[0, 0, 1, 1] = 5.0  # r = 1 + 5 * obstacle
        model.h.bias[0] = 1.0
        model.r.weight[0, 0] = 1.0
        model.q.weight[E, 0, 1, 1] = 1.5
        if west_when_blocked:
            model.q.weight[W, 0, 1, 2] = 1.0  # r of the east neighbour: 1 if free, 6 if obstacle
        model.fc.weight[:, :8] = torch.eye(8)
    return model


def empty_map(n=16):
    obs = np.zeros((n, n), bool)
    obs[0, :] = obs[-1, :] = obs[:, 0] = obs[:, -1] = True
    return obs


@pytest.mark.parametrize(
    "west, start, goal, term, moves",
    [
        (False, (8, 1), (8, 5), "goal", 4),
        (False, (8, 1), (1, 1), "collision", 13),  # L = 7 allows 14 moves; the wall is 13 moves east
        (False, (8, 1), (10, 1), "step_limit", 4),  # L = 2: at most 4 moves
        (True, (8, 1), (1, 1), "loop", 13),  # east to the wall, then west onto a visited cell
    ],
)
def test_hand_built_endings(west, start, goal, term, moves):
    model = hand_vin(west)
    obs, starts, goals = empty_map()[None], np.array([start]), np.array([goal])
    for planner in (plan_batch, plan_reference):
        result = planner(obs, starts, goals, model)
        assert result.termination_names[0] == term
        path = result.paths[0]
        assert len(path) == moves + 1
        np.testing.assert_array_equal(path[0], start)
        np.testing.assert_array_equal(path[:, 0], start[0])
        np.testing.assert_array_equal(path[:, 1], np.arange(start[1], start[1] + moves + 1))
        assert result.reached[0] == (term == "goal")


def test_step_limit_past_the_straight_line_bound():
    # a wall between start and goal: L (around it) exceeds the straight-line distance 2, so the engine's first
    # bound (2 * 2 moves) must give way to the exact 2L
    obs = empty_map()
    obs[9, 1:4] = True
    start, goal = (8, 1), (10, 1)
    _, moves = shortest_distances(obs[None], np.array([goal]), True)
    limit = 2 * int(moves[0, 8, 1])
    assert 4 < limit < 13  # hits the limit before the east wall
    for planner in (plan_batch, plan_reference):
        result = planner(obs[None], np.array([start]), np.array([goal]), hand_vin(False))
        assert result.termination_names[0] == "step_limit"
        assert len(result.paths[0]) == limit + 1


def test_collision_into_obstacle():
    obs = empty_map()
    obs[8, 5] = True  # stops the eastward walk at column 4
    model = hand_vin(False)
    res = plan_batch(obs[None], np.array([[8, 1]]), np.array([[1, 1]]), model)
    assert res.termination_names[0] == "collision" and res.paths[0][-1].tolist() == [8, 4]


def test_unreachable_goal_uses_n_squared_limit():
    obs = empty_map()
    obs[:, 8] = True  # a wall: the goal (8, 12) cannot be reached
    _, moves = shortest_distances(obs[None], np.array([[8, 12]]))
    assert moves[0, 8, 1] == -1
    res = plan_batch(obs[None], np.array([[8, 1]]), np.array([[8, 12]]), hand_vin(False))
    assert res.termination_names[0] == "collision" and len(res.paths[0]) == 7


def test_empty_batch_and_bad_inputs():
    model = planning_vin(16)
    res = plan_batch(np.zeros((0, 16, 16), bool), np.zeros((0, 2), int), np.zeros((0, 2), int), model)
    assert len(res) == 0 and res.paths.offsets.tolist() == [0]
    with pytest.raises(InputError):
        plan_batch(np.zeros((1, 16, 16), bool), np.array([[16, 0]]), np.array([[1, 1]]), model)
    with pytest.raises(InputError):
        plan_batch(np.zeros((1, 16, 15), bool), np.array([[1, 1]]), np.array([[2, 2]]), model)
    assert TERMINATIONS == ("goal", "collision", "loop", "step_limit")


def test_production_code_never_imports_the_reference_planner():
    # the reference is the tests' oracle: the engine must reach its answers by its own means
    root = pathlib.Path(vinadv.__file__).parent
    importers = []
    for path in root.rglob("*.py"):
        text = path.read_text()
        if path.name == "reference.py" or "reference" not in text:  # no import of it without the word: not parsed
            continue
        for node in ast.walk(ast.parse(text)):
            names = [a.name for a in node.names] if isinstance(node, (ast.Import, ast.ImportFrom)) else []
            module = node.module if isinstance(node, ast.ImportFrom) else ""
            if (
                module == "vinadv.planners.vin.reference"
                or "vinadv.planners.vin.reference" in names
                or (module == "vinadv.planners" and "reference" in names)
            ):
                importers.append(str(path.relative_to(root)))
    assert importers == []


def test_exact_value_iteration_weights_plan_optimal_paths():
    # An independent oracle for the engine and the rollout: VIN weights set to exact value iteration must follow
    # Dijkstra's costs from every start whose optimal cost is below k. Its ties send every step through the exact
    # replay (Python), so 30 maps of 5 starts (150 paths) are the size: more maps repeat the same code path.
    maps = generate_maps(30, 16, seed=8, n_starts=5)
    k = 20
    result = plan_maps(maps.obstacles, maps.goals, maps.starts, exact_vin(16, k=k))
    dist, _ = shortest_distances(maps.obstacles, maps.goals)
    b = np.repeat(np.arange(len(maps.goals)), maps.starts.shape[1])
    rows, cols = maps.starts[..., 0].ravel(), maps.starts[..., 1].ravel()
    within = dist[b, rows, cols] < k
    assert within.mean() > 0.95
    assert result.reached[within].all()
    np.testing.assert_allclose(result.paths.costs()[within], dist[b, rows, cols][within], atol=1e-9)
