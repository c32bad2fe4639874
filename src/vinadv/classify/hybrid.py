"""Five-way pair classifiers: the paper's hybrid (path features, then an FP/DP classifier), and the rule.

Both take a `PathPairBatch` and predict the DESIGN.md labels ('invalid', 'UrP', 'UcP', 'DP', 'FP').
`fp_decision(X)` gives the FP score of pairs that reach the FP/DP stage (NaN for the others).
"""

from __future__ import annotations

import numpy as np

from vinadv.classify.base import PairClassifier, model_from_state, pack_state, register_kind
from vinadv.classify.batch import PathPairBatch
from vinadv.classify.features import path_features
from vinadv.classify.models import CNNImageClassifier, MLPImageClassifier, SVMImageClassifier
from vinadv.classify.rule import default_threshold, label_batch
from vinadv.classify.similarity import DistanceThresholdClassifier
from vinadv.errors import InputError
from vinadv.vocabulary import FORK_OR_DETOUR, LABELS

FP_DP_KINDS = ("svm", "cnn", "mlp", "hausdorff", "frechet", "dtw")
SETTINGS = ("baseline", "tuned")
#: the tuned setting's training options, shared by its CNN and MLP
TUNED_TRAINING = dict(
    batch_size=64,
    learning_rate=3e-3,
    weight_decay=1e-4,
    optimizer="adamw",
    schedule="cosine",
    augment=True,
    encoding="split",
)


def make_fp_classifier(kind: str, setting: str = "baseline", seed: int = 0, verbose: bool = False) -> PairClassifier:
    """A fresh FP/DP classifier of `kind` with the hyperparameters of `setting`.

    baseline: the paper's setting (SVC defaults on pixels; CNN and MLP 10 epochs at batch 64 with Adam).
    tuned: vinadv's 'split' path images (cells on both paths green, so red is the rule's Do and blue its Da)
    and row/column co-occurrence features of them (`vinadv.classify.cooccurrence`): SVM C=10 on the offsets
    at which red and blue cells share a row or a column; CNN on the row and column co-occurrence maps; MLP on
    the offsets; CNN and MLP with flip/rotation augmentation, AdamW and a cosine learning-rate schedule.
    Distance baselines have no setting.
    """
    if setting not in SETTINGS:
        raise InputError(f"unknown setting {setting!r}; choose from {list(SETTINGS)}")
    if kind == "svm":
        if setting == "baseline":
            return SVMImageClassifier(C=1.0)
        return SVMImageClassifier(C=10.0, encoding="split", features="offsets")
    if kind == "cnn":
        if setting == "baseline":
            return CNNImageClassifier("plain", width=32, epochs=10, batch_size=64, seed=seed, verbose=verbose)
        return CNNImageClassifier(
            "plain", width=16, epochs=10, features="cooccurrence", seed=seed, verbose=verbose, **TUNED_TRAINING
        )
    if kind == "mlp":
        if setting == "baseline":
            return MLPImageClassifier("plain", width=512, epochs=10, batch_size=64, seed=seed, verbose=verbose)
        return MLPImageClassifier(
            "plain", width=64, epochs=20, features="offsets", seed=seed, verbose=verbose, **TUNED_TRAINING
        )
    if kind in ("hausdorff", "frechet", "dtw"):
        return DistanceThresholdClassifier(kind)
    raise InputError(f"unknown classifier {kind!r}; choose from {list(FP_DP_KINDS)}")


def _check_batch(X) -> PathPairBatch:
    if not isinstance(X, PathPairBatch):
        raise InputError("five-way classifiers need path pairs (a PathPairBatch)")
    return X


class _FiveWay(PairClassifier):
    def _check_labels(self, X, y) -> np.ndarray:
        y, bad = self._label_array(X, y, LABELS)
        if bad:
            raise InputError(f"unknown labels {bad}; labels are {list(LABELS)}")
        self.classes_ = np.array(LABELS)
        return y


@register_kind("hybrid")
class HybridClassifier(_FiveWay):
    """The paper's classifier: invalid/UrP/UcP by path features, then `fp_classifier` for the rest (DP/FP).

    `fit(X, y)`: `y` are five-way labels (from the rule labeller or from people; `None` = the rule with
    threshold `t`); the FP/DP classifier is trained on the pairs labelled DP or FP.
    """

    kind = "hybrid"

    def __init__(self, fp_classifier: PairClassifier | None = None, t: int | None = None):
        self.fp_classifier = fp_classifier
        self.t = t

    def fit(self, X, y=None) -> HybridClassifier:
        X = _check_batch(X)
        if self.fp_classifier is None:
            raise InputError("HybridClassifier needs an fp_classifier")
        y = label_batch(X, self.t).labels if y is None else self._check_labels(X, y)
        self.classes_ = np.array(LABELS)
        rest = np.isin(y, FORK_OR_DETOUR)
        self.fp_classifier.fit(X.take(rest), y[rest])
        self.size_ = X.size
        self.training_time_s_ = getattr(self.fp_classifier, "training_time_s_", 0.0)
        return self

    def fp_decision(self, X) -> np.ndarray:
        """FP score of the pairs the features leave to the FP/DP classifier, NaN for the others: `(n,)`."""
        X = _check_batch(X)
        rest = path_features(X.path_o, X.path_a, X.goals).rest
        out = np.full(len(X), np.nan)
        if rest.any():
            out[rest] = self.fp_classifier.decision_function(X.take(rest))
        return out

    def predict(self, X) -> np.ndarray:
        """Five-way labels `(n,)` str."""
        X = _check_batch(X)
        features = path_features(X.path_o, X.path_a, X.goals)
        labels = np.full(len(X), "DP", dtype="<U7")
        rest = features.rest
        if rest.any():
            labels[rest] = self.fp_classifier.predict(X.take(rest))
        labels[features.unchanged] = "UcP"
        labels[features.unreached] = "UrP"
        labels[features.invalid] = "invalid"
        return labels

    def decision_function(self, X) -> np.ndarray:
        return self.fp_decision(X)

    def _json_params(self) -> dict:
        return {"t": self.t}

    def _state(self):
        if self.fp_classifier is None:
            raise InputError("HybridClassifier needs an fp_classifier")
        header, arrays = pack_state(self.fp_classifier)
        return {"inner": header}, {f"inner.{k}": v for k, v in arrays.items()}

    @classmethod
    def _from_state(cls, kind, params, meta, arrays):
        inner = model_from_state(meta["inner"], {k[6:]: v for k, v in arrays.items() if k.startswith("inner.")})
        model = cls(inner, **params)
        model.classes_ = np.array(LABELS)
        model.training_time_s_ = getattr(inner, "training_time_s_", 0.0)
        return model


@register_kind("rule")
class RuleClassifier(_FiveWay):
    """The exact rule labeller as a classifier: `fit` learns nothing; `t=None` means `round(4 * N / 28)`."""

    kind = "rule"

    def __init__(self, t: int | None = None):
        self.t = t

    def fit(self, X, y=None) -> RuleClassifier:
        X = _check_batch(X)
        if y is not None:
            self._check_labels(X, y)
        self.classes_ = np.array(LABELS)
        self.training_time_s_ = 0.0
        return self

    def predict(self, X) -> np.ndarray:
        return label_batch(_check_batch(X), self.t).labels

    def fp_decision(self, X) -> np.ndarray:
        """`max(dh, dv) - t - 0.5` for the pairs that reach the FP/DP stage (positive = FP), NaN for the others."""
        X = _check_batch(X)
        result = label_batch(X, self.t)
        t = default_threshold(X.size) if self.t is None else self.t
        score = np.maximum(result.dh, result.dv) - t - 0.5
        return np.where(np.isin(result.labels, FORK_OR_DETOUR), score, np.nan)

    def decision_function(self, X) -> np.ndarray:
        return self.fp_decision(X)

    def _state(self):
        return {}, {}

    @classmethod
    def _from_state(cls, kind, params, meta, arrays):
        model = cls(**params)
        model.classes_ = np.array(LABELS)
        model.training_time_s_ = 0.0
        return model
