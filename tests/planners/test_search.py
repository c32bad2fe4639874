"""The search planner shape (`planners.search`): S starts per map become S rows per map, in order; no logits."""

import numpy as np
import pytest

from vinadv.planners.interface import PlannerError
from vinadv.planners.result import GOAL, STEP_LIMIT, PlanResult
from vinadv.planners.search import SearchPlanner, SearchResult


class Recorder(SearchPlanner):
    """Answers "no path found" (the start alone) and expands exactly its start; records the rows it was asked."""

    name, size = "recorder", 5

    def __init__(self):
        self.calls = []

    def plan_paths(self, obstacles, starts, goals, corner_cutting=True):
        self.calls.append(len(starts))
        paths = [np.array([s]) for s in starts]
        expanded = np.zeros(obstacles.shape, bool)
        expanded[np.arange(len(starts)), starts[:, 0], starts[:, 1]] = True
        term = np.where(np.all(starts == goals, axis=1), GOAL, STEP_LIMIT)
        return SearchResult(paths=PlanResult.from_paths(paths, term).paths, termination=term, expanded=expanded)


def test_plan_plans_start_s_of_map_b_as_row_b_times_s_plus_s_in_chunks_of_maps():
    rng = np.random.default_rng(0)
    b, s = 3, 4
    obstacles = np.zeros((b, 5, 5), bool)
    obstacles[1, 0, 0] = True
    goals = rng.integers(0, 5, (b, 2))
    starts = rng.integers(0, 5, (b, s, 2))
    starts[:, :, 0] = 4  # never the goal (no path is found) nor the obstacle
    goals[:, 0] = 0
    planner = Recorder()
    result = planner.plan(obstacles, starts, goals, chunk_size=2)
    assert planner.calls == [8, 4]  # 2 maps of 4 starts, then the last map's 4
    assert planner.plan(obstacles, starts, goals).termination.tolist() == result.termination.tolist()
    assert planner.calls[2:] == [12]  # a search planner gets every row at once unless told a chunk size
    for row in range(b * s):
        m, k = divmod(row, s)
        assert result.paths[row].tolist() == [starts[m, k].tolist()]
        assert result.termination[row] == STEP_LIMIT
    assert result.expansions.tolist() == [1] * (b * s)
    assert result.take([0, 5]).expanded.shape == (2, 5, 5)


def test_a_search_planner_has_no_logits_and_its_value_map_is_minus_the_cost_to_go():
    planner = Recorder()
    with pytest.raises(PlannerError, match="search planner"):
        planner.logits(np.zeros((1, 5, 5), bool), np.array([[0, 0]]))
    value = planner.value_maps(np.zeros((1, 5, 5), bool), np.array([[0, 0]]))
    assert value[0, 4, 4] == pytest.approx(-4 * np.sqrt(2))  # octile: four diagonal moves
    assert value[0, 0, 3] == pytest.approx(-3)


def test_search_result_refuses_expansions_of_another_row_count():
    paths = PlanResult.from_paths([np.array([[0, 0]])], np.array([GOAL])).paths
    with pytest.raises(Exception, match="expanded"):
        SearchResult(paths=paths, termination=np.array([GOAL]), expanded=np.zeros((2, 5, 5), bool))
