"""Path-similarity baselines for FP vs DP: Hausdorff, discrete Frechet and DTW distances between the two
paths of each pair (Euclidean distance between cells, in cells), and a classifier that is one threshold on
such a distance fitted on the training set (FP when the distance is above it).

Distances are Numba kernels over packed paths: O(L_o * L_a) per pair, no Python loop per pair.
"""

from __future__ import annotations

import time

import numba
import numpy as np

from vinadv.classify.base import PairClassifier, register_kind
from vinadv.classify.batch import PathPairBatch
from vinadv.errors import InputError


@numba.njit(cache=True, nogil=True)
def _hausdorff_kernel(o_cells, o_off, a_cells, a_off, out):  # pragma: no cover - compiled
    for p in range(len(o_off) - 1):
        best = 0.0
        for side in range(2):
            if side == 0:
                x, x0, x1, y, y0, y1 = o_cells, o_off[p], o_off[p + 1], a_cells, a_off[p], a_off[p + 1]
            else:
                x, x0, x1, y, y0, y1 = a_cells, a_off[p], a_off[p + 1], o_cells, o_off[p], o_off[p + 1]
            for i in range(x0, x1):
                nearest = np.inf
                for j in range(y0, y1):
                    dr = float(x[i, 0] - y[j, 0])
                    dc = float(x[i, 1] - y[j, 1])
                    d = dr * dr + dc * dc
                    if d < nearest:
                        nearest = d
                if nearest > best:
                    best = nearest
        out[p] = np.sqrt(best)


@numba.njit(cache=True, nogil=True)
def _dp_kernel(o_cells, o_off, a_cells, a_off, out, frechet):  # pragma: no cover - compiled
    # one row of the dynamic programme at a time; frechet: max-min coupling, else DTW: sum of distances
    for p in range(len(o_off) - 1):
        n = o_off[p + 1] - o_off[p]
        m = a_off[p + 1] - a_off[p]
        if n == 0 or m == 0:
            out[p] = np.inf
            continue
        prev = np.empty(m)
        cur = np.empty(m)
        for i in range(n):
            for j in range(m):
                dr = float(o_cells[o_off[p] + i, 0] - a_cells[a_off[p] + j, 0])
                dc = float(o_cells[o_off[p] + i, 1] - a_cells[a_off[p] + j, 1])
                d = np.sqrt(dr * dr + dc * dc)
                if i == 0 and j == 0:
                    best = 0.0
                    cur[j] = d
                    continue
                best = np.inf
                if i > 0:
                    best = min(best, prev[j])
                if j > 0:
                    best = min(best, cur[j - 1])
                if i > 0 and j > 0:
                    best = min(best, prev[j - 1])
                cur[j] = max(best, d) if frechet else best + d
            prev, cur = cur, prev
        out[p] = prev[m - 1]


def _kernel_inputs(batch: PathPairBatch):
    return batch.path_o.cells, batch.path_o.offsets, batch.path_a.cells, batch.path_a.offsets


def hausdorff_distances(batch: PathPairBatch) -> np.ndarray:
    """Symmetric Hausdorff distance between the two paths of each pair, `(n,)` float64 (cells)."""
    out = np.zeros(len(batch))
    _hausdorff_kernel(*_kernel_inputs(batch), out)
    return out


def frechet_distances(batch: PathPairBatch) -> np.ndarray:
    """Discrete Frechet distance between the two paths of each pair, `(n,)` float64 (cells)."""
    out = np.zeros(len(batch))
    _dp_kernel(*_kernel_inputs(batch), out, True)
    return out


def dtw_distances(batch: PathPairBatch) -> np.ndarray:
    """Dynamic time warping distance (sum of matched cell distances), `(n,)` float64 (cells)."""
    out = np.zeros(len(batch))
    _dp_kernel(*_kernel_inputs(batch), out, False)
    return out


DISTANCES = {"hausdorff": hausdorff_distances, "frechet": frechet_distances, "dtw": dtw_distances}


def best_threshold(scores: np.ndarray, is_positive: np.ndarray) -> float:
    """The threshold `thr` that maximises the balanced accuracy of `score > thr` on the given data.

    Candidates are midpoints between consecutive distinct scores (and below the smallest); ties go to the
    smallest such threshold.
    """
    scores = np.asarray(scores, dtype=np.float64)
    is_positive = np.asarray(is_positive, dtype=bool)
    n_pos, n_neg = is_positive.sum(), (~is_positive).sum()
    if n_pos == 0 or n_neg == 0:
        raise InputError("fitting a threshold needs training pairs of both classes (FP and DP)")
    order = np.argsort(scores, kind="stable")
    s, pos = scores[order], is_positive[order]
    # threshold after position k (k items at or below it): negatives at or below are right, positives above
    neg_below = np.concatenate([[0], np.cumsum(~pos)])
    pos_above = n_pos - np.concatenate([[0], np.cumsum(pos)])
    balanced = 0.5 * (neg_below / n_neg + pos_above / n_pos)
    # only cut between distinct scores
    valid = np.concatenate([[True], s[1:] != s[:-1], [True]])
    k = int(np.argmax(np.where(valid, balanced, -1.0)))
    if k == 0:
        return float(s[0] - 1.0)
    if k == len(s):
        return float(s[-1])
    return float(0.5 * (s[k - 1] + s[k]))


@register_kind("hausdorff", "frechet", "dtw")
class DistanceThresholdClassifier(PairClassifier):
    """FP vs DP by one path distance: FP when `distance(original, adversarial) > threshold_`.

    `metric`: 'hausdorff', 'frechet' or 'dtw'. `fit` picks the threshold with the best balanced accuracy on the
    training pairs. `decision_function` is `distance - threshold_` (positive = FP).
    """

    def __init__(self, metric: str = "hausdorff"):
        self.metric = metric

    @property
    def kind(self) -> str:
        return self.metric

    def _distance(self, X: PathPairBatch) -> np.ndarray:
        if self.metric not in DISTANCES:
            raise InputError(f"unknown path distance {self.metric!r}; choose from {sorted(DISTANCES)}")
        if not isinstance(X, PathPairBatch):
            raise InputError("path-similarity classifiers need path pairs (a PathPairBatch), not images")
        return DISTANCES[self.metric](X)

    def fit(self, X: PathPairBatch, y) -> DistanceThresholdClassifier:
        y = self._check_y(X, y)
        start = time.perf_counter()
        self.threshold_ = best_threshold(self._distance(X), y == "FP")
        self.training_time_s_ = time.perf_counter() - start
        return self

    def decision_function(self, X: PathPairBatch) -> np.ndarray:
        self._check_fitted("threshold_")
        return self._distance(X) - self.threshold_

    def _state(self):
        self._check_fitted("threshold_")
        return {"threshold": self.threshold_, "training_time_s": self.training_time_s_}, {}

    @classmethod
    def _from_state(cls, kind, params, meta, arrays):
        model = cls(**params)
        model.threshold_ = float(meta["threshold"])
        model.training_time_s_ = float(meta.get("training_time_s", 0.0))
        return model
