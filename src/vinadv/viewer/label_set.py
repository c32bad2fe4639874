"""People's labels as a training set: stored pairs + their annotations -> (path pairs, labels).

Used by `vinadv classify train --labels human --db URL --run ID`. No Flask here.

Several people (or one person twice) may label a pair. One label per pair: each annotator's latest label counts
once, the label most annotators gave wins, and a tie goes to the label of the most recent annotation among the
tied ones. Pairs nobody labelled are left out.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vinadv.classify.batch import PathPairBatch
from vinadv.errors import InputError


def resolve_human_labels(annotations: Sequence[dict]) -> tuple[np.ndarray, np.ndarray]:
    """One label per annotated pair from annotation dicts (pair_index, label, annotator, id; `id` orders them
    in time, as `Store.read_annotations` returns them). Returns `(pair_indices (k,) int64 ascending,
    labels (k,) object)`."""
    latest: dict[tuple[int, str], tuple[int, str]] = {}  # (pair, annotator) -> (id, label)
    for a in annotations:
        key = (int(a["pair_index"]), str(a["annotator"]))
        stamp = int(a["id"])
        if key not in latest or stamp > latest[key][0]:
            latest[key] = (stamp, str(a["label"]))
    votes: dict[int, dict[str, list[int]]] = {}  # pair -> label -> ids of the votes for it
    for (pair, _), (stamp, label) in latest.items():
        votes.setdefault(pair, {}).setdefault(label, []).append(stamp)
    pairs = np.array(sorted(votes), dtype=np.int64)
    labels = np.array(
        [max(votes[p].items(), key=lambda item: (len(item[1]), max(item[1])))[0] for p in pairs.tolist()],
        dtype=object,
    )
    return pairs, labels


def human_training_set(store, run_id: int) -> tuple[PathPairBatch, np.ndarray, np.ndarray]:
    """The run's human-labelled pairs: `(batch, labels (k,) object, pair_indices (k,) int64)`, in pair order.

    `store` is an open `vinadv.store.Store`; InputError when the run does not exist or nobody labelled any of
    its pairs.
    """
    store.run_info(run_id)  # InputError naming the run when there is none
    pair_indices, labels = resolve_human_labels(store.read_annotations(run_id))
    if len(pair_indices) == 0:
        raise InputError(
            f"run_id {run_id}: no human labels in database {store.url} (label pairs with `vinadv serve`)", "run_id"
        )
    records = store.read_pairs(run_id, pair_indices=pair_indices)
    if len(records) != len(pair_indices):  # an annotation of a pair that is not stored (deleted, other db)
        keep = np.isin(pair_indices, records.pair_index)
        pair_indices, labels = pair_indices[keep], labels[keep]
    batch = PathPairBatch.from_pairs(records)
    return batch, labels, pair_indices
