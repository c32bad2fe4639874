"""Path images (paper section 4.3) and minority-class augmentation by flips and rotations.

A path image is `N x N x 3` uint8 on a black map: adversarial path cells blue `(0, 0, 255)`, then original
path cells red `(255, 0, 0)` drawn on top, so blue shows only where the adversarial path differs.

Augmentation flips and rotates pairs with the dihedral transforms of `vinadv.grid.dihedral` (ids 0-7); the
paper's uses `AUGMENT_TRANSFORMS` = 1-5 (flips and rotations); the FP/DP rule is invariant under all 8.
"""

from __future__ import annotations

import numpy as np

from vinadv.classify.batch import PathPairBatch
from vinadv.errors import InputError
from vinadv.grid.dihedral import transform_grids
from vinadv.grid.paths import PackedPaths

BLUE = np.array([0, 0, 255], dtype=np.uint8)
RED = np.array([255, 0, 0], dtype=np.uint8)
GREEN = np.array([0, 255, 0], dtype=np.uint8)
#: The paper's augmentation: horizontal and vertical flips, 90/180/270 degree rotations.
AUGMENT_TRANSFORMS = (1, 2, 3, 4, 5)
ENCODINGS = ("paper", "split")


def render_path_images(path_o: PackedPaths, path_a: PackedPaths, size: int, encoding: str = "paper") -> np.ndarray:
    """Path images of `n` path pairs (original and adversarial paths): `(n, size, size, 3)` uint8.

    encoding 'paper' (DESIGN.md): adversarial path blue, then the original path red on top.
    encoding 'split' (vinadv's own, richer): as 'paper', but cells on both paths green `(0, 255, 0)`, so red
    shows only the original path's cells off the adversarial path (the rule's `Do`) and blue its `Da`.
    """
    if encoding not in ENCODINGS:
        raise InputError(f"unknown path image encoding {encoding!r}; choose from {list(ENCODINGS)}")
    images = np.zeros((len(path_o), size, size, 3), dtype=np.uint8)
    a_cells = path_a.cells.astype(np.int64)
    o_cells = path_o.cells.astype(np.int64)
    images[path_a.owners(), a_cells[:, 0], a_cells[:, 1]] = BLUE
    o_pairs = path_o.owners()
    if encoding == "split":
        shared = images[o_pairs, o_cells[:, 0], o_cells[:, 1], 2] > 0  # original cells already drawn blue
        images[o_pairs, o_cells[:, 0], o_cells[:, 1]] = np.where(shared[:, None], GREEN, RED)
    else:
        images[o_pairs, o_cells[:, 0], o_cells[:, 1]] = RED
    return images


def render_batch(batch: PathPairBatch, encoding: str = "paper") -> np.ndarray:
    """`render_path_images` of a `PathPairBatch`: `(n, N, N, 3)` uint8."""
    return render_path_images(batch.path_o, batch.path_a, batch.size, encoding)


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
        picks = np.concatenate([rng.permutation(combos) for _ in range(-(-need // combos))])[:need]
        sources.append(members[picks // len(transforms)])
        ids.append(transforms[picks % len(transforms)])
    if not sources:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate(sources), np.concatenate(ids)


def balance_batch(batch: PathPairBatch, labels: np.ndarray, seed: int = 0) -> tuple[PathPairBatch, np.ndarray]:
    """The batch plus flipped/rotated copies of minority-class pairs, so every class has the same count.

    Returns `(balanced batch, labels)`: the original pairs first, then the copies.
    """
    labels = np.asarray(labels)
    if len(labels) != len(batch):
        raise InputError(f"{len(labels)} labels for {len(batch)} path pairs")
    source, transform = augmentation_plan(labels, seed)
    if len(source) == 0:
        return batch, labels
    copies = batch.take(source).transformed(transform)
    return PathPairBatch.concat([batch, copies]), np.concatenate([labels, labels[source]])


def balance_images(images: np.ndarray, labels: np.ndarray, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """`balance_batch` for images already rendered: `(n + k, N, N, 3)` images and their labels."""
    images = np.asarray(images)
    labels = np.asarray(labels)
    source, transform = augmentation_plan(labels, seed)
    copies = [images[:0]]
    for t in np.unique(transform):
        copies.append(transform_grids(images[source[transform == t]], int(t)))
    order = np.concatenate([np.flatnonzero(transform == t) for t in np.unique(transform)] or [np.zeros(0, int)])
    extra = np.concatenate(copies)
    extra_labels = labels[source[order]]
    return np.concatenate([images, extra]), np.concatenate([labels, extra_labels])
