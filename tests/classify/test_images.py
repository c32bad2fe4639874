import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from vinadv.classify.batch import PathPairBatch
from vinadv.classify.images import (
    augmentation_plan,
    balance_batch,
    balance_images,
    render_batch,
)
from vinadv.classify.rule import label_batch
from vinadv.grid.dihedral import transform_grids

from .oracle import path_pairs


def test_path_image_colours_red_on_top_of_blue():
    o = np.array([[0, 0], [1, 1], [2, 2]])
    a = np.array([[0, 0], [1, 0], [2, 1], [2, 2]])
    image = render_batch(PathPairBatch.from_paths([o], [a], [(2, 2)], 4))[0]
    assert image.dtype == np.uint8 and image.shape == (4, 4, 3)
    red, blue, black = [255, 0, 0], [0, 0, 255], [0, 0, 0]
    expected = np.zeros((4, 4, 3), dtype=np.uint8)
    for r, c in a:
        expected[r, c] = blue
    for r, c in o:
        expected[r, c] = red
    assert np.array_equal(image, expected)
    assert image[1, 0].tolist() == blue and image[0, 0].tolist() == red and image[3, 3].tolist() == black


@settings(max_examples=40, deadline=None)
@given(path_pairs(), st.integers(0, 7))
def test_rendering_commutes_with_transforms(batch, k):
    assert np.array_equal(render_batch(batch.transformed(k)), transform_grids(render_batch(batch), k))


def test_augmentation_plan_balances_with_distinct_copies():
    labels = np.array(["DP"] * 20 + ["FP"] * 3)
    source, transform = augmentation_plan(labels, seed=1)
    assert len(source) == 17
    assert set(labels[source]) == {"FP"}
    assert set(transform.tolist()) <= {1, 2, 3, 4, 5}
    assert len(set(zip(source.tolist(), transform.tolist()))) == 15  # 3 x 5 distinct, then repeats
    again = augmentation_plan(labels, seed=1)
    assert np.array_equal(again[0], source) and np.array_equal(again[1], transform)


@settings(max_examples=30, deadline=None)
@given(path_pairs(max_pairs=8), st.integers(0, 100))
def test_augmentation_keeps_labels(batch, seed):
    labels = label_batch(batch).labels
    balanced, new_labels = balance_batch(batch, labels, seed)
    _, counts = np.unique(new_labels, return_counts=True)
    assert len(set(counts.tolist())) == 1
    # the rule gives each flipped/rotated copy the label of its source
    assert label_batch(balanced).labels.tolist() == new_labels.tolist()
    images, image_labels = balance_images(render_batch(batch), labels, seed)
    assert sorted(image_labels.tolist()) == sorted(new_labels.tolist())
    assert np.array_equal(
        np.sort(images.reshape(len(images), -1), axis=0),
        np.sort(render_batch(balanced).reshape(len(images), -1), axis=0),
    )


def test_split_encoding_marks_shared_cells_green():
    o = np.array([[0, 0], [1, 1], [2, 2]])
    a = np.array([[0, 0], [1, 0], [2, 1], [2, 2]])
    image = render_batch(PathPairBatch.from_paths([o], [a], [(2, 2)], 4), encoding="split")[0]
    assert image[0, 0].tolist() == [0, 255, 0] and image[2, 2].tolist() == [0, 255, 0]
    assert image[1, 1].tolist() == [255, 0, 0] and image[1, 0].tolist() == [0, 0, 255]
    assert image[3, 3].tolist() == [0, 0, 0]


@settings(max_examples=20, deadline=None)
@given(path_pairs(), st.integers(0, 7))
def test_split_rendering_commutes_with_transforms(batch, k):
    assert np.array_equal(render_batch(batch.transformed(k), "split"), transform_grids(render_batch(batch, "split"), k))
