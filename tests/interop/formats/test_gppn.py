"""The GPPN layout: drawn starts, GPPN's movement models kept, what vinadv refuses, the policies checked; a file
written the way GPPN's own generator writes it (no border wall, arbitrary actions at the goal) imports."""

from __future__ import annotations

import numpy as np
import pytest

from tests.grid.oracle import brute_distances
from tests.interop.conftest import borderless
from tests.interop.formats.layouts import gppn_arrays, write_gppn, write_gppn_generated
from vinadv.errors import InputError
from vinadv.interop import import_maps, read_maps


def test_gppn_borderless_mazes_get_seeded_starts(tmp_path, small_maps):
    obstacles = borderless(small_maps, seed=1)
    write_gppn(tmp_path / "g.npz", obstacles, small_maps.goals)
    got, info = read_maps(tmp_path / "g.npz", "gppn", starts=4, seed=3)
    again = import_maps(tmp_path / "g.npz", "gppn", starts=4, seed=3)
    np.testing.assert_array_equal(got.starts, again.starts)
    np.testing.assert_array_equal(got.obstacles, obstacles)
    np.testing.assert_array_equal(got.goals, small_maps.goals)
    assert got.moves == info["moves"] == "moore" and info["movement"].startswith("moore")  # GPPN's model, kept
    for i in range(len(got)):
        dist = brute_distances(obstacles[i].tolist(), tuple(got.goals[i]), moves="moore")
        real = [tuple(s) for s in got.starts[i][got.start_mask[i]]]
        assert len(set(real)) == len(real)
        for s, cell in enumerate(real):
            cost, moves = dist[cell]
            assert moves >= 2 and got.expert_costs[i, s] == pytest.approx(cost)


def test_gppn_4_actions_are_news_and_orientations_are_refused(tmp_path, small_maps):
    arrays = gppn_arrays(small_maps.obstacles, small_maps.goals)
    n = small_maps.size
    empty = [np.zeros((0, n, n)), np.zeros((0, 1, n, n)), np.zeros((0, 8, 1, n, n))]
    np.savez(tmp_path / "orient.npz", *empty, *empty, arrays[0], np.repeat(arrays[1], 2, axis=1), arrays[2])
    with pytest.raises(InputError, match="arr_7' has 2 orientations"):
        import_maps(tmp_path / "orient.npz", "gppn")
    np.savez(tmp_path / "five.npz", *empty, *empty, arrays[0], arrays[1], arrays[2][:, :5])
    with pytest.raises(InputError, match=r"'arr_8' has 5 actions, expected 8 \(GPPN's moore\) or 4 \(GPPN's news\)"):
        import_maps(tmp_path / "five.npz", "gppn")


def test_gppn_policy_taking_a_move_that_is_not_optimal_is_refused(tmp_path, small_maps):
    arrays = gppn_arrays(small_maps.obstacles, small_maps.goals)
    empty = [a[:0] for a in arrays]
    # walls, walled-off cells and the goal may hold anything: a one-hot at a wall cell is accepted
    wall = np.argwhere(small_maps.obstacles[0])[0]
    arrays[2][0, :, 0, wall[0], wall[1]] = 0
    arrays[2][0, 0, 0, wall[0], wall[1]] = 1
    np.savez(tmp_path / "ok.npz", *empty, *empty, *arrays)
    assert len(import_maps(tmp_path / "ok.npz", "gppn")) == len(small_maps)
    # a start-able cell next to the border wall whose policy points north, into the wall, is refused
    r, c = 1, int(np.flatnonzero(~small_maps.obstacles[0, 1])[0])
    arrays[2][0, :, 0, r, c] = 0
    arrays[2][0, 0, 0, r, c] = 1  # GPPN index 0 = N
    np.savez(tmp_path / "bad.npz", *empty, *empty, *arrays)
    with pytest.raises(InputError, match=rf"'arr_8' has GPPN action 0 at map 0 cell \(1, {c}\), not an optimal moore"):
        import_maps(tmp_path / "bad.npz", "gppn")


@pytest.mark.parametrize("mechanism", ["moore", "news"])
def test_a_file_written_as_gppns_generator_writes_it_imports_with_its_model(tmp_path, small_maps, mechanism):
    """No border wall, the goal's action arbitrary (often into a wall), walled-off cells arbitrary: imported, the
    maps keep GPPN's model, their expert costs are the model's (a plain Bellman-Ford, tests.grid.oracle)."""
    obstacles = borderless(small_maps, seed=2)
    goals = small_maps.goals
    policies = write_gppn_generated(tmp_path / "g.npz", obstacles, goals, mechanism, seed=4)
    at_goal = policies[np.arange(len(goals)), :, 0, goals[:, 0], goals[:, 1]]
    assert (at_goal.sum(axis=1) == 1).all()  # the generator writes an action at the goal too
    got, info = read_maps(tmp_path / "g.npz", "gppn", starts=3, seed=1)
    assert got.moves == info["moves"] == mechanism and got.corner_cutting
    np.testing.assert_array_equal(got.obstacles, obstacles)
    assert not got.obstacles[:, 0, :].all(axis=1).any()  # no border wall
    for i in range(len(got)):
        dist = brute_distances(obstacles[i].tolist(), tuple(goals[i]), moves=mechanism)
        for s in np.flatnonzero(got.start_mask[i]):
            assert got.expert_costs[i, s] == dist[tuple(got.starts[i, s])][0]
    if mechanism == "moore":  # the user may ask for octile: vinadv's sqrt 2 expert costs, the policy still checked
        octile = import_maps(tmp_path / "g.npz", "gppn", starts=3, seed=1, moves="octile")
        assert octile.moves == "octile"
        i, s = np.argwhere(octile.start_mask)[0]
        want = brute_distances(obstacles[i].tolist(), tuple(goals[i]))[tuple(octile.starts[i, s])][0]
        assert octile.expert_costs[i, s] == pytest.approx(want)
    other = "news" if mechanism == "moore" else "moore"
    with pytest.raises(InputError, match=rf"'arr_8' has {policies.shape[1]} actions \(GPPN's {mechanism}\); moves"):
        import_maps(tmp_path / "g.npz", "gppn", moves=other)
