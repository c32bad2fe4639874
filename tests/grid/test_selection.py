import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from vinadv.grid.selection import smallest_first


def oracle(keys: np.ndarray, k: int) -> list[list[int]]:
    """Each row's indices sorted by (key, index) in plain Python, NaN after every number; the first k."""
    out = []
    for row in keys.tolist():
        order = sorted(range(len(row)), key=lambda j: (row[j] != row[j], 0.0 if row[j] != row[j] else row[j], j))
        out.append(order[:k])
    return out


# few distinct values, so that rows are full of ties; infinities and NaN among them
VALUES = st.sampled_from([0.0, -0.0, 1.0, 2.5, -3.0, np.inf, -np.inf, np.nan])


@settings(max_examples=60, deadline=None)
@given(
    st.tuples(st.integers(0, 4), st.integers(1, 30)).flatmap(
        lambda shape: st.tuples(arrays(np.float64, shape, elements=VALUES), st.integers(0, shape[1] + 2))
    )
)
def test_smallest_first_is_the_stable_sort_s_first_k(case):
    keys, k = case
    got = smallest_first(keys, k)
    assert got.dtype == np.int64 and got.shape == (len(keys), min(k, keys.shape[1]))
    assert got.tolist() == oracle(keys, k)


def test_smallest_first_on_random_keys_of_a_map_s_cells():
    rng = np.random.default_rng(3)
    keys = np.where(rng.random((50, 784)) < 0.7, rng.random((50, 784)), np.inf)
    keys[:5] = np.inf  # rows with no finite key: the lowest indices
    for k in (1, 7, 8):
        assert smallest_first(keys, k).tolist() == oracle(keys, k)
    ints = rng.integers(0, 3, (4, 30))  # not floats: the sort itself
    assert smallest_first(ints, 3).tolist() == np.argsort(ints, axis=1, kind="stable")[:, :3].tolist()
