"""`transpath-cf` and `transpath-focal`: both modes (the compiled replica, the differentiable search) against the
literal restatement of the authors' search on their six example tasks and generated maps (paths and expanded cells,
float32 ties counted), end to end through `plan`, the maps' corner-cutting rule, the capabilities, and the refusal of
other sizes."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import torch

from tests.planners.transpath.literal import example_tasks, literal_search, plain_forward, state
from vinadv.grid import generate_maps
from vinadv.planners import check_planner
from vinadv.planners.interface import PlannerError
from vinadv.planners.registry import load_planner
from vinadv.planners.transpath.differentiable import search_arrays
from vinadv.planners.transpath.model import SHIPPED_WEIGHTS
from vinadv.planners.transpath.planner import TransPathPlanner
from vinadv.planners.transpath.search import transpath_search
from vinadv.planners.weights import weights_checksum

NAMES = {"cf": "transpath-cf", "f": "transpath-focal"}


@pytest.fixture(scope="module")
def examples():
    return example_tasks()


def literal_answers(values: torch.Tensor, obstacles, starts, goals, mode):
    """Per task: `(path, expanded, ties)` of the literal search on the network values `(B, N, N)`."""
    answers = []
    for b in range(len(obstacles)):
        path, expanded, reached, ties = literal_search(values[b], ~obstacles[b], starts[b], goals[b], mode)
        assert reached
        answers.append((path, expanded, ties))
    return answers


def mismatches(result, answers) -> list[int]:
    return [
        b
        for b, (path, expanded, _) in enumerate(answers)
        if [tuple(c) for c in result.paths[b].tolist()] != path or not np.array_equal(result.expanded[b], expanded)
    ]


def both_modes_mismatches(values: torch.Tensor, obstacles, starts, goals, mode, answers) -> tuple[list, list]:
    """The tasks where the compiled replica, and where the differentiable search, part from the literal answers, on
    the same network values."""
    replica = transpath_search(values.numpy(), obstacles, starts, goals, mode, focal_exp=torch.exp(values).numpy())
    assert replica.reached.all()
    paths, _, expanded = search_arrays(values, obstacles, starts, goals, mode)
    return mismatches(replica, answers), mismatches(SimpleNamespace(paths=paths, expanded=expanded), answers)


@pytest.mark.parametrize("mode", ["cf", "f"])
def test_both_modes_equal_the_literal_search_on_the_six_examples(examples, mode):
    """The authors' forward (plain, one batch of the six, as their notebook) and their search, restated literally,
    against the compiled replica and the differentiable search on the same values: the same paths and expanded cells
    on every task, and no float32 tie met (where two cells tie, all take the row-major first; the count would show
    it)."""
    torch.set_num_threads(1)
    obstacles, starts, goals, _ = examples
    with torch.no_grad():
        values = plain_forward(state(mode), obstacles, starts if mode == "f" else None, goals)[:, 0]
    answers = literal_answers(values, obstacles, starts, goals, mode)
    assert both_modes_mismatches(values, obstacles, starts, goals, mode, answers) == ([], [])
    assert [ties for _, _, ties in answers] == [0] * 6


@pytest.mark.parametrize("mode", ["cf", "f"])
def test_the_planner_end_to_end_equals_the_literal_forward_and_search(examples, mode):
    """`plan` (its forward batched its own way: PyTorch's convolutions may round a batch of other maps differently,
    by about 1e-5) against the literal forward and search on two of the tasks (all six: the test above, and
    docs/guide/transpath.md)."""
    torch.set_num_threads(1)
    obstacles, starts, goals = (a[[1, 4]] for a in examples[:3])
    with torch.no_grad():
        values = plain_forward(state(mode), obstacles, starts if mode == "f" else None, goals)[:, 0]
    answers = literal_answers(values, obstacles, starts, goals, mode)
    assert mismatches(load_planner(NAMES[mode], 64).plan(obstacles, starts, goals), answers) == []


def test_the_searches_expand_fewer_cells_than_the_octile_astar(examples):
    """The authors' claim on their examples: both learned searches expand fewer cells than A* with the plain octile
    heuristic (the cf search with every factor 1), with paths at most a few per cent longer."""
    obstacles, starts, goals, _ = examples
    vanilla = transpath_search(np.ones(obstacles.shape, np.float32), obstacles, starts, goals, "cf")
    for mode in ("cf", "f"):
        result = load_planner(NAMES[mode], 64).plan(obstacles, starts, goals)
        assert (result.expansions < vanilla.expansions).all(), (mode, result.expansions, vanilla.expansions)


def test_without_corner_cutting_the_search_keeps_the_maps_rule():
    """A diagonal between two obstacles is the only way through: cut with corner cutting (the authors' rule), refused
    without it (the goal cannot be reached: `[start]`, step_limit)."""
    obstacles = np.zeros((1, 64, 64), dtype=bool)
    obstacles[0, :32, 32] = True  # a wall down column 32 above row 32, down column 31 below:
    obstacles[0, 32:, 31] = True  # the one way across is the diagonal (31, 31) -> (32, 32) between two obstacles
    starts, goals = np.array([[10, 5]]), np.array([[10, 60]])
    for mode in ("cf", "f"):
        planner = load_planner(NAMES[mode], 64)
        cut = planner.plan(obstacles, starts, goals, corner_cutting=True)
        kept = planner.plan(obstacles, starts, goals, corner_cutting=False)
        assert cut.reached.all() and not kept.reached.any()


def test_the_planners_pass_the_checks_and_declare_what_they_do():
    for mode, name in NAMES.items():
        planner = check_planner(load_planner(name, 64))
        assert isinstance(planner, TransPathPlanner) and planner.moves == "octile"
        assert planner.capabilities.expansions and planner.capabilities.value_maps
        assert planner.capabilities.gradients and not planner.capabilities.policy
        assert planner.checksum == weights_checksum(SHIPPED_WEIGHTS[mode])
        assert planner.spec()["name"] == name and planner.config["mode"] == mode


def test_value_maps_are_minus_the_heuristic_or_the_focal_values():
    maps = generate_maps(2, 64, seed=5, n_starts=1)
    starts = maps.starts[:, 0]
    cf = load_planner("transpath-cf", 64)
    values = cf.value_maps(maps.obstacles, maps.goals)
    assert values.shape == (2, 64, 64) and (values <= 0).all()
    assert values[0][tuple(maps.goals[0])] == 0 and values[1][tuple(maps.goals[1])] == 0
    focal = load_planner("transpath-focal", 64)
    out, _ = focal.outputs(maps.obstacles, starts, maps.goals)
    assert np.array_equal(focal.value_maps(maps.obstacles, maps.goals, starts), out.astype(np.float64))


def test_other_sizes_are_refused_in_one_line():
    for name in NAMES.values():
        with pytest.raises(PlannerError, match="for 64x64 maps only .* not 32x32"):
            load_planner(name, 32)
    planner = load_planner("transpath-cf", 64)
    maps = generate_maps(1, 32, seed=0, n_starts=1)
    with pytest.raises(PlannerError, match="64x64"):
        planner.plan(maps.obstacles, maps.starts, maps.goals)


@pytest.mark.parametrize("mode", ["cf", "f"])
def test_both_modes_equal_the_literal_search_on_generated_maps(mode):
    """Three generated 64x64 maps (vinadv's generator, corner cutting: the authors' rule), one start each: the same
    paths and expanded cells in both modes, no float32 tie met (200 maps: docs/results/transpath_faithfulness.json)."""
    torch.set_num_threads(1)
    maps = generate_maps(3, 64, seed=11, n_starts=1)
    obstacles, starts, goals = maps.obstacles, maps.starts[:, 0], maps.goals
    with torch.no_grad():
        values = plain_forward(state(mode), obstacles, starts if mode == "f" else None, goals)[:, 0]
    answers = literal_answers(values, obstacles, starts, goals, mode)
    assert both_modes_mismatches(values, obstacles, starts, goals, mode, answers) == ([], [])
    assert [ties for _, _, ties in answers] == [0] * 3
