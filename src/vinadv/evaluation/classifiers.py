"""`vinadv evaluate`: the paper's classifier comparison (section 5.2) on a stored run, stored for the report.

Data: the run's FP/DP pairs, with the truth from the exact rule labeller (`t = round(4 * N / 28)`; stored labels may
come from a classifier, so they are recomputed). Split 7:3 stratified by label (`seed`). Each FP/DP classifier is
trained twice on the training split: balanced by flipped/rotated copies of minority-class pairs (paper, tables 5 and
6, fig. 9 right), and as it is (fig. 9 left); both are tested on the untouched test split (the real mix). For
fig. 8 the balanced training is repeated on nested, stratified fractions of the training split (each class keeps
at least one pair). `hybrid` is the paper's whole classifier (path features, then an SVM of `setting`) and `rule`
the exact labeller; both are also run five-way on every stored pair they did not train on, and timed on the
paper's 100-pair mix (40 FP/DP pairs of the test split, 60 UrP/UcP pairs).

Every result is one row of the `evaluations` table: metrics (accuracy, per-class precision/recall/F1, ROC AUC, AP,
confusion matrix, training seconds, prediction seconds per 100 pairs) and, at the full training set, the ROC and
PR curve points.
"""

from __future__ import annotations

import time
import uuid
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vinadv.classify import (
    FP_DP_KINDS,
    HybridClassifier,
    PathPairBatch,
    RuleClassifier,
    balance_batch,
    binary_metrics,
    default_threshold,
    label_batch,
    make_fp_classifier,
)
from vinadv.errors import InputError
from vinadv.vocabulary import FORK_OR_DETOUR

CLASSIFIERS = (*FP_DP_KINDS, "hybrid", "rule")
SETTINGS = ("baseline", "tuned")
DEFAULT_SIZES = (0.1, 0.2, 0.4, 0.6, 0.8, 1.0)
TEST_FRACTION = 0.3
#: the paper's timing set: 40 FP/DP pairs of the test split and 60 UrP/UcP pairs (section 5.2, table 7)
PAPER_MIX = (40, 60)
#: at most this many non-FP/DP pairs are read for the five-way check (a sample, for very large runs)
MAX_OTHER_PAIRS = 5000
CURVE_POINTS = 200
TIMING_REPEATS = 5


@dataclass
class RunPairs:
    """The pairs of a run that an evaluation needs.

    `batch` holds the FP/DP pairs first (`n_fp_dp` of them), then a sample of the others; `truth` `(n,)` the rule
    labels; `pair_index` `(n,)` the stored pair indices; `t` the rule threshold; `label_source` the run's labellers.
    """

    batch: PathPairBatch
    truth: np.ndarray
    pair_index: np.ndarray
    n_fp_dp: int
    t: int

    @property
    def fp_dp(self) -> np.ndarray:
        return np.arange(self.n_fp_dp)


def batch_of(records) -> PathPairBatch:
    """The path pairs of stored `PairRecords`, as the classifiers take them."""
    return PathPairBatch.from_pairs(records)


def load_run_pairs(store, run_id: int, seed: int = 0, max_other: int = MAX_OTHER_PAIRS) -> RunPairs:
    """Read the run's FP/DP pairs and up to `max_other` other pairs (a seeded sample) with their rule labels."""
    from vinadv.store import PairRecords  # noqa: PLC0415 (SQLAlchemy)

    index, labels = store.pair_labels(run_id)
    if not len(index):
        raise InputError(f"run {run_id} has no stored pairs to evaluate on")
    # the feature stage is exact whatever labelled the run, so the stored FP/DP set is the rule's FP/DP set
    fp_dp = np.sort(index[np.isin(labels, FORK_OR_DETOUR)])
    others = np.sort(index[~np.isin(labels, FORK_OR_DETOUR)])
    if len(others) > max_other:
        others = np.sort(np.random.default_rng(seed).choice(others, max_other, replace=False))
    parts = [store.read_pairs(run_id, pair_indices=part) for part in (fp_dp, others) if len(part)]
    records = PairRecords.concat(parts)
    batch = batch_of(records)
    t = default_threshold(batch.size)
    truth = label_batch(batch, t).labels
    return RunPairs(batch, truth, records.pair_index, len(fp_dp), t)


def split_fp_dp(
    truth: np.ndarray, seed: int = 0, test_fraction: float = TEST_FRACTION, source: str = "run"
) -> tuple[np.ndarray, np.ndarray]:
    """Stratified train/test split of the FP/DP positions of `truth`: `(train, test)` sorted int64 indices."""
    from sklearn.model_selection import train_test_split

    fp_dp = np.flatnonzero(np.isin(truth, FORK_OR_DETOUR))
    n_fp, n_dp = int(np.sum(truth == "FP")), int(np.sum(truth == "DP"))
    if n_fp < 2 or n_dp < 2:
        raise InputError(
            f"{source} has {n_fp} FP and {n_dp} DP pairs; the classifier comparison needs at least 2 "
            "of each (a larger --n, or another attack strategy)"
        )
    train, test = train_test_split(fp_dp, test_size=test_fraction, stratify=truth[fp_dp], random_state=seed)
    return np.sort(train), np.sort(test)


def nested_fraction(train: np.ndarray, truth: np.ndarray, fraction: float, seed: int = 0) -> np.ndarray:
    """A stratified subset of `train` with `fraction` of each class (at least one pair per class); the subsets of
    growing fractions are nested (prefixes of one seeded permutation per class)."""
    rng = np.random.default_rng(seed)
    chosen = []
    for cls in FORK_OR_DETOUR:
        members = rng.permutation(train[truth[train] == cls])
        chosen.append(members[: max(1, int(round(fraction * len(members))))])
    return np.sort(np.concatenate(chosen))


def paper_mix(truth: np.ndarray, test: np.ndarray, seed: int = 0) -> np.ndarray:
    """The paper's 100 timing pairs: 40 FP/DP pairs of `test` and 60 UrP/UcP pairs (fewer when the run lacks
    them; the rest then comes from the other group), as positions into `truth`."""
    rng = np.random.default_rng(seed)
    fd_all = rng.permutation(test)
    other_all = rng.permutation(np.flatnonzero(np.isin(truth, ("UrP", "UcP"))))
    total = sum(PAPER_MIX)
    n_fd = min(PAPER_MIX[0], len(fd_all))
    n_other = min(total - n_fd, len(other_all))
    n_fd = min(total - n_other, len(fd_all))
    fd, other = fd_all[:n_fd], other_all[:n_other]
    return np.concatenate([fd, other])


def _curve_points(positive: np.ndarray, scores: np.ndarray) -> dict | None:
    from sklearn.metrics import precision_recall_curve, roc_curve

    if len(np.unique(positive)) < 2:
        return None
    fpr, tpr, _ = roc_curve(positive, scores)
    precision, recall, _ = precision_recall_curve(positive, scores)

    def thin(*arrays):
        n = len(arrays[0])
        keep = np.unique(np.linspace(0, n - 1, min(n, CURVE_POINTS)).round().astype(int))
        return [np.round(a[keep], 6).tolist() for a in arrays]

    fpr, tpr = thin(fpr, tpr)
    precision, recall = thin(precision, recall)
    return {"roc": {"fpr": fpr, "tpr": tpr}, "pr": {"precision": precision, "recall": recall}}


def median_seconds(fn, repeats: int = TIMING_REPEATS) -> float:
    """Median wall time of `repeats` calls of `fn`, in seconds."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def _counts(labels) -> dict:
    values, counts = np.unique(np.asarray(labels), return_counts=True)
    return {str(v): int(c) for v, c in zip(values, counts)}


def _score(model, batch: PathPairBatch) -> np.ndarray:
    if isinstance(model, (HybridClassifier, RuleClassifier)):
        return model.fp_decision(batch)
    return model.decision_function(batch)


def evaluate_model(
    model, data: RunPairs, train: np.ndarray, test: np.ndarray, balanced: bool, seed: int = 0, curves: bool = True
) -> tuple[dict, dict | None, int]:
    """Fit `model` on the pairs `train` (balanced by augmentation if asked), test on `test`.

    Returns `(metrics, curves or None, training set size)`.
    """
    train_batch, train_labels = data.batch.take(train), data.truth[train]
    if balanced:
        train_batch, train_labels = balance_batch(train_batch, train_labels, seed=seed)
    start = time.perf_counter()
    model.fit(train_batch, train_labels)
    training_s = time.perf_counter() - start
    test_batch, truth = data.batch.take(test), data.truth[test]
    start = time.perf_counter()
    predicted = model.predict(test_batch)
    predict_s = time.perf_counter() - start
    scores = _score(model, test_batch)
    metrics = binary_metrics(truth, predicted, scores)
    metrics.update(
        training_s=training_s,
        prediction_s_per_100=100.0 * predict_s / max(len(test), 1),
        train_counts=_counts(data.truth[train]),
        train_counts_used=_counts(train_labels),
        test_counts=_counts(truth),
        threshold=data.t,
    )
    return metrics, (_curve_points(truth == "FP", scores) if curves else None), len(train_labels)


def five_way_check(model, data: RunPairs, train: np.ndarray, test: np.ndarray, seed: int = 0) -> dict:
    """Five-way labels of every read pair not used in training, against the rule; and the time for the paper's
    100-pair mix (median of a few repeats, classification only: the paths are in memory)."""
    unseen = np.setdiff1d(np.arange(len(data.truth)), train)
    batch = data.batch.take(unseen)
    start = time.perf_counter()
    labels = model.predict(batch)
    seconds = time.perf_counter() - start
    mix = paper_mix(data.truth, test, seed)
    mix_batch = data.batch.take(mix)
    return {
        "n": int(len(unseen)),
        "accuracy": float(np.mean(labels == data.truth[unseen])) if len(unseen) else None,
        "truth_counts": _counts(data.truth[unseen]),
        "predicted_counts": _counts(labels),
        "s_per_100": 100.0 * seconds / max(len(unseen), 1),
        "paper_mix_pairs": int(len(mix)),
        "paper_mix_counts": _counts(data.truth[mix]),
        "paper_mix_s": median_seconds(lambda: model.predict(mix_batch)),
    }


def _make(kind: str, setting: str, seed: int, t: int, max_epochs: int | None = None):
    if kind == "hybrid":
        return HybridClassifier(make_fp_classifier("svm", setting, seed), t=t)
    if kind == "rule":
        return RuleClassifier(t=t)
    model = make_fp_classifier(kind, setting, seed)
    if max_epochs is not None and hasattr(model, "epochs"):
        model.epochs = min(model.epochs, int(max_epochs))  # a quicker comparison (the demo's), said on the page
    return model


def parse_list(text: str | Sequence[str] | None, allowed: Sequence[str], option: str) -> list[str]:
    """`'svm,rule'` -> `['svm', 'rule']`, checked against `allowed` (InputError names the bad value)."""
    if text is None:
        return list(allowed)
    items = [s.strip() for s in (text.split(",") if isinstance(text, str) else text) if s.strip()]
    bad = [s for s in items if s not in allowed]
    if bad or not items:
        raise InputError(f"{option}: {', '.join(bad) or 'empty'} not in {','.join(allowed)}", option)
    return list(dict.fromkeys(items))


def parse_sizes(text: str | Sequence[float] | None) -> list[float]:
    """Training-set fractions for fig. 8, each in (0, 1]; 1.0 is always included."""
    if text is None:
        return list(DEFAULT_SIZES)
    try:
        values = [float(s) for s in (text.split(",") if isinstance(text, str) else text) if str(s).strip()]
    except ValueError:
        raise InputError(f"sizes: expected comma-separated fractions like 0.1,0.5,1, got {text!r}", "sizes") from None
    bad = [v for v in values if not 0.0 < v <= 1.0]
    if bad:
        raise InputError(f"sizes: fractions must be in (0, 1], got {bad[0]}", "sizes")
    return sorted(set(values) | {1.0})


def evaluate_run(
    store,
    run_id: int,
    classifiers: Sequence[str] = CLASSIFIERS,
    setting: str = "baseline",
    sizes: Sequence[float] = DEFAULT_SIZES,
    seed: int = 0,
    progress: bool = False,
    write: bool = True,
    max_epochs: int | None = None,
) -> list[dict]:
    """Run the comparison on the stored run `run_id` of `store` and (with `write`) store its rows.

    `max_epochs` caps the CNN's and MLP's epochs (None: the setting's, 10 or 20); each row's metrics record the
    epochs used. Returns the rows (dicts with the `evaluations` columns, `metrics` and `curves` as dicts).
    """
    if setting not in SETTINGS:
        raise InputError(f"setting: {setting!r} not in {','.join(SETTINGS)}", "setting")
    if max_epochs is not None and int(max_epochs) < 1:
        raise InputError(f"max_epochs: must be >= 1, got {max_epochs}")
    classifiers = parse_list(list(classifiers), CLASSIFIERS, "classifiers")
    sizes = parse_sizes(list(sizes))
    store.run_info(run_id)
    data = load_run_pairs(store, run_id, seed)
    train, test = split_fp_dp(data.truth, seed, source=f"run {run_id}")
    jobs = []
    for kind in classifiers:
        if kind == "rule":
            jobs.append((kind, "none", 1.0))
            continue
        jobs += [(kind, "balanced", 1.0), (kind, "imbalanced", 1.0)]
        if kind != "hybrid":
            jobs += [(kind, "balanced", f) for f in sizes if f < 1.0]
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(jobs), desc="evaluations", unit="fit")
    batch_id = uuid.uuid4().hex[:16]
    rows = []
    for kind, training, fraction in jobs:
        if bar is not None:
            bar.set_postfix_str(f"{kind} {training} {fraction:g}")
        subset = train if fraction >= 1.0 else nested_fraction(train, data.truth, fraction, seed)
        model = _make(kind, setting, seed, data.t, max_epochs)
        metrics, curves, train_size = evaluate_model(
            model, data, subset, test, training == "balanced", seed, curves=fraction >= 1.0
        )
        if hasattr(model, "epochs"):
            metrics["epochs"] = int(model.epochs)
        if kind in ("hybrid", "rule"):
            metrics["five_way"] = five_way_check(model, data, subset, test, seed)
        if kind == "rule":  # nothing is trained
            metrics["training_s"] = 0.0
            train_size = 0
        rows.append(
            {
                "batch": batch_id,
                "classifier": kind,
                "setting": setting,
                "training": training,
                "train_fraction": float(fraction),
                "train_size": int(train_size),
                "test_size": int(len(test)),
                "seed": int(seed),
                "metrics": jsonable(metrics),
                "curves": curves,
            }
        )
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    if write:
        store.add_evaluations(run_id, rows)
    return rows


def jsonable(value):
    """Plain JSON values (floats stay floats; NaN becomes None, which every database's JSON accepts)."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return None if not np.isfinite(value) else float(value)
    return value


#: the comparison `vinadv run --report` (and so `make demo`) runs: every classifier, those with hyperparameters in
#: both settings, on fewer training-set fractions and with the networks' epochs capped, to keep the demo short on
#: 2 cores (the CNN is most of its time; the page and the README say so)
QUICK_SIZES = (0.25, 0.5, 1.0)
QUICK_MAX_EPOCHS = 2
#: classifiers without a setting (the same model in both): compared once, in the baseline setting
SETTINGLESS = ("hausdorff", "frechet", "dtw", "rule")


def compare_for_report(
    store,
    run_id: int,
    settings: Sequence[str] = SETTINGS,
    sizes: Sequence[float] = QUICK_SIZES,
    max_epochs: int | None = QUICK_MAX_EPOCHS,
    seed: int = 0,
    progress: bool = False,
) -> tuple[list[dict], str | None]:
    """The classifier comparison of `run_id` in each of `settings` (the settingless classifiers in the first only),
    stored; `(rows, None)`, or `(rows so far, reason)` when the run cannot be compared (fewer than 2 FP or DP
    pairs: nothing to split)."""
    rows: list[dict] = []
    for k, setting in enumerate(settings):
        kinds = [c for c in CLASSIFIERS if k == 0 or c not in SETTINGLESS]
        try:
            rows += evaluate_run(store, run_id, kinds, setting, sizes, seed, progress=progress, max_epochs=max_epochs)
        except InputError as exc:
            if "at least 2" not in str(exc):
                raise
            return rows, str(exc)
    return rows, None
