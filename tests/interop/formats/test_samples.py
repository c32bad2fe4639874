"""What the layouts share: the file's optimal paths kept, padded maps through export, import and evaluation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.interop.formats.layouts import assert_same_maps, trajectories, write_kentsommer
from vinadv.errors import InputError
from vinadv.evaluation.planner_metrics import evaluate_vin
from vinadv.grid import MapSet, PackedPaths
from vinadv.interop import export_maps, import_maps, read_maps
from vinadv.planners.vin.reference import plan_reference
from vinadv.testing.planners import planning_vin


def test_the_files_optimal_paths_are_kept_and_others_replaced(tmp_path):
    # 5x5 rooms, from (3, 1) to the goal (1, 3). Map 0: the file's N,N,E,E costs 4, not optimal (NE,NE costs
    # 2 sqrt 2): replaced. Map 1, centre blocked: the file's E,NE,N is optimal (2 + sqrt 2), and vinadv's tie-break
    # (lowest action index first) would take N,NE,E instead: kept as the file has it.
    obstacles = np.zeros((2, 5, 5), bool)
    obstacles[:, [0, -1], :] = obstacles[:, :, [0, -1]] = True
    obstacles[1, 2, 2] = True  # the diagonal is blocked on map 1: the optimal paths cost 2 + sqrt 2
    goals = np.array([[1, 3], [1, 3]])
    maps = MapSet(
        obstacles=obstacles,
        goals=goals,
        starts=np.zeros((2, 0, 2), int),
        expert_costs=np.zeros((2, 0)),
        expert=PackedPaths.empty(),
    )
    detour = [(3, 1), (2, 1), (1, 1), (1, 2), (1, 3)]
    optimal_1 = [(3, 1), (3, 2), (2, 3), (1, 3)]  # E, NE, N on map 1: 2 + sqrt 2
    write_kentsommer(tmp_path / "k.npz", maps, [], [(0, detour), (1, optimal_1)])
    got, info = read_maps(tmp_path / "k.npz", "kentsommer")
    assert info["file_paths_optimal"] == 1
    np.testing.assert_array_equal(got.expert_path(0), [(3, 1), (2, 2), (1, 3)])  # replaced by vinadv's
    np.testing.assert_array_equal(got.expert_path(1), optimal_1)  # kept
    assert got.expert_costs[0, 0] == pytest.approx(2 * math.sqrt(2))
    assert got.expert_costs[1, 0] == pytest.approx(2 + math.sqrt(2))


def test_padded_maps_survive_export_and_import(tmp_path, small_maps):
    keep = {0: 1, 7: 2}
    write_kentsommer(tmp_path / "k.npz", small_maps, [], trajectories(small_maps, lambda i, s: s < keep.get(i, 3)))
    padded = import_maps(tmp_path / "k.npz", "kentsommer")
    for fmt, name in (("kentsommer", "k2.npz"), ("avivt", "a.mat")):
        export_maps(padded, tmp_path / name, fmt)
        back = import_maps(tmp_path / name, fmt)
        np.testing.assert_array_equal(back.start_counts, padded.start_counts)
        assert_same_maps(back, padded, counts=padded.start_counts)


def test_evaluation_leaves_padded_starts_out(tmp_path, small_maps):
    keep = {1: 1, 4: 2, 9: 1}
    write_kentsommer(tmp_path / "k.npz", small_maps, [], trajectories(small_maps, lambda i, s: s < keep.get(i, 3)))
    padded = import_maps(tmp_path / "k.npz", "kentsommer")
    model = planning_vin(10, seed=2)
    metrics = evaluate_vin(model, padded)
    real = [(i, s) for i in range(len(padded)) for s in range(keep.get(i, 3))]
    assert metrics["rollouts"] == len(real) == sum(metrics["terminations"].values())
    idx = np.array([i for i, _ in real])
    ref = plan_reference(
        padded.obstacles[idx], np.array([padded.starts[i, s] for i, s in real]), padded.goals[idx], model
    )
    assert metrics["success_rate"] == pytest.approx(ref.reached.mean())


def test_start_counts_field_is_validated(tmp_path, small_maps):
    maps = MapSet(**{**small_maps.__dict__, "start_counts": np.full(len(small_maps), 4)})
    maps.save(tmp_path / "m.npz")
    with pytest.raises(InputError, match=r"field 'start_counts' has a count outside 1\.\.3"):
        MapSet.load(tmp_path / "m.npz")
    data = dict(np.load(tmp_path / "m.npz"))
    data["start_counts"] = data["start_counts"][:3]
    np.savez(tmp_path / "short.npz", **data)
    with pytest.raises(InputError, match="field 'start_counts' has shape"):
        MapSet.load(tmp_path / "short.npz")
