"""Row/column co-occurrence features, against loops written from their definition; the tuned classifiers on
them learn the FP/DP rule from labelled pairs."""

import json

import numpy as np
import pytest
import torch
from sklearn.metrics import balanced_accuracy_score, roc_auc_score

from vinadv.classify import balance_batch, label_batch, make_fp_classifier, render_batch
from vinadv.classify.cooccurrence import (
    FEATURES,
    cooccurrence,
    feature_shape,
    image_features,
    offset_cooccurrence,
    offset_matrix,
    torch_features,
)
from vinadv.classify.models import CNNImageClassifier, MLPImageClassifier, SVMImageClassifier
from vinadv.errors import InputError
from vinadv.grid.dihedral import transform_grids
from vinadv.testing.classify import synthetic_pairs

pytestmark = pytest.mark.slow


def _random_images(n: int, size: int, seed: int) -> np.ndarray:
    """Images with random red, green and blue cells (pure colours, as the encodings draw them)."""
    rng = np.random.default_rng(seed)
    colour = rng.choice(4, size=(n, size, size), p=[0.5, 0.2, 0.1, 0.2])  # black, red, green, blue
    palette = np.array([[0, 0, 0], [255, 0, 0], [0, 255, 0], [0, 0, 255]], dtype=np.uint8)
    return palette[colour]


def _loop_cooccurrence(image: np.ndarray) -> np.ndarray:
    size = image.shape[0]
    red = image[..., 0] > 0
    blue = image[..., 2] > 0
    out = np.zeros((2, size, size))
    for a in range(size):
        for b in range(size):
            out[0, a, b] = sum(red[i, a] and blue[i, b] for i in range(size))  # same row i
            out[1, a, b] = sum(red[a, j] and blue[b, j] for j in range(size))  # same column j
    return out


def _loop_offsets(image: np.ndarray) -> np.ndarray:
    size = image.shape[0]
    red = image[..., 0] > 0
    blue = image[..., 2] > 0
    out = np.zeros((2, 2 * size - 1))
    for i in range(size):
        for a in range(size):
            for b in range(size):
                out[0, b - a + size - 1] += red[i, a] and blue[i, b]  # columns a, b of row i
                out[1, b - a + size - 1] += red[a, i] and blue[b, i]  # rows a, b of column i
    return out


@pytest.mark.parametrize("size", [1, 5, 7])
def test_cooccurrence_and_offsets_match_loops(size):
    images = _random_images(6, size, seed=size)
    c = cooccurrence(images)
    p = offset_cooccurrence(images)
    assert c.shape == (6, 2, size, size) and c.dtype == np.float32
    assert p.shape == (6, 2, 2 * size - 1) and p.dtype == np.float32
    for k, image in enumerate(images):
        assert np.array_equal(c[k], _loop_cooccurrence(image))
        assert np.array_equal(p[k], _loop_offsets(image))


def test_features_of_rendered_pairs_see_the_rules_cell_sets():
    """In the split encoding, red/blue co-occurrence is about Do and Da: the largest offset with a pair in a row
    (column) is the rule's dh (dv)."""
    batch = synthetic_pairs(40, size=12, seed=3)
    result = label_batch(batch)
    keep = np.isin(result.labels, ("DP", "FP"))
    p = offset_cooccurrence(render_batch(batch.take(keep), "split"))
    offsets = np.abs(np.arange(-11, 12))
    dh = np.array([offsets[row > 0].max(initial=0) for row in p[:, 0]])
    dv = np.array([offsets[col > 0].max(initial=0) for col in p[:, 1]])
    assert np.array_equal(dh, result.dh[keep]) and np.array_equal(dv, result.dv[keep])


def test_transpose_swaps_rows_and_columns():
    images = _random_images(4, 6, seed=1)
    c = cooccurrence(images)
    t = cooccurrence(transform_grids(images, 6))
    assert np.array_equal(t[:, 0], c[:, 1]) and np.array_equal(t[:, 1], c[:, 0])


@pytest.mark.parametrize("features", FEATURES)
def test_image_features_are_presence_and_match_torch(features):
    images = _random_images(5, 6, seed=2)
    flat = image_features(images, features)
    assert flat.shape == (5, int(np.prod(feature_shape(features, 6)))) and set(np.unique(flat)) <= {0.0, 1.0}
    x = torch.from_numpy(images.transpose(0, 3, 1, 2).copy()).float() / 255.0
    tensor = torch_features(x, features, torch.from_numpy(offset_matrix(6))).numpy()
    assert tensor.shape == (5, *feature_shape(features, 6))
    if features == "pixels":  # the networks see channels first, the SVM (row, column, channel)
        tensor = tensor.transpose(0, 2, 3, 1)
    assert np.array_equal(tensor.reshape(5, -1), flat)


def test_bad_features_refused():
    images = _random_images(2, 4, seed=0)
    with pytest.raises(InputError, match="unknown features 'edges'"):
        image_features(images, "edges")
    with pytest.raises(InputError, match=r"\(n, N, N, 3\)"):
        cooccurrence(images[..., :2])
    batch = synthetic_pairs(30, size=10, seed=1)
    y = np.where(np.arange(len(batch)) % 2 == 0, "FP", "DP")
    with pytest.raises(InputError, match="unknown features"):
        SVMImageClassifier(features="edges").fit(batch, y)
    with pytest.raises(InputError, match="image-shaped inputs"):
        CNNImageClassifier(features="offsets", epochs=1).fit(batch, y)


@pytest.fixture(scope="module")
def rule_pairs():
    """Synthetic FP/DP pairs on 16x16 maps with their rule labels (t=2): a balanced training set and an
    independent test set with the real (imbalanced) mix."""
    train = synthetic_pairs(1500, size=16, seed=1)
    test = synthetic_pairs(1000, size=16, seed=2)
    y_train, y_test = label_batch(train).labels, label_batch(test).labels
    keep_train, keep_test = np.isin(y_train, ("DP", "FP")), np.isin(y_test, ("DP", "FP"))
    X, y = balance_batch(train.take(keep_train), y_train[keep_train])
    Xt, yt = test.take(keep_test), y_test[keep_test]
    assert (yt == "FP").sum() >= 30
    return X, y, Xt, yt


@pytest.mark.parametrize("kind", ["svm", "mlp"])
def test_tuned_classifiers_learn_the_rule(rule_pairs, kind):
    X, y, Xt, yt = rule_pairs
    model = make_fp_classifier(kind, "tuned")
    if kind == "mlp":
        model.set_params(epochs=4)  # short, for the test's time: 4 epochs score 0.999 and 1.0 on these pairs
    model.fit(X, y)
    assert balanced_accuracy_score(yt, model.predict(Xt)) >= 0.97
    assert roc_auc_score(yt == "FP", model.decision_function(Xt)) >= 0.99


@pytest.mark.parametrize(
    "make",
    [
        lambda: SVMImageClassifier(C=10.0, encoding="split", features="offsets"),
        lambda: SVMImageClassifier(encoding="split", features="cooccurrence"),
        lambda: MLPImageClassifier(
            width=8, epochs=1, batch_size=32, augment=True, encoding="split", features="offsets"
        ),
        lambda: MLPImageClassifier(width=8, epochs=1, batch_size=32, encoding="split", features="cooccurrence"),
        lambda: CNNImageClassifier(width=4, epochs=1, batch_size=32, encoding="split", features="cooccurrence"),
    ],
    ids=["svm-offsets", "svm-cooccurrence", "mlp-offsets", "mlp-cooccurrence", "cnn-cooccurrence"],
)
def test_feature_models_round_trip(rule_pairs, make, tmp_path):
    X, y, Xt, _ = rule_pairs
    X, y = X.take(np.arange(0, len(X), 4)), y[::4]
    model = make().fit(X, y)
    params = model.get_params()
    assert params["features"] == model.features and params["encoding"] == "split"
    path = tmp_path / "model.npz"
    model.save(path)
    loaded = type(model).load(path)
    assert loaded.get_params() == params
    assert np.array_equal(loaded.decision_function(Xt), model.decision_function(Xt))
    assert np.array_equal(loaded.predict(Xt), model.predict(Xt))
    # images in, same answer as pairs in
    assert np.array_equal(model.decision_function(render_batch(Xt, "split")), model.decision_function(Xt))


def test_model_files_from_before_features_load_as_pixels(rule_pairs, tmp_path):
    """Files written before the `features` parameter existed have no such entry: they are pixel models."""
    X, y, Xt, _ = rule_pairs
    X, y = X.take(np.arange(0, len(X), 8)), y[::8]
    model = SVMImageClassifier().fit(X, y)
    path = tmp_path / "old.npz"
    model.save(path)
    with np.load(path, allow_pickle=False) as archive:
        entries = {k: archive[k] for k in archive.files}
    params = json.loads(str(entries["params"]))
    del params["features"]
    entries["params"] = np.array(json.dumps(params))
    with open(path, "wb") as handle:
        np.savez(handle, **entries)
    loaded = SVMImageClassifier.load(path)
    assert loaded.features == "pixels"
    assert np.array_equal(loaded.decision_function(Xt), model.decision_function(Xt))
