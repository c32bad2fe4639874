import numpy as np
import pytest

from tests.classify.test_harm import dijkstra, optimal_path
from vinadv.errors import InputError
from vinadv.grid import generate_maps, generator, obstacle_fraction, shortest_distances
from vinadv.grid.generator import _paint_shapes


@pytest.fixture(scope="module")
def maps28():
    return generate_maps(600, 28, seed=11)


def test_obstacle_fraction_at_28_is_about_30_percent(maps28):
    assert 0.25 <= obstacle_fraction(maps28.obstacles) <= 0.35


def test_maps_have_border_free_interior_goal_and_good_starts(maps28):
    obs = maps28.obstacles
    assert obs[:, 0].all() and obs[:, -1].all() and obs[:, :, 0].all() and obs[:, :, -1].all()
    n = len(maps28)
    goals = maps28.goals
    assert ((goals >= 1) & (goals <= 26)).all()
    assert not obs[np.arange(n), goals[:, 0], goals[:, 1]].any()
    starts = maps28.starts
    assert starts.shape == (n, 7, 2)
    assert not obs[np.arange(n)[:, None], starts[..., 0], starts[..., 1]].any()
    flat = starts[..., 0] * 28 + starts[..., 1]
    assert all(len(set(row)) == 7 for row in flat.tolist())  # distinct starts
    _, moves = shortest_distances(obs, goals)
    start_moves = moves[np.arange(n)[:, None], starts[..., 0], starts[..., 1]]
    assert (start_moves >= 2).all()
    # expert paths have exactly the optimal number of moves
    np.testing.assert_array_equal(maps28.expert.lengths - 1, start_moves.ravel())


def test_same_seed_same_maps_and_prefix_stable():
    a = generate_maps(700, 16, seed=5, n_starts=3)
    b = generate_maps(700, 16, seed=5, n_starts=3)
    c = generate_maps(100, 16, seed=5, n_starts=3)
    for field in ("obstacles", "goals", "starts", "expert_costs"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert a.expert == b.expert
    np.testing.assert_array_equal(a.obstacles[:100], c.obstacles)
    np.testing.assert_array_equal(a.starts[:100], c.starts)
    d = generate_maps(100, 16, seed=6, n_starts=3)
    assert not np.array_equal(c.obstacles, d.obstacles)


@pytest.mark.parametrize("size", [8, 16, 28, 33])
def test_sizes(size):
    maps = generate_maps(50, size, seed=0)
    assert maps.obstacles.shape == (50, size, size)
    assert len(maps) == 50 and maps.size == size


def test_bad_arguments_are_input_errors():
    # the library names its parameters (the CLI shows them as flags: tests/commands/test_errors.py)
    with pytest.raises(InputError, match="^size must be >= 8") as exc:
        generate_maps(5, 6)
    assert exc.value.parameters == ("size",)
    with pytest.raises(InputError, match="^n must be >= 0"):
        generate_maps(-1)
    with pytest.raises(InputError, match="^n_starts must be >= 1"):
        generate_maps(3, 8, n_starts=0)


@pytest.mark.parametrize("moves", ["octile", "news"])
def test_starts_past_the_cells_a_start_can_be_on_are_refused_before_any_map(moves, monkeypatch):
    """34 starts on 8x8 maps (36 interior cells, the goal and at least two cells one move from it) drew 32,768 maps
    before giving up; 10**9 starts are refused as well, never allocated. Checked before any chunk is made."""

    def no_chunk(*args, **kwargs):
        raise AssertionError("a chunk was generated")

    monkeypatch.setattr(generator, "_generate_chunk", no_chunk)
    for n_starts in (34, 10**9):
        with pytest.raises(InputError, match=f"^n_starts {n_starts}: a 8x8 map has at most 33 cells a start") as exc:
            generate_maps(2, 8, n_starts=n_starts, moves=moves)
        assert exc.value.parameters == ("n_starts",)
    monkeypatch.undo()
    assert generator.start_cells(8) == 33 and generator.start_cells(28) == 673


def _shapes_by_testing_every_cell(attempts, is_disc, top, left, height, width, radius, goals, size):
    """The placement as first written: every attempt tested against every cell, `(n, max_obs, N, N)` at once."""
    rows = np.arange(size)[None, None, :, None]
    cols = np.arange(size)[None, None, None, :]
    t, lft = top[..., None, None], left[..., None, None]
    rect = (rows >= t) & (rows < t + height[..., None, None]) & (cols >= lft) & (cols < lft + width[..., None, None])
    disc = (rows - t) ** 2 + (cols - lft) ** 2 <= radius[..., None, None] ** 2
    shapes = np.where(is_disc[..., None, None], disc, rect)
    shapes &= (np.arange(top.shape[1])[None, :] < attempts[:, None])[..., None, None]
    shapes &= ~shapes[np.arange(len(goals)), :, goals[:, 0], goals[:, 1]][..., None, None]
    return shapes.any(axis=1)


@pytest.mark.parametrize("size, max_obs, max_size", [(9, 12, 4), (28, 50, 2), (16, 30, 7)])
def test_painted_shapes_equal_testing_every_cell(size, max_obs, max_size):
    rng = np.random.default_rng(size)
    n = 300
    draws = dict(
        attempts=rng.integers(1, max_obs, n, endpoint=True),
        is_disc=rng.random((n, max_obs)) < 0.5,
        top=rng.integers(0, size, (n, max_obs)),
        left=rng.integers(0, size, (n, max_obs)),
        height=rng.integers(1, max_size, (n, max_obs), endpoint=True),
        width=rng.integers(1, max_size, (n, max_obs), endpoint=True),
        radius=rng.integers(1, max_size, (n, max_obs), endpoint=True),
        goals=rng.integers(0, size, (n, 2)),
    )
    painted = np.zeros((n, size, size), dtype=bool)
    _paint_shapes(*draws.values(), painted)
    expected = _shapes_by_testing_every_cell(*draws.values(), size)
    assert np.array_equal(painted, expected)
    assert not painted[np.arange(n), draws["goals"][:, 0], draws["goals"][:, 1]].any()


@pytest.mark.parametrize("moves", ["octile", "moore", "news"])
def test_expert_costs_and_paths_of_each_model_match_a_plain_python_dijkstra(moves):
    """The generator's expert costs are a heapq Dijkstra's over the model's moves and costs (tests.classify.test_harm,
    written from DESIGN.md), and its expert paths are the lowest-index optimal paths of that oracle."""
    maps = generate_maps(6, 10, seed=8, n_starts=3, moves=moves)
    for i in range(len(maps)):
        rows = maps.obstacles[i].tolist()
        dist = dijkstra(rows, tuple(maps.goals[i]), True, moves)
        for s in range(maps.n_starts):
            start = tuple(maps.starts[i, s])
            assert maps.expert_costs[i, s] == pytest.approx(dist[start], abs=1e-12)
            assert maps.expert_path(i, s).tolist() == [
                list(c) for c in optimal_path(rows, start, tuple(maps.goals[i]), True, moves)
            ]
