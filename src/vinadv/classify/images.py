"""Path images (paper section 4.3), the 8 flips/rotations of the square, and minority-class augmentation.

A path image is `N x N x 3` uint8 on a black map: adversarial path cells blue `(0, 0, 255)`, then original
path cells red `(255, 0, 0)` drawn on top, so blue shows only where the adversarial path differs.

Dihedral transforms, by id (cells are `(row, col)`; "clockwise" as the image is displayed):
`0` identity, `1` rotate 90 clockwise, `2` rotate 180, `3` rotate 270 clockwise, `4` flip horizontally
(left-right), `5` flip vertically (up-down), `6` transpose, `7` anti-transpose. The paper's augmentation uses
`AUGMENT_TRANSFORMS` = 1-5 (flips and rotations); the FP/DP rule is invariant under all 8.
"""

from __future__ import annotations

import numpy as np

from vinadv.classify.batch import PathPairBatch, pair_ids
from vinadv.errors import InputError

BLUE = np.array([0, 0, 255], dtype=np.uint8)
RED = np.array([255, 0, 0], dtype=np.uint8)
GREEN = np.array([0, 255, 0], dtype=np.uint8)
TRANSFORM_NAMES = ("identity", "rot90", "rot180", "rot270", "flip_h", "flip_v", "transpose", "antitranspose")
#: The paper's augmentation: horizontal and vertical flips, 90/180/270 degree rotations.
AUGMENT_TRANSFORMS = (1, 2, 3, 4, 5)


def transform_cells(cells: np.ndarray, size: int, transform) -> np.ndarray:
    """`(row, col)` cells `(m, 2)` moved by dihedral transform(s) `transform` (scalar or `(m,)` ids 0-7)."""
    cells = np.asarray(cells, dtype=np.int64).reshape(-1, 2)
    r, c = cells[:, 0], cells[:, 1]
    last = int(size) - 1
    candidates = np.stack(
        [
            np.stack([r, c], 1),
            np.stack([c, last - r], 1),
            np.stack([last - r, last - c], 1),
            np.stack([last - c, r], 1),
            np.stack([r, last - c], 1),
            np.stack([last - r, c], 1),
            np.stack([c, r], 1),
            np.stack([last - c, last - r], 1),
        ]
    )  # (8, m, 2)
    transform = np.broadcast_to(np.asarray(transform, dtype=np.int64), (len(cells),))
    if np.any((transform < 0) | (transform > 7)):
        raise InputError("dihedral transform ids must be 0-7")
    return candidates[transform, np.arange(len(cells))]


def transform_images(images: np.ndarray, transform: int) -> np.ndarray:
    """Images `(n, N, N, ...)` under one dihedral transform (same ids as `transform_cells`)."""
    images = np.asarray(images)
    axes = (1, 2)
    if transform == 0:
        out = images
    elif transform in (1, 2, 3):
        out = np.rot90(images, k=-transform, axes=axes)
    elif transform == 4:
        out = images[:, :, ::-1]
    elif transform == 5:
        out = images[:, ::-1, :]
    elif transform == 6:
        out = np.swapaxes(images, 1, 2)
    elif transform == 7:
        out = np.swapaxes(images, 1, 2)[:, ::-1, ::-1]
    else:
        raise InputError(f"dihedral transform id must be 0-7, got {transform}")
    return np.ascontiguousarray(out)


ENCODINGS = ("paper", "split")


def render_path_images(o_cells, o_offsets, a_cells, a_offsets, size: int, encoding: str = "paper") -> np.ndarray:
    """Path images of `n` packed path pairs: `(n, size, size, 3)` uint8.

    encoding 'paper' (DESIGN.md): adversarial path blue, then the original path red on top.
    encoding 'split' (vinadv's own, richer): as 'paper', but cells on both paths green `(0, 255, 0)`, so red
    shows only the original path's cells off the adversarial path (the rule's `Do`) and blue its `Da`.
    """
    if encoding not in ENCODINGS:
        raise InputError(f"unknown path image encoding {encoding!r}; choose from {list(ENCODINGS)}")
    o_offsets = np.asarray(o_offsets, dtype=np.int64)
    a_offsets = np.asarray(a_offsets, dtype=np.int64)
    n = len(o_offsets) - 1
    images = np.zeros((n, size, size, 3), dtype=np.uint8)
    a_cells = np.asarray(a_cells, dtype=np.int64).reshape(-1, 2)
    o_cells = np.asarray(o_cells, dtype=np.int64).reshape(-1, 2)
    images[pair_ids(a_offsets), a_cells[:, 0], a_cells[:, 1]] = BLUE
    o_pairs = pair_ids(o_offsets)
    if encoding == "split":
        shared = images[o_pairs, o_cells[:, 0], o_cells[:, 1], 2] > 0  # original cells already drawn blue
        images[o_pairs, o_cells[:, 0], o_cells[:, 1]] = np.where(shared[:, None], GREEN, RED)
    else:
        images[o_pairs, o_cells[:, 0], o_cells[:, 1]] = RED
    return images


def render_batch(batch: PathPairBatch, encoding: str = "paper") -> np.ndarray:
    """`render_path_images` of a `PathPairBatch`: `(n, N, N, 3)` uint8."""
    return render_path_images(batch.o_cells, batch.o_offsets, batch.a_cells, batch.a_offsets, batch.size, encoding)


def augmentation_plan(labels: np.ndarray, seed: int = 0, transforms=AUGMENT_TRANSFORMS):
    """Which minority-class items to copy, and how, so that every class has as many items as the largest.

    Returns `(source (k,) int64 indices into labels, transform (k,) int64 ids)`. Copies are distinct
    (item, transform) combinations as long as there are enough of them, drawn at random with `seed`.
    """
    labels = np.asarray(labels)
    rng = np.random.default_rng(seed)
    classes, counts = np.unique(labels, return_counts=True)
    target = counts.max() if len(counts) else 0
    sources, ids = [], []
    transforms = np.asarray(transforms, dtype=np.int64)
    for cls, count in zip(classes, counts):
        need = int(target - count)
        if need == 0:
            continue
        members = np.flatnonzero(labels == cls)
        combos = len(members) * len(transforms)
        # distinct (member, transform) combinations first, repeats only when all are used
        picks = np.concatenate(
            [rng.permutation(combos) for _ in range(-(-need // combos))]
        )[:need]
        sources.append(members[picks // len(transforms)])
        ids.append(transforms[picks % len(transforms)])
    if not sources:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate(sources), np.concatenate(ids)


def balance_batch(batch: PathPairBatch, labels: np.ndarray, seed: int = 0) -> tuple[PathPairBatch, np.ndarray]:
    """The batch plus flipped/rotated copies of minority-class pairs, so every class has the same count.

    Returns `(balanced batch, labels)`: the original pairs first, then the copies.
    """
    from vinadv.classify.batch import concat_batches

    labels = np.asarray(labels)
    if len(labels) != len(batch):
        raise InputError(f"{len(labels)} labels for {len(batch)} path pairs")
    source, transform = augmentation_plan(labels, seed)
    if len(source) == 0:
        return batch, labels
    copies = batch.subset(source).transformed(transform)
    return concat_batches([batch, copies]), np.concatenate([labels, labels[source]])


def balance_images(images: np.ndarray, labels: np.ndarray, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """`balance_batch` for images already rendered: `(n + k, N, N, 3)` images and their labels."""
    images = np.asarray(images)
    labels = np.asarray(labels)
    source, transform = augmentation_plan(labels, seed)
    copies = [images[:0]]
    for t in np.unique(transform):
        copies.append(transform_images(images[source[transform == t]], int(t)))
    order = np.concatenate([np.flatnonzero(transform == t) for t in np.unique(transform)] or [np.zeros(0, int)])
    extra = np.concatenate(copies)
    extra_labels = labels[source[order]]
    return np.concatenate([images, extra]), np.concatenate([labels, extra_labels])
