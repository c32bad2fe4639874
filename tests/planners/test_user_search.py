"""Bring-your-own search planners (`FILE.py:FACTORY` returning an object with `plan_paths`): the shipped example
against a plain breadth-first search, and every check of `check_paths` refusing its own kind of bad answer."""

from collections import deque
from pathlib import Path

import numpy as np
import pytest

from tests.grid.oracle import DELTAS, legal
from vinadv.grid import generate_maps
from vinadv.planners.interface import PlannerError
from vinadv.planners.registry import PlannerRef, load_planner
from vinadv.planners.result import COLLISION, GOAL, STEP_LIMIT
from vinadv.planners.search import SearchResult, UserSearchPlanner, check_paths

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "my_search_planner.py"
SIZE = 8


def bfs_moves(obstacles, start, goal, corner_cutting=True):
    """Fewest moves from start to goal (None if unreachable), and the cells a level-by-level search took off its
    queue before the goal's level: plain Python from the oracle's move rule."""
    depth = {tuple(start): 0}
    queue = deque([tuple(start)])
    while queue:
        r, c = queue.popleft()
        for a, (dr, dc) in enumerate(DELTAS):
            nxt = (r + dr, c + dc)
            if nxt not in depth and legal(obstacles, r, c, a, corner_cutting):
                depth[nxt] = depth[(r, c)] + 1
                queue.append(nxt)
    g = depth.get(tuple(goal))
    return g, {cell for cell, d in depth.items() if g is None or d < g}


@pytest.fixture(scope="module")
def maps():
    return generate_maps(10, SIZE, seed=4, n_starts=3)


@pytest.mark.parametrize("corner_cutting", [True, False])
def test_the_example_finds_fewest_move_paths_and_reports_its_expansions(maps, corner_cutting):
    planner = load_planner(f"{EXAMPLE}:make", SIZE)
    assert isinstance(planner, UserSearchPlanner)
    result = planner.plan(maps.obstacles, maps.starts, maps.goals, corner_cutting)
    obstacles = maps.obstacles.tolist()
    for row in range(len(result)):
        m, s = divmod(row, 3)
        if not maps.start_mask[m, s]:
            continue
        fewest, expanded = bfs_moves(obstacles[m], maps.starts[m, s], maps.goals[m], corner_cutting)
        assert len(result.paths[row]) - 1 == fewest
        assert result.termination[row] == GOAL
        assert {tuple(c) for c in np.argwhere(result.expanded[row]).tolist()} == expanded


def test_the_example_says_no_path_where_the_goal_is_walled_off():
    obstacles = np.zeros((1, 5, 5), bool)
    obstacles[0, :, 2] = True
    result = load_planner(f"{EXAMPLE}:make", 5).plan(obstacles, np.array([[0, 0]]), np.array([[0, 4]]))
    assert result.paths[0].tolist() == [[0, 0]] and result.termination_names.tolist() == ["step_limit"]
    assert result.expansions.tolist() == [10]  # the two columns left of the wall


class Answers:
    """A user's planner that answers what it is told to (the paths or result of `answer(obstacles, starts, goals)`)."""

    def __init__(self, answer, **attrs):
        self.answer = answer
        self.__dict__.update(attrs)

    def plan_paths(self, obstacles, starts, goals, corner_cutting=True):
        return self.answer(obstacles, starts, goals)


def straight(obstacles, starts, goals):
    """From (1, 1) east along row 1 to the goal (1, 4) on an empty 6x6 map: a legal path."""
    return [np.array([[1, c] for c in range(s[1], g[1] + 1)]) for s, g in zip(starts, goals, strict=True)]


def run(answer, obstacles=None, **attrs):
    planner = UserSearchPlanner(Answers(answer, **attrs), "mine.py:make", 6)
    obstacles = np.zeros((2, 6, 6), bool) if obstacles is None else obstacles
    return planner.plan(obstacles, np.array([[1, 1], [1, 1]]), np.array([[1, 4], [1, 4]]))


def test_a_legal_answer_passes_and_gets_its_terminations():
    result = run(straight)
    assert result.reached.all() and result.paths[0].tolist() == [[1, 1], [1, 2], [1, 3], [1, 4]]
    assert result.expanded is None and result.expansions is None


BAD = {
    "not paths": (lambda o, s, g: "a path", r"returned str; expected a SearchResult or a list of B"),
    "too few rows": (lambda o, s, g: straight(o, s, g)[:1], r"returned 1 paths for 2 rows"),
    "empty path": (lambda o, s, g: [np.zeros((0, 2), int), *straight(o, s, g)[1:]], r"an empty path for row 0"),
    "not cells": (lambda o, s, g: [np.array([1, 2, 3]), np.array([[1, 1]])], r"paths that are not \(L, 2\)"),
    "off the grid": (
        lambda o, s, g: [np.array([[1, 1], [1, 2]]), np.array([[1, 1], [1, 6], [1, 7]])],
        r"cell \(1, 6\) outside the 6x6 grid \(row 1\)",
    ),
    "wrong start": (
        lambda o, s, g: [np.array([[2, 1], [1, 2]]), np.array([[1, 1]])],
        r"a path for row 0 that starts at \(2, 1\), not at its start \(1, 1\)",
    ),
    "jump": (
        lambda o, s, g: [np.array([[1, 1], [1, 3], [1, 4]]), np.array([[1, 1]])],
        r"moves from \(1, 1\) to \(1, 3\), not one legal move \(octile",
    ),
    "stays put": (
        lambda o, s, g: [np.array([[1, 1], [1, 1], [1, 2]]), np.array([[1, 1]])],
        r"moves from \(1, 1\) to \(1, 1\)",
    ),
    "into an obstacle": (lambda o, s, g: straight(o, s, g), r"row 1 that moves from \(1, 2\) to \(1, 3\)"),
    "a diagonal on news maps": (
        lambda o, s, g: [np.array([[1, 1], [2, 2]]), np.array([[1, 1]])],
        r"moves from \(1, 1\) to \(2, 2\), not one legal move \(news",
    ),
    "goal claimed, not reached": (
        lambda o, s, g: SearchResult(
            paths=SearchResult.from_paths([[[1, 1]], [[1, 1]]], g).paths, termination=np.array([GOAL, STEP_LIMIT])
        ),
        r"termination 'goal' for row 0, whose path ends at \(1, 1\) with the goal at \(1, 4\)",
    ),
    "goal reached, not claimed": (
        lambda o, s, g: SearchResult(
            paths=SearchResult.from_paths(straight(o, s, g), g).paths, termination=np.array([GOAL, COLLISION])
        ),
        r"termination 'collision' for row 1, whose path ends at \(1, 4\)",
    ),
    "unknown termination": (
        lambda o, s, g: SearchResult(
            paths=SearchResult.from_paths(straight(o, s, g), g).paths, termination=np.array([GOAL, 9])
        ),
        r"termination code 9 for row 1",
    ),
    "expansions of another shape": (
        lambda o, s, g: SearchResult.from_paths(straight(o, s, g), g, expanded=np.zeros((2, 5, 5), bool)),
        r"expansions of shape \(2, 5, 5\) and dtype bool; expected \(2, 6, 6\) bool",
    ),
    # cells checked in their own dtype before int16: a column 65536 past a legal one never wraps into the grid, a
    # float is never truncated, and expansions are a 0/1 mask (a NaN is not an expanded cell)
    "a cell that int16 wraps": (
        lambda o, s, g: [np.array([[1, 1], [1, 2 + 65536], [1, 3], [1, 4]]), *straight(o, s, g)[1:]],
        r"paths that are not \(L, 2\) integer cells: cells hold 65538, outside -32768\.\.32767",
    ),
    "a wrapped cell in a result": (
        lambda o, s, g: SearchResult.from_paths(
            [np.array([[1, 1], [1, 2 - 65536], [1, 3], [1, 4]]), *straight(o, s, g)[1:]], g
        ),
        r"plan_paths failed: InputError: cells hold -65534, outside -32768\.\.32767",
    ),
    "a float cell": (
        lambda o, s, g: [np.array([[1, 1], [1, 2.7], [1, 3], [1, 4]]), *straight(o, s, g)[1:]],
        r"cells hold 2\.7, not a whole number",
    ),
    "a NaN cell": (
        lambda o, s, g: [np.array([[1, 1], [np.nan, 2], [1, 3], [1, 4]]), *straight(o, s, g)[1:]],
        r"cells hold nan, not a whole number",
    ),
    "NaN expansions": (
        lambda o, s, g: SearchResult.from_paths(straight(o, s, g), g, expanded=np.full((2, 6, 6), np.nan)),
        r"expanded holds nan \(72 cells\); expected a mask",
    ),
    "expansions that are counts": (
        lambda o, s, g: SearchResult.from_paths(straight(o, s, g), g, expanded=np.full((2, 6, 6), -1)),
        r"expanded holds -1 \(72 cells\)",
    ),
    "raises": (lambda o, s, g: 1 / 0, r"planner 'mine.py:make': plan_paths failed: ZeroDivisionError"),
    "exits": (lambda o, s, g: exit(3), r"planner 'mine.py:make': plan_paths failed: SystemExit: 3"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_each_bad_answer_is_refused_in_one_line_naming_the_planner(case):
    answer, message = BAD[case]
    obstacles = np.zeros((2, 6, 6), bool)
    attrs = {}
    if case == "into an obstacle":
        obstacles[1, 1, 3] = True
    if case == "a diagonal on news maps":
        attrs["moves"] = "news"
    with pytest.raises(PlannerError, match=message) as info:
        run(answer, obstacles, **attrs)
    text = str(info.value)
    assert "\n" not in text and "mine.py:make" in text


def test_a_diagonal_between_two_obstacles_is_refused_without_corner_cutting():
    obstacles = np.zeros((1, 6, 6), bool)
    obstacles[0, 1, 2] = obstacles[0, 2, 1] = True
    path = [np.array([[1, 1], [2, 2]])]
    args = (obstacles, np.array([[1, 1]]), np.array([[2, 2]]))
    assert check_paths("p", path, *args, corner_cutting=True).reached.all()
    with pytest.raises(PlannerError, match="no corner cutting"):
        check_paths("p", path, *args, corner_cutting=False)


def test_a_user_planner_of_another_movement_model_is_refused_and_a_bad_model_named():
    planner = UserSearchPlanner(Answers(straight, moves="moore"), "mine.py:make", 6)
    assert planner.for_moves("moore") is planner
    with pytest.raises(PlannerError, match="plans moore moves"):
        planner.for_moves("octile")
    with pytest.raises(PlannerError, match="its moves 'hex' is not a movement model"):
        UserSearchPlanner(Answers(straight, moves="hex"), "mine.py:make", 6)


def test_a_factory_that_fails_or_a_file_that_exits_is_one_line(tmp_path):
    (tmp_path / "exits.py").write_text("import sys\nsys.exit(4)\n")
    (tmp_path / "fails.py").write_text("def make(size):\n    raise RuntimeError('no GPU')\n")
    with pytest.raises(PlannerError, match=r"exits.py failed to import: SystemExit: 4"):
        load_planner(f"{tmp_path / 'exits.py'}:make", 6)
    with pytest.raises(PlannerError, match=r"make\(6\) failed: RuntimeError: no GPU"):
        load_planner(f"{tmp_path / 'fails.py'}:make", 6)


def test_a_file_search_planner_travels_by_reference_and_records_its_source(tmp_path):
    planner = load_planner(f"{EXAMPLE}:make", SIZE)
    spec = planner.spec()
    assert spec["weights_sha256"] is None and len(spec["config"]["source_sha256"]) == 64
    ref = PlannerRef.of(planner, f"{EXAMPLE}:make", None, True)
    again = ref.load()
    assert isinstance(again, UserSearchPlanner) and again.spec() == spec


def test_a_user_value_map_is_used_and_checked():
    own = Answers(straight, value_maps=lambda obstacles, goals: np.ones(obstacles.shape))
    planner = UserSearchPlanner(own, "mine.py:make", 6)
    assert (planner.value_maps(np.zeros((2, 6, 6), bool), np.array([[1, 4], [1, 4]])) == 1).all()
    bad = UserSearchPlanner(Answers(straight, value_maps=lambda o, g: np.ones((1, 6))), "mine.py:make", 6)
    with pytest.raises(PlannerError, match=r"value maps of shape \(1, 6\)"):
        bad.value_maps(np.zeros((2, 6, 6), bool), np.array([[1, 4], [1, 4]]))


def test_a_search_planner_has_no_policy_to_average_or_to_read_per_cell(maps):
    with pytest.raises(PlannerError, match=r"declares no policy \(a search planner\); \+d4 averages a policy"):
        load_planner(f"{EXAMPLE}:make+d4", SIZE)
    from vinadv.evaluation.protocols import gppn_protocol, planner_actions  # noqa: PLC0415 (PyTorch: this test only)

    planner = load_planner(f"{EXAMPLE}:make", SIZE)
    with pytest.raises(PlannerError, match="the gppn protocol follows a policy from every cell"):
        gppn_protocol(planner, maps)
    with pytest.raises(PlannerError, match="needs a policy planner"):
        planner_actions(planner, maps.obstacles, maps.goals)


@pytest.mark.parametrize(
    ("moves", "corner_cutting"),
    [("octile", True), ("octile", False), ("moore", True), ("moore", False), ("news", True)],  # news cuts no corner
)
def test_the_move_check_agrees_with_the_oracle_s_move_rule_for_every_step(moves, corner_cutting):
    """Every step from every free cell of a random 5x5 map to each of its 3x3 neighbourhood (staying put included):
    accepted exactly where the oracle's `legal` says it is one legal move."""
    rng = np.random.default_rng(7)
    obstacles = rng.random((1, 5, 5)) < 0.35
    for r, c in np.argwhere(~obstacles[0]).tolist():
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                dst = (r + dr, c + dc)
                if not (0 <= dst[0] < 5 and 0 <= dst[1] < 5):
                    continue
                expected = (dr, dc) in DELTAS and legal(
                    obstacles[0].tolist(), r, c, DELTAS.index((dr, dc)), corner_cutting, moves
                )
                args = ([np.array([[r, c], dst])], obstacles, np.array([[r, c]]), np.array([[0, 0]]))
                try:
                    check_paths("p", *args, corner_cutting=corner_cutting, moves=moves)
                    accepted = True
                except PlannerError:
                    accepted = False
                assert accepted == expected, (r, c, dr, dc)


def test_expansions_as_a_0_1_number_mask_are_counted_as_the_bool_mask():
    expanded = np.zeros((2, 6, 6))
    expanded[:, 1, 1:5] = 1.0
    result = run(lambda o, s, g: SearchResult.from_paths(straight(o, s, g), g, expanded=expanded))
    assert result.expanded.dtype == bool and result.expansions.tolist() == [4, 4]


def test_a_user_planner_that_declares_start_values_gets_the_starts_and_one_that_does_not_never_does():
    class Reads:
        capabilities = {"start_values": True}

        def plan_paths(self, obstacles, starts, goals, corner_cutting=True):
            return [np.array([s]) for s in starts]

        def value_maps(self, obstacles, goals, starts=None):
            self.got = starts
            return np.zeros(obstacles.shape)

    class Ignores(Reads):
        capabilities = {}

        def value_maps(self, obstacles, goals):  # two arguments: never given the starts
            return np.ones(obstacles.shape)

    obstacles, goals, starts = np.zeros((2, 6, 6), bool), np.array([[1, 4], [1, 4]]), np.array([[0, 0], [5, 5]])
    reads = UserSearchPlanner(Reads(), "reads", 6)
    assert reads.capabilities.start_values
    reads.value_maps(obstacles, goals, starts)
    assert np.array_equal(reads.impl.got, starts)
    ignores = UserSearchPlanner(Ignores(), "ignores", 6)
    assert not ignores.capabilities.start_values
    assert (ignores.value_maps(obstacles, goals, starts) == 1).all()
