import math

import numpy as np
import pytest
from hypothesis import given, settings
from scipy.spatial.distance import directed_hausdorff

from vinadv.classify.batch import PathPairBatch
from vinadv.classify.similarity import (
    DistanceThresholdClassifier,
    best_threshold,
    dtw_distances,
    frechet_distances,
    hausdorff_distances,
)
from vinadv.errors import InputError

from .oracle import pairs_as_lists, path_pairs


def frechet_oracle(p, q):
    memo = {}

    def c(i, j):
        if (i, j) not in memo:
            d = math.dist(p[i], q[j])
            if i == 0 and j == 0:
                memo[i, j] = d
            elif i == 0:
                memo[i, j] = max(c(0, j - 1), d)
            elif j == 0:
                memo[i, j] = max(c(i - 1, 0), d)
            else:
                memo[i, j] = max(min(c(i - 1, j), c(i - 1, j - 1), c(i, j - 1)), d)
        return memo[i, j]

    return c(len(p) - 1, len(q) - 1)


def dtw_oracle(p, q):
    cost = np.full((len(p) + 1, len(q) + 1), np.inf)
    cost[0, 0] = 0
    for i in range(1, len(p) + 1):
        for j in range(1, len(q) + 1):
            cost[i, j] = math.dist(p[i - 1], q[j - 1]) + min(cost[i - 1, j], cost[i, j - 1], cost[i - 1, j - 1])
    return cost[-1, -1]


@settings(max_examples=60, deadline=None)
@given(path_pairs(max_size=10))
def test_distances_match_references(batch):
    h, f, d = hausdorff_distances(batch), frechet_distances(batch), dtw_distances(batch)
    for i, (o, a, _) in enumerate(pairs_as_lists(batch)):
        ref_h = max(directed_hausdorff(np.array(o), np.array(a))[0], directed_hausdorff(np.array(a), np.array(o))[0])
        assert h[i] == pytest.approx(ref_h)
        assert f[i] == pytest.approx(frechet_oracle(o, a))
        assert d[i] == pytest.approx(dtw_oracle(o, a))


def test_best_threshold_separates_when_possible():
    assert best_threshold([1, 2, 3, 10, 11], [False, False, False, True, True]) == pytest.approx(6.5)
    with pytest.raises(InputError):
        best_threshold([1, 2], [True, True])


def test_distance_classifier_fits_threshold():
    o = [np.array([[5, c] for c in range(10)])] * 2
    near = np.array([[5, 0], [4, 1]] + [[5, c] for c in range(2, 10)])
    far = np.array([[5, 0]] + [[5 - k, k] for k in range(1, 5)] + [[5 - 4 + (k - 4), k] for k in range(5, 10)])
    batch = PathPairBatch.from_paths(o, [near, far], [(5, 9), (5, 9)], 12)
    model = DistanceThresholdClassifier("hausdorff").fit(batch, np.array(["DP", "FP"]))
    assert model.predict(batch).tolist() == ["DP", "FP"]
    assert model.get_params() == {"metric": "hausdorff"}
