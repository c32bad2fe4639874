"""Image classifiers, hybrid and rule classifiers, model files."""

import numpy as np
import pytest
import scipy.sparse
from sklearn.svm import SVC

from vinadv.classify import (
    HybridClassifier,
    RuleClassifier,
    SVMImageClassifier,
    label_batch,
    load_model,
    make_fp_classifier,
    render_batch,
)
from vinadv.classify.base import MODEL_FORMAT
from vinadv.classify.models import CNNImageClassifier, MLPImageClassifier
from vinadv.errors import InputError
from vinadv.testing.classify import synthetic_pairs

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def pairs():
    """Synthetic pairs on 12x12 maps (all five labels), and the FP/DP ones with their rule labels."""
    batch = synthetic_pairs(160, size=12, seed=5, mix=True)
    labels = label_batch(batch).labels
    fp_dp = np.flatnonzero(np.isin(labels, ("DP", "FP")))
    assert {"DP", "FP"} <= set(labels[fp_dp].tolist())
    return batch, labels, batch.take(fp_dp), labels[fp_dp]


def test_svm_decision_equals_sklearn_svc(pairs):
    _, _, X, y = pairs
    model = SVMImageClassifier(C=3.0).fit(X, y)
    flat = render_batch(X).reshape(len(X), -1) / 255.0
    reference = SVC(C=3.0, kernel="rbf", gamma="scale").fit(scipy.sparse.csr_matrix(flat), y)
    assert np.allclose(model.decision_function(X), reference.decision_function(flat), atol=1e-6)
    assert np.array_equal(model.predict(X), reference.predict(flat))
    # images in, same answer as pairs in
    assert np.array_equal(model.decision_function(render_batch(X)), model.decision_function(X))


TINY = {
    "svm": lambda: make_fp_classifier("svm", "tuned"),
    "cnn": lambda: CNNImageClassifier("plain", width=4, epochs=1, batch_size=16),
    "cnn-rowcol": lambda: CNNImageClassifier(
        "rowcol", width=4, epochs=2, batch_size=16, augment=True, encoding="split", optimizer="adamw", schedule="cosine"
    ),
    "mlp": lambda: MLPImageClassifier("plain", width=16, epochs=2, batch_size=16, augment=True),
    "hausdorff": lambda: make_fp_classifier("hausdorff"),
    "frechet": lambda: make_fp_classifier("frechet"),
    "dtw": lambda: make_fp_classifier("dtw"),
}


@pytest.mark.parametrize("name", sorted(TINY))
def test_fit_predict_and_save_load_round_trip(pairs, name, tmp_path):
    _, _, X, y = pairs
    model = TINY[name]().fit(X, y)
    assert set(np.unique(model.predict(X))) <= {"DP", "FP"}
    assert model.get_params()  # scikit-learn API
    path = tmp_path / "model.bin"
    model.save(path)
    loaded = type(model).load(path)
    assert loaded.get_params() == model.get_params()
    assert np.array_equal(loaded.decision_function(X), model.decision_function(X))
    assert np.array_equal(loaded.predict(X), model.predict(X))
    assert path.exists() and not (tmp_path / "model.bin.npz").exists()


def test_torch_training_is_seeded(pairs):
    _, _, X, y = pairs
    a = MLPImageClassifier(width=8, epochs=1, batch_size=16, seed=3).fit(X, y).decision_function(X)
    b = MLPImageClassifier(width=8, epochs=1, batch_size=16, seed=3).fit(X, y).decision_function(X)
    assert np.array_equal(a, b)
    proba = MLPImageClassifier(width=8, epochs=1, seed=3).fit(X, y).predict_proba(X)
    assert proba.shape == (len(X), 2) and np.allclose(proba.sum(1), 1)


def test_hybrid_uses_features_then_classifier(pairs, tmp_path):
    batch, labels, _, _ = pairs
    hybrid = HybridClassifier(make_fp_classifier("hausdorff")).fit(batch, labels)
    predicted = hybrid.predict(batch)
    feature_labelled = np.isin(labels, ("invalid", "UrP", "UcP"))
    assert np.array_equal(predicted[feature_labelled], labels[feature_labelled])
    rest = ~feature_labelled
    assert np.array_equal(predicted[rest], hybrid.fp_classifier.predict(batch.take(rest)))
    assert np.isnan(hybrid.fp_decision(batch)[feature_labelled]).all()
    # with no labels given, the hybrid trains on the rule's
    assert np.array_equal(HybridClassifier(make_fp_classifier("hausdorff")).fit(batch).predict(batch), predicted)
    hybrid.save(tmp_path / "hybrid.npz", record={"seed": 1}, record_arrays={"test_index": np.arange(3)})
    loaded = load_model(tmp_path / "hybrid.npz")
    assert isinstance(loaded, HybridClassifier)
    assert np.array_equal(loaded.predict(batch), predicted)
    assert loaded.record_ == {"seed": 1} and loaded.record_arrays_["test_index"].tolist() == [0, 1, 2]


def test_rule_classifier_is_the_labeller(pairs, tmp_path):
    batch, labels, _, _ = pairs
    rule = RuleClassifier().fit(batch)
    assert np.array_equal(rule.predict(batch), labels)
    decision = rule.fp_decision(batch)
    rest = np.isin(labels, ("DP", "FP"))
    assert np.array_equal(decision[rest] > 0, labels[rest] == "FP")
    rule.save(tmp_path / "rule.npz")
    assert np.array_equal(RuleClassifier.load(tmp_path / "rule.npz").predict(batch), labels)


def _rewrite(path, **changes):
    with np.load(path, allow_pickle=False) as archive:
        entries = {k: archive[k] for k in archive.files}
    entries.update({k: np.array(v) for k, v in changes.items()})
    with open(path, "wb") as handle:
        np.savez(handle, **entries)


def test_wrong_version_or_kind_refused(pairs, tmp_path):
    _, _, X, y = pairs
    path = tmp_path / "m.npz"
    make_fp_classifier("hausdorff").fit(X, y).save(path)
    with pytest.raises(InputError, match="holds a 'hausdorff' model, not a SVMImageClassifier"):
        SVMImageClassifier.load(path)
    _rewrite(path, format="vinadv.classifier/2")
    with pytest.raises(InputError, match=r"model format 'vinadv.classifier/2'.*vinadv.classifier/1"):
        load_model(path)
    _rewrite(path, format=MODEL_FORMAT, kind="forest")
    with pytest.raises(InputError, match="unknown model kind 'forest'"):
        load_model(path)
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(InputError, match="not a vinadv model file"):
        load_model(tmp_path / "junk.npz")
    np.savez(tmp_path / "other.npz", x=np.arange(3))
    with pytest.raises(InputError, match="no 'format'"):
        load_model(tmp_path / "other.npz")


def test_bad_labels_refused(pairs):
    _, _, X, y = pairs
    with pytest.raises(InputError, match="labels"):
        SVMImageClassifier().fit(X, np.where(y == "FP", "UrP", y))
    with pytest.raises(InputError, match="both classes"):
        SVMImageClassifier().fit(X, np.full(len(X), "DP"))
    with pytest.raises(InputError, match="unknown classifier"):
        make_fp_classifier("forest")


def test_model_trained_on_other_size_refused(pairs):
    _, _, X, y = pairs
    model = SVMImageClassifier().fit(X, y)
    other = synthetic_pairs(4, size=10, seed=1)
    with pytest.raises(InputError, match="12x12"):
        model.predict(other)
