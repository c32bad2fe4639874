import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from vinadv.grid import pack_paths, path_costs, take_paths, unpack_paths

paths_strategy = st.lists(
    st.lists(st.tuples(st.integers(0, 27), st.integers(0, 27)), min_size=1, max_size=12), min_size=0, max_size=8
)


@settings(max_examples=100, deadline=None)
@given(paths_strategy)
def test_pack_unpack_round_trip(paths):
    cells, offsets = pack_paths([np.array(p) for p in paths])
    assert cells.dtype == np.int16 and offsets.dtype == np.int64 and offsets[0] == 0
    assert [p.tolist() for p in unpack_paths(cells, offsets)] == [[list(c) for c in p] for p in paths]


@settings(max_examples=100, deadline=None)
@given(paths_strategy.filter(bool), st.data())
def test_take_paths_matches_list_indexing(paths, data):
    idx = np.array(data.draw(st.lists(st.integers(0, len(paths) - 1), max_size=10)), dtype=np.int64)
    cells, offsets = take_paths(*pack_paths([np.array(p) for p in paths]), idx)
    assert [p.tolist() for p in unpack_paths(cells, offsets)] == [[list(c) for c in paths[i]] for i in idx]


def test_path_costs_counts_orthogonal_and_diagonal_moves():
    paths = [np.array([[3, 3]]), np.array([[1, 1], [1, 2], [2, 3], [3, 4], [3, 5]])]
    costs = path_costs(*pack_paths(paths))
    assert costs[0] == 0.0
    assert math.isclose(costs[1], 2 + 2 * math.sqrt(2))
