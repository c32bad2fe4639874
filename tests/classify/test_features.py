import numpy as np

from vinadv.classify.batch import PathPairBatch
from vinadv.classify.features import path_features, reaches_goal
from vinadv.grid.paths import PackedPaths


def test_reaches_goal_uses_last_cell():
    paths = PackedPaths.pack([np.array([[0, 0], [1, 1]]), np.zeros((0, 2)), np.array([[1, 1], [0, 0]])])
    assert reaches_goal(paths, [(1, 1), (1, 1), (1, 1)]).tolist() == [True, False, False]


def test_same_paths_compares_order_and_length():
    o = [np.array([[0, 0], [1, 1]]), np.array([[0, 0], [1, 1]]), np.array([[0, 0]]), np.zeros((0, 2))]
    a = [np.array([[0, 0], [1, 1]]), np.array([[1, 1], [0, 0]]), np.array([[0, 0], [0, 1]]), np.zeros((0, 2))]
    assert PackedPaths.pack(o).same_as(PackedPaths.pack(a)).tolist() == [True, False, False, True]


def test_features_are_exclusive_in_design_order():
    goal = (2, 2)
    o_ok = np.array([[0, 0], [1, 1], [2, 2]])
    o_bad = np.array([[0, 0], [1, 1]])
    a_other = np.array([[0, 0], [1, 0], [2, 1], [2, 2]])
    batch = PathPairBatch.from_paths(
        [o_bad, o_bad, o_ok, o_ok, o_ok], [o_bad, a_other, o_bad, o_ok, a_other], [goal] * 5, 4
    )
    f = path_features(batch.path_o, batch.path_a, batch.goals)
    assert f.invalid.tolist() == [True, True, False, False, False]
    assert f.unreached.tolist() == [False, False, True, False, False]
    assert f.unchanged.tolist() == [False, False, False, True, False]
    assert f.rest.tolist() == [False, False, False, False, True]
