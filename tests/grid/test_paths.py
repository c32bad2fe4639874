import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vinadv.errors import InputError
from vinadv.grid.paths import PackedPaths

# paths of 0..12 cells (the type allows empty paths; files do not)
paths_strategy = st.lists(
    st.lists(st.tuples(st.integers(0, 27), st.integers(0, 27)), min_size=0, max_size=12), min_size=0, max_size=8
)


def as_lists(packed: PackedPaths) -> list:
    return [p.tolist() for p in packed.unpack()]


def lists(paths) -> list:
    return [[list(c) for c in p] for p in paths]


@settings(max_examples=100, deadline=None)
@given(paths_strategy)
def test_pack_unpack_round_trip(paths):
    packed = PackedPaths.pack(paths)
    assert packed.cells.dtype == np.int16 and packed.cells.shape == (sum(map(len, paths)), 2)
    assert packed.offsets.dtype == np.int64 and packed.offsets[0] == 0
    assert len(packed) == len(paths) and packed.lengths.tolist() == [len(p) for p in paths]
    assert as_lists(packed) == lists(paths)
    assert [packed[i].tolist() for i in range(len(paths))] == lists(paths)


@settings(max_examples=100, deadline=None)
@given(paths_strategy, st.data())
def test_take_matches_list_indexing(paths, data):
    idx = data.draw(st.lists(st.integers(0, max(len(paths) - 1, 0)), max_size=10)) if paths else []
    packed = PackedPaths.pack(paths).take(np.array(idx, dtype=np.int64))
    assert as_lists(packed) == lists([paths[i] for i in idx])
    mask = np.array(data.draw(st.lists(st.booleans(), min_size=len(paths), max_size=len(paths))), dtype=bool)
    assert as_lists(PackedPaths.pack(paths).take(mask)) == lists([p for p, m in zip(paths, mask) if m])


@pytest.mark.slow  # over a second: the quick tier keeps the module's other tests
@settings(max_examples=100, deadline=None)
@given(st.lists(paths_strategy, max_size=4))
def test_concat_matches_list_concatenation(groups):
    packed = PackedPaths.concat([PackedPaths.pack(g) for g in groups])
    assert as_lists(packed) == lists([p for g in groups for p in g])


def test_concat_of_nothing_is_zero_paths():
    empty = PackedPaths.concat([])
    assert len(empty) == 0 and empty.offsets.tolist() == [0] and empty.cells.shape == (0, 2)
    assert PackedPaths.concat([empty, PackedPaths.empty(2)]).offsets.tolist() == [0, 0, 0]


@settings(max_examples=100, deadline=None)
@given(paths_strategy)
def test_costs_match_a_plain_sum_of_moves(paths):
    expect = [
        sum(
            math.sqrt(2) if abs(a[0] - b[0]) + abs(a[1] - b[1]) == 2 else abs(a[0] - b[0]) + abs(a[1] - b[1])
            for a, b in zip(p, p[1:])
        )
        for p in paths
    ]
    np.testing.assert_allclose(PackedPaths.pack(paths).costs(), expect, atol=1e-12)


def test_costs_count_orthogonal_and_diagonal_moves():
    costs = PackedPaths.pack([[[3, 3]], [[1, 1], [1, 2], [2, 3], [3, 4], [3, 5]], []]).costs()
    assert costs[0] == 0.0 and costs[2] == 0.0
    assert math.isclose(costs[1], 2 + 2 * math.sqrt(2))


@settings(max_examples=100, deadline=None)
@given(paths_strategy, st.data())
def test_same_as_compares_cell_for_cell(paths, data):
    other = [data.draw(st.sampled_from([p, p[:-1], p[::-1], [(0, 0)] + p])) for p in paths]
    same = PackedPaths.pack(paths).same_as(PackedPaths.pack(other))
    assert same.tolist() == [list(map(list, p)) == list(map(list, q)) for p, q in zip(paths, other)]


def test_equality_pickling_and_owners():
    packed = PackedPaths.pack([[[1, 2], [2, 2]], [], [[0, 0]]])
    assert packed == PackedPaths.pack([[[1, 2], [2, 2]], [], [[0, 0]]]) and packed != PackedPaths.empty(3)
    assert pickle.loads(pickle.dumps(packed)) == packed
    assert packed.owners().tolist() == [0, 0, 2]


@pytest.mark.parametrize(
    "cells, offsets, match",
    [
        (np.zeros((3, 2), dtype=int), [0, 2], "end at the number of cells"),
        (np.zeros((3, 2), dtype=int), [1, 3], "start at 0"),
        (np.zeros((3, 2), dtype=int), [0, 2, 1, 3], "never decrease"),
        (np.zeros((3, 3), dtype=int), [0, 3], "cells has shape"),
        (np.zeros((2, 2), dtype=int), [[0, 2]], "offsets has shape"),
        (np.full((1, 2), 0.5), [0, 1], "expected integers"),
    ],
)
def test_bad_layout_is_refused_naming_the_field(cells, offsets, match):
    with pytest.raises(InputError, match=match):
        PackedPaths(cells, np.asarray(offsets))


def test_check_grid_names_the_paths():
    PackedPaths.pack([[[0, 0], [4, 4]]]).check_grid(5)
    with pytest.raises(InputError, match="original paths: cells outside the 4x4 grid"):
        PackedPaths.pack([[[0, 0], [4, 4]]]).check_grid(4, "original paths")
