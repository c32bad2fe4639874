import numpy as np
import pytest
import torch

from vinadv.errors import InputError
from vinadv.grid.dihedral import NAMES, transform_cells, transform_grids

SIZE = 5
GRID = np.arange(2 * SIZE * SIZE).reshape(2, SIZE, SIZE)
# independent definitions of the 8 transforms with NumPy's own rotations and flips
REFERENCE = {
    0: GRID,
    1: np.rot90(GRID, -1, axes=(1, 2)),
    2: np.rot90(GRID, 2, axes=(1, 2)),
    3: np.rot90(GRID, 1, axes=(1, 2)),
    4: GRID[:, :, ::-1],
    5: GRID[:, ::-1, :],
    6: GRID.transpose(0, 2, 1),
    7: np.rot90(GRID, 2, axes=(1, 2)).transpose(0, 2, 1),
}


@pytest.mark.parametrize("k", range(8))
def test_grids_match_numpy_rotations_and_flips(k):
    out = transform_grids(GRID, k)
    assert np.array_equal(out, REFERENCE[k]) and out.flags.c_contiguous
    # channels-first tensors, as the image networks hold them: rows and columns on axes 2 and 3
    tensor = torch.from_numpy(GRID[:, None].copy())
    assert np.array_equal(transform_grids(tensor, k, axes=(2, 3)).numpy()[:, 0], REFERENCE[k])


@pytest.mark.parametrize("k", range(8))
def test_cells_move_where_their_grid_value_goes(k):
    cells = np.array([(r, c) for r in range(SIZE) for c in range(SIZE)])
    moved = transform_cells(cells, SIZE, k)
    out = np.empty_like(GRID[0])
    out[moved[:, 0], moved[:, 1]] = GRID[0, cells[:, 0], cells[:, 1]]
    assert np.array_equal(out, REFERENCE[k][0]), NAMES[k]


def test_one_transform_per_cell_and_bad_ids():
    cells = np.array([[0, 1], [0, 1], [0, 1]])
    assert transform_cells(cells, SIZE, [0, 1, 4]).tolist() == [[0, 1], [1, 4], [0, 3]]
    with pytest.raises(InputError, match="0-7, got 8"):
        transform_cells(cells, SIZE, 8)
    with pytest.raises(InputError, match="0-7, got -1"):
        transform_grids(GRID, -1)
