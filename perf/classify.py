"""Throughput of vinadv.classify: the rule labeller, path images, each classifier's prediction, the hybrid.

    nice .venv/bin/python perf/classify.py [--pairs PAIRS.npz] [--n 20000] [--json]

Without --pairs it uses synthetic pairs (expert paths on generated 28x28 maps, one obstacle added on the path,
then mixed into all five categories; see vinadv.testing.classify) and says so. Classifiers are trained on a
small balanced FP/DP sample only to have something to time (CNN/MLP 1 epoch): accuracy is not measured here
(use `vinadv classify eval`). Ratios are measured side by side in this run: the rule labeller against a plain
Python loop written straight from DESIGN.md, our SVM decision function against scikit-learn's SVC.predict,
and the hybrid against the paper's 100 pairs in 0.22 s.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np
import scipy.sparse
from sklearn.svm import SVC

from vinadv.attacks.pairs import PairSet
from vinadv.classify import (
    HybridClassifier,
    PathPairBatch,
    balance_batch,
    label_batch,
    make_fp_classifier,
    render_batch,
)
from vinadv.testing.classify import synthetic_pairs
from vinadv.vocabulary import FORK_OR_DETOUR

PAPER_PAIRS_PER_S = 100 / 0.22


def timed(fn, min_seconds=0.5):
    """Best time of repeated calls (at least one, until min_seconds have passed)."""
    best, total, result = np.inf, 0.0, None
    while total < min_seconds or best == np.inf:
        start = time.perf_counter()
        result = fn()
        elapsed = time.perf_counter() - start
        best, total = min(best, elapsed), total + elapsed
    return best, result


def python_rule(batch, t):
    """The DESIGN.md rule, one pair at a time in plain Python (the side-by-side reference)."""
    labels = []
    for i in range(len(batch)):
        o = [tuple(c) for c in batch.path_o[i].tolist()]
        a = [tuple(c) for c in batch.path_a[i].tolist()]
        goal = tuple(batch.goals[i].tolist())
        if not o or o[-1] != goal:
            labels.append("invalid")
            continue
        if not a or a[-1] != goal:
            labels.append("UrP")
            continue
        if o == a:
            labels.append("UcP")
            continue
        d_o, d_a = set(o) - set(a), set(a) - set(o)
        dh = max([abs(ci - cj) for (ri, ci) in d_o for (rj, cj) in d_a if ri == rj], default=0)
        dv = max([abs(ri - rj) for (ri, ci) in d_o for (rj, cj) in d_a if ci == cj], default=0)
        labels.append("DP" if dh <= t and dv <= t else "FP")
    return np.array(labels)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", help="a real pairs file (vinadv.pairs/1); default: synthetic pairs")
    parser.add_argument("--n", type=int, default=20000, help="pairs to time (synthetic pairs are tiled to it)")
    parser.add_argument("--train", type=int, default=1000, help="FP/DP training pairs per classifier")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)

    if args.pairs:
        batch = PathPairBatch.from_pairs(PairSet.load(args.pairs))
        source = f"real pairs from {args.pairs}"
    else:
        base = synthetic_pairs(min(args.n, 5000), 28, seed=0, mix=True)
        batch = PathPairBatch.concat([base] * -(-args.n // len(base))).take(np.arange(args.n))
        source = (
            "SYNTHETIC pairs (expert paths on generated 28x28 maps, one obstacle on the path, mixed into "
            "all five categories), not VIN attack pairs"
        )
    n = len(batch)
    results = {"source": source, "pairs": n, "size": batch.size}
    print(f"{source}: {n} pairs of {batch.size}x{batch.size}", file=sys.stderr)

    label_batch(batch.take(np.arange(10)))  # compile the Numba kernel outside the timing
    seconds, labels = timed(lambda: label_batch(batch))
    counts = dict(zip(*np.unique(labels.labels, return_counts=True)))
    results["label_counts"] = {str(k): int(v) for k, v in counts.items()}
    results["rule_pairs_per_s"] = n / seconds
    small = batch.take(np.arange(min(n, 2000)))
    py_seconds, py_labels = timed(lambda: python_rule(small, labels.t), 0.2)
    assert np.array_equal(py_labels, labels.labels[: len(small)]), "the labeller disagrees with the Python rule"
    results["python_rule_pairs_per_s"] = len(small) / py_seconds
    # the same comparison on FP/DP pairs only, where the rule has to compare cells
    fp_dp_only = batch.take(np.flatnonzero(np.isin(labels.labels, FORK_OR_DETOUR)))
    seconds, _ = timed(lambda: label_batch(fp_dp_only))
    results["rule_fp_dp_pairs_per_s"] = len(fp_dp_only) / seconds
    small_fp_dp = fp_dp_only.take(np.arange(min(len(fp_dp_only), 1000)))
    seconds, _ = timed(lambda: python_rule(small_fp_dp, labels.t), 0.2)
    results["python_rule_fp_dp_pairs_per_s"] = len(small_fp_dp) / seconds
    seconds, _ = timed(lambda: render_batch(batch))
    results["render_pairs_per_s"] = n / seconds

    y = labels.labels
    fp_dp = np.flatnonzero(np.isin(y, FORK_OR_DETOUR))
    rng = np.random.default_rng(0)
    train = np.sort(rng.choice(fp_dp, size=min(args.train, len(fp_dp)), replace=False))
    train_batch, train_y = balance_batch(batch.take(train), y[train], seed=0)
    fp_dp_batch = batch.take(fp_dp)
    results["fp_dp_pairs"] = len(fp_dp)
    predict = {}
    models = {}
    for kind in ("svm", "cnn", "mlp", "hausdorff", "frechet", "dtw"):
        for setting in ("baseline", "tuned") if kind in ("svm", "cnn", "mlp") else ("baseline",):
            model = make_fp_classifier(kind, setting)
            if kind in ("cnn", "mlp"):
                model.set_params(epochs=1)
            model.fit(train_batch, train_y)
            model.decision_function(fp_dp_batch.take(np.arange(10)))  # warm up (Numba, torch)
            subset = (
                fp_dp_batch
                if kind in ("svm", "hausdorff", "frechet", "dtw")
                else fp_dp_batch.take(np.arange(min(len(fp_dp), 5000)))
            )
            seconds, _ = timed(lambda: model.decision_function(subset), 0.3)
            name = kind if setting == "baseline" else f"{kind}_tuned"
            predict[name] = len(subset) / seconds
            models[name] = model
            print(f"  {name}: {predict[name]:,.0f} FP/DP pairs/s", file=sys.stderr)
    results["predict_pairs_per_s"] = predict

    # scikit-learn's own SVC.predict on the same model, side by side with our decision function
    svc = SVC(kernel="rbf", gamma="scale").fit(
        scipy.sparse.csr_matrix(render_batch(train_batch).reshape(len(train_batch), -1) / 255.0), train_y
    )
    probe = fp_dp_batch.take(np.arange(min(len(fp_dp), 2000)))
    flat = scipy.sparse.csr_matrix(render_batch(probe).reshape(len(probe), -1) / 255.0)
    seconds, _ = timed(lambda: svc.predict(flat), 0.3)
    results["sklearn_svc_predict_pairs_per_s"] = len(probe) / seconds

    hybrid = HybridClassifier(models["svm"])
    seconds, _ = timed(lambda: hybrid.predict(batch))
    results["hybrid_svm_pairs_per_s"] = n / seconds
    results["paper_pairs_per_s"] = PAPER_PAIRS_PER_S
    results["ratios"] = {
        "rule_vs_python_loop": results["rule_pairs_per_s"] / results["python_rule_pairs_per_s"],
        "rule_vs_python_loop_fp_dp": results["rule_fp_dp_pairs_per_s"] / results["python_rule_fp_dp_pairs_per_s"],
        "svm_decision_vs_sklearn_predict": predict["svm"] / results["sklearn_svc_predict_pairs_per_s"],
        "hybrid_svm_vs_paper": results["hybrid_svm_pairs_per_s"] / PAPER_PAIRS_PER_S,
    }
    if args.json:
        print(json.dumps(results, indent=1))
        return 0
    print(f"source: {source}")
    print(f"pairs: {n} ({results['label_counts']}), FP/DP pairs: {len(fp_dp)}")
    print(f"rule labeller (features + FP/DP rule): {results['rule_pairs_per_s']:>12,.0f} pairs/s  (target 100,000)")
    print(
        f"  same rule, plain Python loop:        {results['python_rule_pairs_per_s']:>12,.0f} pairs/s  "
        f"-> x{results['ratios']['rule_vs_python_loop']:,.0f}"
    )
    print(f"rule labeller, FP/DP pairs only:       {results['rule_fp_dp_pairs_per_s']:>12,.0f} pairs/s")
    print(
        f"  same rule, plain Python loop:        {results['python_rule_fp_dp_pairs_per_s']:>12,.0f} pairs/s  "
        f"-> x{results['ratios']['rule_vs_python_loop_fp_dp']:,.0f}"
    )
    print(f"path image rendering:                  {results['render_pairs_per_s']:>12,.0f} pairs/s")
    for name, rate in predict.items():
        print(f"predict {name:<13} (FP/DP pairs):   {rate:>12,.0f} pairs/s")
    print(
        f"  scikit-learn SVC.predict (same data): {results['sklearn_svc_predict_pairs_per_s']:>11,.0f} pairs/s  "
        f"-> ours x{results['ratios']['svm_decision_vs_sklearn_predict']:.1f}"
    )
    print(
        f"hybrid + SVM, all pairs:               {results['hybrid_svm_pairs_per_s']:>12,.0f} pairs/s  "
        f"(target 20,000; paper {PAPER_PAIRS_PER_S:,.0f}) -> x{results['ratios']['hybrid_svm_vs_paper']:,.0f} "
        "the paper"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
