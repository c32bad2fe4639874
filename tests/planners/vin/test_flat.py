"""The flat layout: round trip, zero padding, and the nine neighbour offsets."""

import numpy as np
import pytest

from vinadv.planners.vin.flat import from_flat, layout, to_flat, zero_row_gaps


@pytest.mark.parametrize("n", [8, 9, 13, 16, 28])
def test_round_trip_and_neighbours(n):
    rng = np.random.default_rng(n)
    maps = rng.standard_normal((3, n, n)).astype(np.float32)
    flat = to_flat(maps)
    width, p0, length, size = layout(n)
    assert width % 8 == 0 and width > n and flat.shape == (3, size)
    np.testing.assert_array_equal(from_flat(flat, n), maps)
    padded = np.pad(maps, ((0, 0), (1, 1), (1, 1)))
    for i in range(n):  # every cell's 3x3 neighbourhood sits at the same nine offsets, zeros off the grid
        for j in range(n):
            cell = p0 + i * width + j
            got = np.stack([flat[:, cell + di * width + dj] for di in (-1, 0, 1) for dj in (-1, 0, 1)], 1)
            np.testing.assert_array_equal(got, padded[:, i : i + 3, j : j + 3].reshape(3, 9))
    assert p0 + length <= size and p0 - width - 1 >= 0


def test_zero_row_gaps_clears_only_the_gaps():
    n = 9
    width, p0, length, _ = layout(n)
    flat = to_flat(np.ones((1, n, n), np.float32))[0]
    flat[p0 : p0 + length] = 5.0
    zero_row_gaps(flat, n)
    np.testing.assert_array_equal(from_flat(flat[None], n)[0], np.full((n, n), 5.0))
    assert flat.sum() == 5.0 * n * n
