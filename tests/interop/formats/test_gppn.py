"""The GPPN layout: drawn starts, what vinadv refuses, the policies checked."""

from __future__ import annotations

import numpy as np
import pytest

from tests.grid.oracle import brute_distances
from tests.interop.conftest import borderless
from tests.interop.formats.layouts import gppn_arrays, write_gppn
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
    assert "sqrt 2" in info["movement"]
    for i in range(len(got)):
        dist = brute_distances(obstacles[i].tolist(), tuple(got.goals[i]))
        real = [tuple(s) for s in got.starts[i][got.start_mask[i]]]
        assert len(set(real)) == len(real)
        for s, cell in enumerate(real):
            cost, moves = dist[cell]
            assert moves >= 2 and got.expert_costs[i, s] == pytest.approx(cost)


def test_gppn_4_actions_and_orientations_are_refused(tmp_path, small_maps):
    arrays = gppn_arrays(small_maps.obstacles, small_maps.goals)
    n = small_maps.size
    empty = [np.zeros((0, n, n)), np.zeros((0, 1, n, n)), np.zeros((0, 8, 1, n, n))]
    np.savez(tmp_path / "news.npz", *empty, *empty, arrays[0], arrays[1], arrays[2][:, :4])
    with pytest.raises(InputError, match=r"news\.npz: array 'arr_8' has 4 actions.*8 moves"):
        import_maps(tmp_path / "news.npz", "gppn")
    np.savez(tmp_path / "orient.npz", *empty, *empty, arrays[0], np.repeat(arrays[1], 2, axis=1), arrays[2])
    with pytest.raises(InputError, match="arr_7' has 2 orientations"):
        import_maps(tmp_path / "orient.npz", "gppn")


def test_gppn_policy_taking_illegal_moves_is_refused(tmp_path, small_maps):
    arrays = gppn_arrays(small_maps.obstacles, small_maps.goals)
    empty = [a[:0] for a in arrays]
    # walls and walled-off cells may hold anything: a one-hot at a wall cell is accepted
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
    with pytest.raises(InputError, match="'arr_8' takes an action into a wall"):
        import_maps(tmp_path / "bad.npz", "gppn")
