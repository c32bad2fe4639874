"""`vinadv classify train` and `vinadv classify eval`: FP/DP path image classifiers on pairs files."""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from vinadv.errors import InputError

KINDS = ("svm", "cnn", "mlp", "hausdorff", "frechet", "dtw")


def register(subparsers) -> None:
    classify = subparsers.add_parser("classify", help="train and evaluate FP/DP path pair classifiers")
    sub = classify.add_subparsers(dest="classify_command", metavar="ACTION")
    sub.required = True

    train = sub.add_parser(
        "train",
        help="train an FP/DP classifier on the FP/DP pairs of a pairs file (stratified train/test split)",
        description="Train the paper's hybrid classifier: invalid/UrP/UcP by path features, and an FP/DP "
        "classifier trained on the pairs of the file that the labels call FP or DP. The pairs are split "
        "train:test stratified by label; the test indices are kept in the model file for `classify eval`.",
    )
    train.add_argument("--pairs", default=None, help="pairs file (.npz, vinadv.pairs/1); needed with --labels rule")
    train.add_argument("--model", required=True, choices=KINDS, help="FP/DP classifier")
    train.add_argument("--out", required=True, help="output model file")
    train.add_argument("--setting", choices=("baseline", "tuned"), default="baseline",
                       help="baseline = the paper's (pixels of the paper's path images; CNN/MLP 10 epochs, batch "
                       "64), or tuned (row/column co-occurrence features of 'split' path images)")
    train.add_argument("--balance", action="store_true",
                       help="balance the training set: flipped/rotated copies of minority-class pairs")
    train.add_argument("--test-fraction", type=float, default=0.3,
                       help="fraction of the FP/DP pairs held out for testing (default 0.3; 0 = train on all)")
    train.add_argument("--seed", type=int, default=0, help="seed of the split, augmentation and training")
    train.add_argument("--labels", choices=("rule", "human"), default="rule",
                       help="where training labels come from: the exact rule labeller on --pairs (default), or "
                       "people's annotations (`vinadv serve`) of the stored pairs of --db/--run")
    train.add_argument("--db", default=None, help="with --labels human: the results database (URL or SQLite file)")
    train.add_argument("--run", default=None, help="with --labels human: the run (id or name) whose labelled pairs to use")
    train.add_argument("--threshold", type=int, default=None,
                       help="the rule's threshold t (default round(4 * N / 28), 4 at 28x28)")
    train.add_argument("--json", action="store_true", help="print a JSON summary")
    train.add_argument("--quiet", action="store_true", help="print nothing but errors")
    train.set_defaults(func=cmd_train)

    ev = sub.add_parser(
        "eval",
        help="evaluate a model on a pairs file (its held-out test split when it is the training file)",
    )
    ev.add_argument("--pairs", required=True, help="pairs file (.npz, vinadv.pairs/1)")
    ev.add_argument("--model", required=True, help="model file written by `vinadv classify train`")
    ev.add_argument("--all", action="store_true",
                    help="evaluate on every FP/DP pair of the file, even if the model was trained on it")
    ev.add_argument("--json", action="store_true", help="print the figures as JSON")
    ev.add_argument("--quiet", action="store_true", help="print nothing but errors")
    ev.set_defaults(func=cmd_eval)


def _load_pairs(path):
    from vinadv.attacks.pairs import PairSet
    from vinadv.classify import PathPairBatch

    return PathPairBatch.from_pairset(PairSet.load(path))


def _human_labels(args):
    """(batch, labels, description) of the human-labelled pairs of --db/--run (`vinadv.viewer.training`)."""
    if args.run is None:
        raise InputError("--labels human needs --run (and --db, or env VINADV_DB)")
    from vinadv.store import Store
    from vinadv.viewer.training import human_training_set

    with Store.open(args.db, readonly=True) as store:
        run_id = store.resolve_run(args.run)
        batch, labels, _ = human_training_set(store, run_id)
        return batch, labels, f"{store.url} run {run_id} (human labels)"


def _counts(labels) -> dict:
    values, counts = np.unique(np.asarray(labels), return_counts=True)
    return {str(v): int(c) for v, c in zip(values, counts)}


def cmd_train(args: argparse.Namespace) -> int:
    from sklearn.model_selection import train_test_split

    from vinadv.classify import HybridClassifier, balance_batch, default_threshold, label_batch, make_fp_classifier

    if not 0.0 <= args.test_fraction < 1.0:
        raise InputError(f"--test-fraction must be in [0, 1), got {args.test_fraction}")
    if args.labels == "human":
        batch, labels, args.pairs = _human_labels(args)
        t = default_threshold(batch.size) if args.threshold is None else args.threshold
    else:
        if args.pairs is None:
            raise InputError("--pairs is required with --labels rule")
        batch = _load_pairs(args.pairs)
        t = default_threshold(batch.size) if args.threshold is None else args.threshold
        labels = label_batch(batch, t).labels
    fp_dp = np.flatnonzero(np.isin(labels, ("DP", "FP")))
    counts = _counts(labels[fp_dp])
    need = 2 if args.test_fraction > 0 else 1
    if counts.get("DP", 0) < need or counts.get("FP", 0) < need:
        raise InputError(f"{args.pairs}: training needs at least {need} FP and {need} DP pairs, "
                         f"the file has {counts.get('FP', 0)} FP and {counts.get('DP', 0)} DP")
    if args.test_fraction > 0:
        train_index, test_index = train_test_split(
            fp_dp, test_size=args.test_fraction, stratify=labels[fp_dp], random_state=args.seed
        )
        train_index, test_index = np.sort(train_index), np.sort(test_index)
    else:
        train_index, test_index = fp_dp, np.zeros(0, dtype=np.int64)
    train_batch, train_labels = batch.subset(train_index), labels[train_index]
    if args.balance:
        train_batch, train_labels = balance_batch(train_batch, train_labels, seed=args.seed)
    model = HybridClassifier(make_fp_classifier(args.model, args.setting, args.seed, verbose=not args.quiet), t=t)
    start = time.perf_counter()
    model.fit(train_batch, train_labels)
    seconds = time.perf_counter() - start
    record = {
        "pairs": str(args.pairs), "pairs_fingerprint": batch.fingerprint(), "n_pairs": len(batch),
        "size": batch.size, "labels": args.labels, "threshold": t, "model": args.model, "setting": args.setting,
        "balance": bool(args.balance), "seed": args.seed, "test_fraction": args.test_fraction,
        "train_counts": _counts(labels[train_index]), "train_counts_balanced": _counts(train_labels),
        "test_counts": _counts(labels[test_index]), "training_seconds": round(seconds, 3),
    }
    model.save(args.out, record, {"train_index": train_index, "test_index": test_index})
    if args.json:
        print(json.dumps({"out": args.out, **record}))
    elif not args.quiet:
        print(f"trained {args.model} ({args.setting}) on {len(train_labels)} pairs "
              f"{record['train_counts_balanced']} in {seconds:.2f} s; held out {len(test_index)} "
              f"{record['test_counts']}; wrote {args.out}")
    return 0


def cmd_eval(args: argparse.Namespace) -> int:
    from vinadv.classify import HybridClassifier, RuleClassifier, binary_metrics, default_threshold, label_batch
    from vinadv.classify.base import load_model

    model = load_model(args.model)
    if not isinstance(model, (HybridClassifier, RuleClassifier)):
        record, arrays = model.record_, model.record_arrays_
        model = HybridClassifier(model, t=record.get("threshold"))
        model.record_, model.record_arrays_ = record, arrays
    batch = _load_pairs(args.pairs)
    record = getattr(model, "record_", {}) or {}
    t = model.t if model.t is not None else default_threshold(batch.size)
    truth = label_batch(batch, t).labels
    same_file = record.get("pairs_fingerprint") == batch.fingerprint()
    train_index = model.record_arrays_.get("train_index", np.zeros(0, np.int64)) if same_file else np.zeros(0, np.int64)
    if same_file and not args.all:
        eval_index = model.record_arrays_.get("test_index", np.zeros(0, np.int64)).astype(np.int64)
        scope = "held-out test split of the training file"
    else:
        eval_index = np.flatnonzero(np.isin(truth, ("DP", "FP")))
        scope = "all FP/DP pairs of the file" + (" (including training pairs)" if same_file else "")
    if len(eval_index) == 0:
        raise InputError(f"{args.pairs}: no FP/DP pairs to evaluate on ({scope})")

    subset = batch.subset(eval_index)
    start = time.perf_counter()
    predicted = model.predict(subset)
    predict_seconds = time.perf_counter() - start
    scores = model.fp_decision(subset)
    figures = binary_metrics(truth[eval_index], predicted, scores)

    # the five-way labels of every pair the model did not train on (features + classifier, against the rule)
    unseen = np.setdiff1d(np.arange(len(batch)), train_index)
    start = time.perf_counter()
    five_way = model.predict(batch.subset(unseen))
    five_way_seconds = time.perf_counter() - start
    result = {
        "pairs": str(args.pairs), "model": str(args.model), "kind": record.get("model", model.kind),
        "setting": record.get("setting"), "threshold": t, "scope": scope, "fp_dp": figures,
        "training_time_s": getattr(model, "training_time_s_", None),
        "prediction_seconds_per_100_pairs": round(100 * predict_seconds / len(eval_index), 6),
        "five_way": {
            "n": int(len(unseen)),
            "accuracy": float(np.mean(five_way == truth[unseen])) if len(unseen) else None,
            "truth_counts": _counts(truth[unseen]), "predicted_counts": _counts(five_way),
            "prediction_seconds_per_100_pairs": round(100 * five_way_seconds / max(len(unseen), 1), 6),
        },
    }
    if args.json:
        print(json.dumps(result))
    elif not args.quiet:
        print(_format(result))
    return 0


def _fmt(value, digits=4):
    return "n/a" if value is None else f"{value:.{digits}f}"


def _format(r: dict) -> str:
    f = r["fp_dp"]
    lines = [
        f"model {r['model']} ({r['kind']}, {r['setting']}), threshold t={r['threshold']}",
        f"FP/DP on {f['n']} pairs ({r['scope']}):",
        f"  accuracy {_fmt(f['accuracy'])}   ROC AUC {_fmt(f['roc_auc'])}   average precision "
        f"{_fmt(f['average_precision'])}",
        "  class  precision  recall  F1      support",
    ]
    for c in f["classes"]:
        p = f["per_class"][c]
        lines.append(f"  {c:<5}  {p['precision']:.4f}     {p['recall']:.4f}  {p['f1']:.4f}  {p['support']}")
    cm = f["confusion_matrix"]
    lines += [
        "  confusion (rows true, columns predicted): DP FP",
        f"    DP {cm[0][0]:>6} {cm[0][1]:>6}",
        f"    FP {cm[1][0]:>6} {cm[1][1]:>6}",
        f"  training time {_fmt(r['training_time_s'], 2)} s; prediction "
        f"{_fmt(r['prediction_seconds_per_100_pairs'], 5)} s per 100 pairs",
        f"five-way labels of {r['five_way']['n']} unseen pairs: accuracy {_fmt(r['five_way']['accuracy'])} "
        f"({_fmt(r['five_way']['prediction_seconds_per_100_pairs'], 5)} s per 100 pairs); truth "
        f"{r['five_way']['truth_counts']}",
    ]
    return "\n".join(lines)
