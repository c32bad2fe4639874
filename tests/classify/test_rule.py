import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vinadv.classify.batch import PathPairBatch
from vinadv.classify.rule import default_threshold, label_batch, label_pairs, path_distances
from vinadv.errors import InputError
from vinadv.grid.paths import PackedPaths

from .oracle import pairs_as_lists, path_pairs, rule_oracle


def one(o, a, goal=None, size=28, t=None):
    goal = o[-1] if goal is None else goal
    batch = PathPairBatch.from_paths([np.array(o)], [np.array(a)], [goal], size)
    result = label_batch(batch, t)
    return str(result.labels[0]), int(result.dh[0]), int(result.dv[0])


def row6(a):
    """The straight original path along row 6 under the detour `a` (same start and goal)."""
    return [(6, c) for c in range(1, a[-1][1] + 1)]


def arch(height_row):
    """Row-6 path with a trapezoid detour whose top is on row `height_row` (shared prefix and suffix)."""
    up = list(range(5, height_row - 1, -1))  # rows climbed diagonally
    path = [(6, 1)]
    col = 2
    for r in up:
        path.append((r, col))
        col += 1
    path.append((height_row, col))
    col += 1
    for r in reversed(up):
        path.append((r, col))
        col += 1
    return path + [(6, c) for c in range(col, col + 3)]


def test_default_threshold_scales_with_size():
    assert default_threshold(28) == 4
    assert default_threshold(14) == 2
    assert default_threshold(56) == 8
    assert default_threshold(8) == 1


def test_invalid_when_original_misses_goal():
    o = [(1, 1), (1, 2), (1, 3)]
    assert one(o, o, goal=(1, 4))[0] == "invalid"
    # even when the adversarial path reaches it
    assert one(o, [(1, 1), (1, 2), (1, 3), (1, 4)], goal=(1, 4))[0] == "invalid"


def test_unreached_when_adversarial_misses_goal():
    o = [(1, 1), (1, 2), (1, 3)]
    assert one(o, [(1, 1), (2, 2)])[0] == "UrP"


def test_unchanged_when_identical():
    o = [(1, 1), (2, 2), (3, 3)]
    assert one(o, list(o)) == ("UcP", 0, 0)


def test_same_cells_other_order_is_not_unchanged():
    o = [(1, 1), (1, 2), (2, 2), (2, 3)]
    a = [(1, 1), (2, 2), (1, 2), (2, 3)]
    assert one(o, a) == ("DP", 0, 0)


def test_detour_distance_exactly_t_is_dp_and_t_plus_one_is_fp():
    # top of the detour on row 2: |6 - 2| = 4 = t
    label, dh, dv = one(row6(arch(2)), arch(2))
    assert (label, dh, dv) == ("DP", 0, 4)
    label, dh, dv = one(row6(arch(1)), arch(1))
    assert (label, dv) == ("FP", 5)


def test_equal_row_pairs_missing_gives_dh_zero():
    # Do lies on row 6 only, Da on rows 1-5 only: no equal-row pair, so dh = 0 and FP by dv alone
    _, dh, dv = one(row6(arch(1)), arch(1))
    assert dh == 0 and dv == 5


def test_one_large_distance_is_enough_for_fp():
    # transposed: FP by dh alone (the paper's "AND" would leave it unclassified)
    o = [(c, r) for r, c in row6(arch(1))]
    a = [(c, r) for r, c in arch(1)]
    assert one(o, a) == ("FP", 5, 0)


def test_shared_prefix_and_suffix_do_not_count():
    # a shared prefix cell (5, 1) shares row 5 with Da cells up to (5, 9), 8 apart; it is not in Do
    o = [(5, 1), (5, 2), (5, 3), (4, 4), (4, 5), (4, 6), (4, 7), (4, 8), (4, 9), (4, 10)]
    a = [(5, 1), (5, 2), (5, 3), (5, 4), (5, 5), (5, 6), (5, 7), (5, 8), (5, 9), (4, 10)]
    assert one(o, a) == ("DP", 0, 1)


def test_diagonal_shortcut():
    # original: down column 1, then along row 10; adversarial cuts the corner diagonally
    o = [(r, 1) for r in range(1, 11)] + [(10, c) for c in range(2, 11)]
    a = [(r, 1) for r in range(1, 6)] + [(6, 2), (7, 3), (8, 4), (9, 5)] + [(10, c) for c in range(6, 11)]
    assert one(o, a) == ("DP", 4, 4)
    o2 = [(r, 1) for r in range(1, 12)] + [(11, c) for c in range(2, 12)]
    a2 = [(r, 1) for r in range(1, 6)] + [(6, 2), (7, 3), (8, 4), (9, 5), (10, 6)] + [(11, c) for c in range(7, 12)]
    assert one(o2, a2) == ("FP", 5, 5)


def test_parallel_paths_one_apart_fork_by_row_distance():
    # the rule compares cells of one row at any distance: Do (6,10) and Da (6,3) are 7 apart
    o = [(5, c) for c in range(1, 11)] + [(6, 10), (7, 10)]
    a = [(5, 1), (5, 2)] + [(6, c) for c in range(3, 10)] + [(7, 10)]
    assert one(o, a) == ("FP", 7, 1)


def test_adversarial_covering_original_has_zero_distances():
    o = [(1, 1), (2, 2), (3, 3)]
    a = [(1, 1), (1, 2), (2, 2), (3, 3)]
    assert one(o, a) == ("DP", 0, 0)


def test_threshold_is_a_parameter():
    assert one(row6(arch(2)), arch(2), t=3)[0] == "FP"
    assert one(row6(arch(1)), arch(1), t=5)[0] == "DP"


def test_empty_batch_and_empty_paths():
    batch = PathPairBatch.from_paths([], [], np.zeros((0, 2)), 5)
    assert len(label_batch(batch).labels) == 0
    batch = PathPairBatch.from_paths([np.zeros((0, 2))], [np.zeros((0, 2))], [(1, 1)], 5)
    assert label_batch(batch).labels.tolist() == ["invalid"]


def test_cells_outside_grid_refused():
    with pytest.raises(InputError, match="original paths: cells outside the 5x5 grid"):
        path_distances(PackedPaths.pack([[[0, 9]]]), PackedPaths.pack([[[0, 0]]]), 5)
    with pytest.raises(InputError, match="threshold t must be >= 0"):
        label_pairs(PackedPaths.pack([[[0, 0]]]), PackedPaths.pack([[[0, 0]]]), [(0, 0)], 5, t=-1)
    with pytest.raises(InputError, match="adversarial paths: cells outside"):
        PathPairBatch.from_paths([[[0, 0]]], [[[5, 0]]], [(0, 0)], 5)


@settings(max_examples=150, deadline=None)
@given(path_pairs(), st.integers(0, 5))
def test_rule_matches_brute_force_oracle(batch, t):
    result = label_batch(batch, t)
    for i, (o, a, goal) in enumerate(pairs_as_lists(batch)):
        assert (result.labels[i], result.dh[i], result.dv[i]) == rule_oracle(o, a, goal, t)


@settings(max_examples=80, deadline=None)
@given(path_pairs(), st.integers(0, 7), st.integers(0, 5))
def test_rule_invariant_under_flips_and_rotations(batch, transform, t):
    before = label_batch(batch, t)
    after = label_batch(batch.transformed(transform), t)
    assert after.labels.tolist() == before.labels.tolist()
    # rotations by 90 degrees and transposes swap the horizontal and vertical distances
    swap = transform in (1, 3, 6, 7)
    assert np.array_equal(after.dh, before.dv if swap else before.dh)
    assert np.array_equal(after.dv, before.dh if swap else before.dv)
