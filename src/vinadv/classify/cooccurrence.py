"""Row/column co-occurrence features of path images, for the FP/DP classifiers.

The FP/DP rule compares cells of the two paths that lie in the same row (or the same column) at any distance,
a relation that pixel-based classifiers (an RBF kernel on pixels, small convolutions) struggle to learn from a
few thousand images. These features expose it and leave the rest to learning: which distances matter (the
rule's threshold) is learned from the labels, nothing about it is written here.

Of a path image, `red` is the set of cells with a red component and `blue` those with a blue one. In the
'split' encoding (`vinadv.classify.images`) red is exactly the rule's `Do` (original path cells off the
adversarial path) and blue its `Da`; in the paper's encoding red is the whole original path.

- `cooccurrence`: `C_h[a, b] = sum_i red[i, a] * blue[i, b]` (a red cell in column `a` and a blue cell in
  column `b` of the same row) and `C_v[a, b] = sum_j red[a, j] * blue[b, j]` (rows `a`, `b` of one column):
  `(n, 2, N, N)`.
- `offset_cooccurrence`: the same summed over positions, by offset `d = b - a` from `-(N - 1)` to `N - 1`:
  `P_h[d] = sum_a C_h[a, a + d]`, `P_v` likewise, `(n, 2, 2N - 1)` (translation invariant: how many red/blue
  cell pairs of one row, or one column, lie `d` cells apart).

Feature sets (`FEATURES`), as classifiers use them, all 0/1 (presence): 'pixels' (the image scaled to 0/1,
`3 N^2` values; a pixel value is 0 or 255), 'cooccurrence' (`C > 0`, `2 N^2`), 'offsets' (`P > 0`, `2 (2N - 1)`).
"""

from __future__ import annotations

import numpy as np

from vinadv.errors import InputError

FEATURES = ("pixels", "cooccurrence", "offsets")


def _check_images(images) -> np.ndarray:
    images = np.asarray(images)
    if images.ndim != 4 or images.shape[3] != 3 or images.shape[1] != images.shape[2]:
        raise InputError(f"path images must be (n, N, N, 3), got shape {images.shape}")
    return images


def cooccurrence(images) -> np.ndarray:
    """Row and column co-occurrence counts of red and blue cells: `(n, 2, N, N)` float32 (`[:, 0]` = `C_h`,
    `[:, 1]` = `C_v`) of path images `(n, N, N, 3)`."""
    images = _check_images(images)
    red = (images[..., 0] > 0).astype(np.float32)
    blue = (images[..., 2] > 0).astype(np.float32)
    out = np.empty((len(images), 2, images.shape[1], images.shape[1]), dtype=np.float32)
    np.matmul(red.transpose(0, 2, 1), blue, out=out[:, 0])  # C_h[a, b] = sum_i red[i, a] blue[i, b]
    np.matmul(red, blue.transpose(0, 2, 1), out=out[:, 1])  # C_v[a, b] = sum_j red[a, j] blue[b, j]
    return out


def offset_matrix(size: int) -> np.ndarray:
    """`(N * N, 2N - 1)` float32 0/1: entry `(a * N + b, d + N - 1)` is 1 where `b - a = d` (sums the
    diagonals of a flattened `N x N` map)."""
    a, b = np.divmod(np.arange(size * size), size)
    out = np.zeros((size * size, 2 * size - 1), dtype=np.float32)
    out[np.arange(size * size), b - a + size - 1] = 1.0
    return out


def offset_cooccurrence(images) -> np.ndarray:
    """Red/blue cell pairs of one row (`[:, 0]`) or one column (`[:, 1]`) by offset `d = b - a`, index
    `d + N - 1`: `(n, 2, 2N - 1)` float32 of path images `(n, N, N, 3)`."""
    c = cooccurrence(images)
    n, _, size, _ = c.shape
    return (c.reshape(n * 2, size * size) @ offset_matrix(size)).reshape(n, 2, 2 * size - 1)


def feature_shape(features: str, size: int) -> tuple[int, ...]:
    """Shape of one item's features as the networks see them: `(3, N, N)`, `(2, N, N)` or `(2, 2N - 1)`."""
    if features == "pixels":
        return (3, size, size)
    if features == "cooccurrence":
        return (2, size, size)
    if features == "offsets":
        return (2, 2 * size - 1)
    raise InputError(f"unknown features {features!r}; choose from {list(FEATURES)}")


def image_features(images, features: str = "pixels") -> np.ndarray:
    """0/1 features of path images `(n, N, N, 3)` uint8, flattened: `(n, prod(feature_shape))` float32."""
    images = _check_images(images)
    feature_shape(features, images.shape[1])  # checks the name
    if features == "pixels":
        return (images.reshape(len(images), -1) > 0).astype(np.float32)  # (row, column, channel) order
    values = cooccurrence(images) if features == "cooccurrence" else offset_cooccurrence(images)
    return (values.reshape(len(images), -1) > 0).astype(np.float32)


def torch_features(x, features: str, offsets=None):
    """The same features of a `(B, 3, N, N)` float tensor of path images scaled to 0/1, for the networks:
    `(B, 3, N, N)`, `(B, 2, N, N)` or `(B, 2, 2N - 1)` float, 0/1. `offsets`: `offset_matrix(N)` as a tensor
    (needed for 'offsets')."""
    import torch

    if features == "pixels":
        return x
    red = (x[:, 0] > 0).to(x.dtype)
    blue = (x[:, 2] > 0).to(x.dtype)
    c = torch.stack([red.transpose(1, 2) @ blue, red @ blue.transpose(1, 2)], dim=1)
    if features == "cooccurrence":
        return (c > 0).to(x.dtype)
    if features == "offsets":
        size = x.shape[-1]
        p = c.reshape(len(x), 2, size * size) @ offsets
        return (p > 0).to(x.dtype)
    raise InputError(f"unknown features {features!r}; choose from {list(FEATURES)}")
