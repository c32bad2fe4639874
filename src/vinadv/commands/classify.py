"""`vinadv classify train` and `vinadv classify eval`: FP/DP path image classifiers on pairs files."""

from __future__ import annotations

import argparse

from vinadv.commands import add_actions, add_db_argument, db_file, option_values
from vinadv.commands.output import add_output_options, emit, shows_progress
from vinadv.errors import InputError
from vinadv.outfile import check_output_path

KINDS = ("svm", "cnn", "mlp", "hausdorff", "frechet", "dtw")


def register(subparsers) -> None:
    sub = add_actions(subparsers, "classify", help="train and evaluate FP/DP path pair classifiers")

    train = sub.add_parser(
        "train",
        help="train an FP/DP classifier on the FP/DP pairs of a pairs file (stratified train/test split)",
        description="Train the paper's hybrid classifier: invalid/UrP/UcP by path features, and an FP/DP "
        "classifier trained on the pairs of the file that the labels call FP or DP. The pairs are split "
        "train:test stratified by label; the test indices are kept in the model file for `classify eval`.",
    )
    train.add_argument("--pairs", default=None, help="pairs file (.npz, vinadv.pairs/3); needed with --labels rule")
    train.add_argument("--model", required=True, choices=KINDS, help="FP/DP classifier")
    train.add_argument("--out", required=True, help="output model file")
    add_setting_argument(train)
    train.add_argument(
        "--balance",
        action="store_true",
        help="balance the training set: flipped/rotated copies of minority-class pairs",
    )
    train.add_argument(
        "--test-fraction",
        type=float,
        default=0.3,
        help="fraction of the FP/DP pairs held out for testing (default 0.3; 0 = train on all)",
    )
    train.add_argument("--seed", type=int, default=0, help="seed of the split, augmentation and training")
    train.add_argument(
        "--labels",
        choices=("rule", "human"),
        default="rule",
        help="where training labels come from: the exact rule labeller on --pairs (default), or "
        "people's annotations (`vinadv serve`) of the stored pairs of --db/--run",
    )
    add_db_argument(train, when="with --labels human: ")
    train.add_argument(
        "--run", default=None, help="with --labels human: the run (id or name) whose labelled pairs to use"
    )
    train.add_argument(
        "--threshold", type=int, default=None, help="the rule's threshold t (default round(4 * N / 28), 4 at 28x28)"
    )
    add_output_options(train, json="the summary", quiet=True)
    train.set_defaults(func=cmd_train)

    ev = sub.add_parser(
        "eval",
        help="evaluate a model on a pairs file (its held-out test split when it is the training file)",
    )
    ev.add_argument("--pairs", required=True, help="pairs file (.npz, vinadv.pairs/3)")
    ev.add_argument("--model", required=True, help="model file written by `vinadv classify train`")
    ev.add_argument(
        "--all",
        action="store_true",
        help="evaluate on every FP/DP pair of the file, even if the model was trained on it",
    )
    add_output_options(ev, json="the figures", quiet=True)
    ev.set_defaults(func=cmd_eval)


def add_setting_argument(parser) -> None:
    """`--setting baseline|tuned`: the features and training of the FP/DP classifiers (`classify train`,
    `evaluate`)."""
    parser.add_argument(
        "--setting",
        choices=("baseline", "tuned"),
        default="baseline",
        help="baseline = the paper's (pixels of the paper's path images; CNN/MLP 10 epochs, batch "
        "64), or tuned (row/column co-occurrence features of 'split' path images)",
    )


def _load_pairs(path):
    from vinadv.attacks.pairs import PairSet
    from vinadv.classify.batch import PathPairBatch

    return PathPairBatch.from_pairs(PairSet.load(path))


def _human_labels(args):
    """(batch, labels, description) of the human-labelled pairs of --db/--run (`vinadv.viewer.label_set`)."""
    if args.run is None:
        raise InputError("--labels human needs --run (and --db, or env VINADV_DB)")
    from vinadv.store import Store
    from vinadv.viewer.label_set import human_training_set

    with Store.open(args.db, readonly=True) as store:
        run_id = store.resolve_run(args.run)
        batch, labels, _ = human_training_set(store, run_id)
        return batch, labels, f"{store.url} run {run_id} (human labels)"


def cmd_train(args: argparse.Namespace) -> int:
    from vinadv.classify.rule import default_threshold, label_batch
    from vinadv.classify.train_eval import train_classifier

    human = args.labels == "human"  # before the training: writable, and not the pairs or the database it reads
    check_output_path(args.out, inputs={"--pairs": args.pairs, "--db": db_file(args.db) if human else None})
    if args.labels == "human":
        batch, labels, args.pairs = _human_labels(args)
    else:
        if args.pairs is None:
            raise InputError("--pairs is required with --labels rule")
        batch = _load_pairs(args.pairs)
        labels = label_batch(batch, default_threshold(batch.size) if args.threshold is None else args.threshold).labels
    model, record, arrays = train_classifier(
        batch,
        labels,
        **option_values(args, "model", "setting", "threshold", "balance", "test_fraction", "seed"),
        source=str(args.pairs),
        verbose=shows_progress(args),
    )
    record = {**record, "labels": args.labels}
    model.save(args.out, record, arrays)
    return emit(
        args,
        {"out": args.out, **record},
        f"trained {args.model} ({args.setting}) on {sum(record['train_counts_balanced'].values())} "
        f"pairs {record['train_counts_balanced']} in {record['training_seconds']:.2f} s; held out "
        f"{len(arrays['test_index'])} {record['test_counts']}; wrote {args.out}",
    )


def cmd_eval(args: argparse.Namespace) -> int:
    from vinadv.classify.base import load_model
    from vinadv.classify.train_eval import as_hybrid, evaluate_classifier

    model = as_hybrid(load_model(args.model))
    result = evaluate_classifier(model, _load_pairs(args.pairs), all_pairs=args.all, source=str(args.pairs))
    result = {"pairs": result["pairs"], "model": str(args.model), **result}
    return emit(args, result, lambda: print(_format(result)))


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
