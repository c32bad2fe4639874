import numpy as np
import pytest

from vinadv.errors import InputError
from vinadv.grid import generate_maps, obstacle_fraction, shortest_distances


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
