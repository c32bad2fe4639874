"""Table 7's processing time, measured and stored: the exact rule labeller and the database read on the paper's
100-pair mix of a run (`timing_pairs`), medians of a few repeats.

`evaluate_timing` stores `{"pairs", "counts", "read_s", "rule_s", "machine", "repeats"}` with the run
(`Store.add_measurement`, kind `TIMING`); the hybrid classifier's time comes from its stored classifier evaluation
(`five_way.paper_mix_s`), which the report reads beside it.
"""

from __future__ import annotations

import os
import platform

import numpy as np

from vinadv.classify.batch import PathPairBatch
from vinadv.classify.rule import label_batch
from vinadv.evaluation.classifiers import TIMING_REPEATS, median_seconds, paper_mix
from vinadv.vocabulary import STRENGTH_ORDER, TIMING

#: repeats of the database read (each reads the 100 pairs)
READ_REPEATS = 3


def timing_pairs(index: np.ndarray, labels: np.ndarray, seed: int = 0) -> np.ndarray:
    """The paper's 100-pair mix of a run, from all its stored pairs (`index`, `labels`): up to 40 FP/DP pairs and
    60 UrP/UcP pairs (the rest from the other group when one is short), sorted pair indices."""
    chosen = paper_mix(labels, np.flatnonzero(np.isin(labels, ("FP", "DP"))), seed)
    return np.sort(index[chosen]) if len(chosen) else index[:100]


def machine() -> str:
    """The machine the times are measured on: `x86_64, 2 CPUs, Python 3.12.3`."""
    return f"{platform.machine()}, {os.cpu_count()} CPUs, Python {platform.python_version()}"


def evaluate_timing(store, run_id: int) -> dict:
    """Time the database read and the rule labeller on the paper's mix of the stored run `run_id` (seconds for
    all `pairs` of the mix, medians of `repeats`) and store the result with the run; return it."""
    mix = timing_pairs(*store.pair_labels(run_id))
    read_s = median_seconds(lambda: store.read_pairs(run_id, pair_indices=mix), READ_REPEATS)
    records = store.read_pairs(run_id, pair_indices=mix)
    batch = PathPairBatch.from_pairs(records)
    rule_s = median_seconds(lambda: label_batch(batch))
    result = {
        "pairs": len(records),
        "counts": {lab: int(np.sum(records.label == lab)) for lab in STRENGTH_ORDER},
        "read_s": read_s,
        "rule_s": rule_s,
        "machine": machine(),
        "repeats": TIMING_REPEATS,
    }
    store.add_measurement(run_id, TIMING, result)
    return result
