"""Thumbnails drawn in pixels: each cell's block in the palette's colour of what lies there, checked cell by cell on
hand-made pairs, and a batch the same as its pairs drawn one at a time."""

from __future__ import annotations

import numpy as np

from vinadv.plot.palette import PALETTE
from vinadv.plot.thumbnails import thumbnail_images, thumbnail_scale


def packed(paths):
    cells = np.array([c for p in paths for c in p], dtype=np.int64).reshape(-1, 2)
    return cells, np.concatenate([[0], np.cumsum([len(p) for p in paths])])


def block(image, r, c, s):
    return image[r * s : (r + 1) * s, c * s : (c + 1) * s]


def test_every_cell_has_the_colour_of_what_lies_there():
    size, s = 6, 4
    obstacles = np.zeros((2, size, size), bool)
    obstacles[:, 0, 5] = True
    obstacles[0, 2, 3] = True  # pair 0 adds (2, 3); pair 1 frees (4, 4)
    images = thumbnail_images(
        obstacles,
        starts=[[1, 1], [1, 1]],
        goals=[[4, 1], [4, 1]],
        added=[[[2, 3]], [[4, 4]]],
        removed=[False, True],
        path_o=packed([[(1, 1), (2, 1), (3, 1), (4, 1)], [(1, 1), (4, 1)]]),
        path_a=packed([[(1, 1), (1, 2), (3, 1), (4, 1)], []]),
        expanded=packed([[(5, 5), (0, 5)], []]),
        scale=s,
    )
    assert images.shape == (2, size * s, size * s, 3) and images.dtype == np.uint8
    one = images[0]
    assert (block(one, 0, 0, s) == PALETTE.free.rgb).all()
    assert (block(one, 0, 5, s) == PALETTE.obstacle.rgb).all()  # expanded under an obstacle: still an obstacle
    assert (block(one, 5, 5, s) == PALETTE.expanded.rgb).all()
    assert (block(one, 2, 3, s) == PALETTE.added.rgb).all()
    assert (block(one, 2, 1, s) == PALETTE.original.rgb).all()  # the original path alone
    both = block(one, 3, 1, s)  # on both paths: a ring of the original round the adversarial's inside
    assert (both[1:-1, 1:-1] == PALETTE.adversarial.rgb).all() and (both[0] == PALETTE.original.rgb).all()
    adversarial = block(one, 1, 2, s)
    assert (adversarial[1:-1, 1:-1] == PALETTE.adversarial.rgb).all() and (adversarial[0] == PALETTE.free.rgb).all()
    for (r, c), style in (((1, 1), PALETTE.start), ((4, 1), PALETTE.goal)):
        marker = block(one, r, c, s)
        assert (marker[1:-1, 1:-1] == style.rgb).all() and (marker[0] == PALETTE.edge.rgb).all()
    freed = block(images[1], 4, 4, s)  # a freed cell: an outline of the removed colour round a free inside
    assert (freed[0] == PALETTE.removed.rgb).all() and (freed[1:-1, 1:-1] == PALETTE.free.rgb).all()
    assert not (images[1] == PALETTE.expanded.rgb).all(axis=-1).any()


def test_a_batch_draws_each_pair_as_alone():
    rng = np.random.default_rng(0)
    n, size = 5, 9
    obstacles = rng.random((n, size, size)) < 0.3
    paths = [[tuple(c) for c in rng.integers(0, size, (int(rng.integers(0, 8)), 2))] for _ in range(2 * n)]
    args = dict(
        starts=rng.integers(0, size, (n, 2)),
        goals=rng.integers(0, size, (n, 2)),
        added=rng.integers(0, size, (n, 2, 2)),
        removed=rng.random(n) < 0.5,
    )
    batch = thumbnail_images(obstacles, **args, path_o=packed(paths[:n]), path_a=packed(paths[n:]))
    assert batch.shape[1] == size * thumbnail_scale(size)
    for i in range(n):
        alone = thumbnail_images(
            obstacles[i : i + 1],
            **{k: v[i : i + 1] for k, v in args.items()},
            path_o=packed([paths[i]]),
            path_a=packed([paths[n + i]]),
        )
        assert np.array_equal(alone[0], batch[i])


def test_scale_fits_the_thumbnail():
    assert thumbnail_scale(28) == 4 and thumbnail_scale(100) == 1 and thumbnail_scale(500) == 1
