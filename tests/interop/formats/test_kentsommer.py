"""The kentsommer layout: samples regrouped into maps and trajectories, padding."""

from __future__ import annotations

import numpy as np
import pytest

from tests.interop.formats.layouts import assert_same_maps, trajectories, write_kentsommer
from vinadv.grid import MapSet, PackedPaths, generate_maps
from vinadv.interop import import_maps, read_maps


@pytest.mark.parametrize("prior", [0.0, -1.0])
def test_kentsommer_samples_regroup_into_maps_and_trajectories(tmp_path, small_maps, prior):
    train = trajectories(small_maps, keep=lambda i, s: i < 4)
    test = trajectories(small_maps, keep=lambda i, s: i >= 4)
    write_kentsommer(tmp_path / "k.npz", small_maps, train, test, prior)
    got, info = read_maps(tmp_path / "k.npz", "kentsommer", split="test")
    assert info["maps"] == 8 and info["trajectories"] == 8 * 3 and got.start_counts is None
    assert info["file_paths_optimal"] == 24
    rest = generate_maps(12, 10, seed=5, n_starts=3)
    idx = np.arange(4, 12)
    want = MapSet(
        obstacles=rest.obstacles[idx],
        goals=rest.goals[idx],
        starts=rest.starts[idx],
        expert_costs=rest.expert_costs[idx],
        expert=rest.expert,
    )
    assert_same_maps(got, want)
    everything = import_maps(tmp_path / "k.npz", "kentsommer", split="all")
    assert_same_maps(everything, small_maps)


def test_kentsommer_maps_with_fewer_trajectories_are_padded_not_dropped(tmp_path, small_maps):
    # map 2 keeps 1 trajectory, map 5 two, the others 3
    keep = {2: 1, 5: 2}
    trajs = trajectories(small_maps, keep=lambda i, s: s < keep.get(i, 3))
    write_kentsommer(tmp_path / "k.npz", small_maps, [], trajs)
    got, info = read_maps(tmp_path / "k.npz", "kentsommer")
    counts = [keep.get(i, 3) for i in range(len(small_maps))]
    assert info["maps_padded"] == 2 and got.n_starts == 3
    assert_same_maps(got, small_maps, counts=counts)
    np.testing.assert_array_equal(got.start_counts, counts)
    # padding is explicit: the goal, cost 0, and kept through save/load
    np.testing.assert_array_equal(got.starts[2, 1], got.goals[2])
    assert got.expert_costs[2, 1] == 0
    got.save(tmp_path / "m.npz")
    np.testing.assert_array_equal(MapSet.load(tmp_path / "m.npz").start_counts, counts)


def walled_map_without_starts() -> MapSet:
    """One free 6x6 map inside a border wall, goal (1, 4), no starts: the trajectories written give them."""
    obstacles = np.zeros((1, 6, 6), bool)
    obstacles[0, [0, -1], :] = obstacles[0, :, [0, -1]] = True
    return MapSet(
        obstacles=obstacles,
        goals=np.array([[1, 4]]),
        starts=np.zeros((1, 0, 2), int),
        expert_costs=np.zeros((1, 0)),
        expert=PackedPaths.empty(),
    )


def test_kentsommer_consecutive_trajectories_are_split_by_the_move_rule(tmp_path):
    # two trajectories on one map where the second starts next to where the first one was: only the labelled
    # move decides where a trajectory ends
    maps = walled_map_without_starts()
    trajs = [(0, [(4, 1), (3, 2), (2, 3), (1, 4)]), (0, [(3, 1), (2, 2), (1, 3), (1, 4)])]
    write_kentsommer(tmp_path / "k.npz", maps, [], trajs)
    got = import_maps(tmp_path / "k.npz", "kentsommer")
    np.testing.assert_array_equal(got.starts[0], [[4, 1], [3, 1]])


def test_kentsommer_a_repeated_start_is_dropped_and_the_file_loads(tmp_path):
    # the file's generator may start two trajectories of a map on one cell: the maps file keeps the first (a maps
    # file's starts differ; before, the import wrote a file that MapSet.load refused)
    maps = walled_map_without_starts()
    path = [(4, 1), (3, 2), (2, 3), (1, 4)]
    trajs = [(0, path), (0, [(3, 1), (2, 2), (1, 3), (1, 4)]), (0, [(4, 1), (3, 1), (2, 2), (1, 3), (1, 4)])]
    write_kentsommer(tmp_path / "k.npz", maps, [], trajs)
    got, info = read_maps(tmp_path / "k.npz", "kentsommer")
    assert info["trajectories"] == 2 and info["trajectories_repeated_start"] == 1
    np.testing.assert_array_equal(got.starts[0], [[4, 1], [3, 1]])
    np.testing.assert_array_equal(got.expert_path(0, 0), path)  # the first trajectory's path, not the repeat's
    got.save(tmp_path / "m.npz")
    np.testing.assert_array_equal(MapSet.load(tmp_path / "m.npz").starts, got.starts)
