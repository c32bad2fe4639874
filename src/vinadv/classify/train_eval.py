"""Training and evaluating a five-way classifier on labelled path pairs: the work behind `vinadv classify train`
and `vinadv classify eval`, callable from Python.

Training: the FP/DP pairs are split (stratified, `test_fraction` held out), the training part optionally balanced
by flipped/rotated copies of the minority class, and an FP/DP model is fitted inside the paper's hybrid (path
features first). Evaluation: FP/DP figures on the held-out split of the training file (or on all FP/DP pairs of
another file), and the five-way labels of every pair the model did not train on, against the rule.
"""

from __future__ import annotations

import time

import numpy as np

from vinadv.classify.batch import PathPairBatch
from vinadv.classify.hybrid import HybridClassifier, RuleClassifier, make_fp_classifier
from vinadv.classify.images import balance_batch
from vinadv.classify.metrics import binary_metrics
from vinadv.classify.rule import default_threshold, label_batch
from vinadv.errors import InputError
from vinadv.vocabulary import FORK_OR_DETOUR


def label_counts_of(labels) -> dict:
    """`{label: count}` of the labels present, in sorted order."""
    values, counts = np.unique(np.asarray(labels), return_counts=True)
    return {str(v): int(c) for v, c in zip(values, counts)}


def train_classifier(
    batch: PathPairBatch,
    labels: np.ndarray,
    *,
    model: str,
    setting: str = "baseline",
    threshold: int | None = None,
    balance: bool = False,
    test_fraction: float = 0.0,
    seed: int = 0,
    source: str = "pairs",
    verbose: bool = False,
) -> tuple[HybridClassifier, dict, dict]:
    """Fit an FP/DP `model` (a `make_fp_classifier` kind) inside the hybrid on the FP/DP pairs of `batch`.

    `labels`: `(n,)` str, one per pair (the rule's or people's); `source` names them in errors and the record.
    Returns `(hybrid, record, arrays)`: the record (JSON-able: counts, settings, training time) and the
    split (`train_index`, `test_index` into `batch`), as `HybridClassifier.save` stores them.
    """
    from sklearn.model_selection import train_test_split

    if not 0.0 <= test_fraction < 1.0:
        raise InputError(f"test_fraction must be in [0, 1), got {test_fraction}", "test_fraction")
    labels = np.asarray(labels)
    t = default_threshold(batch.size) if threshold is None else threshold
    fp_dp = np.flatnonzero(np.isin(labels, FORK_OR_DETOUR))
    counts = label_counts_of(labels[fp_dp])
    need = 2 if test_fraction > 0 else 1
    if counts.get("DP", 0) < need or counts.get("FP", 0) < need:
        raise InputError(
            f"{source}: training needs at least {need} FP and {need} DP pairs, "
            f"the file has {counts.get('FP', 0)} FP and {counts.get('DP', 0)} DP"
        )
    if test_fraction > 0:
        train_index, test_index = train_test_split(
            fp_dp, test_size=test_fraction, stratify=labels[fp_dp], random_state=seed
        )
        train_index, test_index = np.sort(train_index), np.sort(test_index)
    else:
        train_index, test_index = fp_dp, np.zeros(0, dtype=np.int64)
    train_batch, train_labels = batch.take(train_index), labels[train_index]
    if balance:
        train_batch, train_labels = balance_batch(train_batch, train_labels, seed=seed)
    hybrid = HybridClassifier(make_fp_classifier(model, setting, seed, verbose=verbose), t=t)
    start = time.perf_counter()
    hybrid.fit(train_batch, train_labels)
    seconds = time.perf_counter() - start
    record = {
        "pairs": str(source),
        "pairs_fingerprint": batch.fingerprint(),
        "n_pairs": len(batch),
        "size": batch.size,
        "threshold": t,
        "model": model,
        "setting": setting,
        "balance": bool(balance),
        "seed": seed,
        "test_fraction": test_fraction,
        "train_counts": label_counts_of(labels[train_index]),
        "train_counts_balanced": label_counts_of(train_labels),
        "test_counts": label_counts_of(labels[test_index]),
        "training_seconds": round(seconds, 3),
    }
    return hybrid, record, {"train_index": train_index, "test_index": test_index}


def as_hybrid(model) -> HybridClassifier | RuleClassifier:
    """A loaded model as a five-way classifier: an FP/DP model goes inside the hybrid with its training record."""
    if isinstance(model, (HybridClassifier, RuleClassifier)):
        return model
    record, arrays = model.record_, model.record_arrays_
    hybrid = HybridClassifier(model, t=record.get("threshold"))
    hybrid.record_, hybrid.record_arrays_ = record, arrays
    return hybrid


def evaluate_classifier(
    model: HybridClassifier | RuleClassifier, batch: PathPairBatch, *, all_pairs: bool = False, source: str = "pairs"
) -> dict:
    """The figures of `model` (`as_hybrid` of a loaded model) on `batch`, against the rule's labels.

    On the file the model was trained on (same fingerprint), FP/DP figures are on its held-out split unless
    `all_pairs`; elsewhere on all FP/DP pairs. Five-way figures cover every pair it did not train on.
    """
    record = getattr(model, "record_", {}) or {}
    arrays = getattr(model, "record_arrays_", {}) or {}
    t = model.t if model.t is not None else default_threshold(batch.size)
    truth = label_batch(batch, t).labels
    same_file = record.get("pairs_fingerprint") == batch.fingerprint()
    none = np.zeros(0, np.int64)
    train_index = arrays.get("train_index", none) if same_file else none
    if same_file and not all_pairs:
        eval_index = arrays.get("test_index", none).astype(np.int64)
        scope = "held-out test split of the training file"
    else:
        eval_index = np.flatnonzero(np.isin(truth, FORK_OR_DETOUR))
        scope = "all FP/DP pairs of the file" + (" (including training pairs)" if same_file else "")
    if len(eval_index) == 0:
        raise InputError(f"{source}: no FP/DP pairs to evaluate on ({scope})")

    subset = batch.take(eval_index)
    start = time.perf_counter()
    predicted = model.predict(subset)
    predict_seconds = time.perf_counter() - start
    figures = binary_metrics(truth[eval_index], predicted, model.fp_decision(subset))

    # the five-way labels of every pair the model did not train on (features + classifier, against the rule)
    unseen = np.setdiff1d(np.arange(len(batch)), train_index)
    start = time.perf_counter()
    five_way = model.predict(batch.take(unseen))
    five_way_seconds = time.perf_counter() - start
    return {
        "pairs": str(source),
        "kind": record.get("model", model.kind),
        "setting": record.get("setting"),
        "threshold": t,
        "scope": scope,
        "fp_dp": figures,
        "training_time_s": getattr(model, "training_time_s_", None),
        "prediction_seconds_per_100_pairs": round(100 * predict_seconds / len(eval_index), 6),
        "five_way": {
            "n": int(len(unseen)),
            "accuracy": float(np.mean(five_way == truth[unseen])) if len(unseen) else None,
            "truth_counts": label_counts_of(truth[unseen]),
            "predicted_counts": label_counts_of(five_way),
            "prediction_seconds_per_100_pairs": round(100 * five_way_seconds / max(len(unseen), 1), 6),
        },
    }
