"""Store reads for the report (`pair_labels`, `termination_counts`) on every backend, against plain Python counts
of the records written (pair indices shuffled and with gaps, two runs side by side)."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from vinadv.errors import InputError
from vinadv.store import Store
from vinadv.store.synthetic import random_records


def test_pair_labels_and_terminations_match_the_records_written(db_url):
    first = random_records(90, size=8, seed=5)
    # gaps in the indices, written in shuffled order: the reads must come back ordered by pair index
    second = random_records(30, size=8, seed=6, first_index=500).take(np.random.default_rng(0).permutation(30)[:20])
    with Store.open(db_url) as store:
        ids = [store.create_run("a"), store.create_run("b"), store.create_run("empty")]
        store.write_pairs(ids[0], first)
        store.write_pairs(ids[1], second)
        for run_id, records in zip(ids[:2], (first, second)):
            index, labels = store.pair_labels(run_id)
            expected = sorted(zip(records.pair_index.tolist(), records.label.tolist()))
            assert index.dtype == np.int64 and labels.dtype == object
            assert list(zip(index.tolist(), labels.tolist())) == expected
            for side in ("o", "a"):
                counts = store.termination_counts(run_id, side)
                assert counts == dict(sorted(Counter(getattr(records, f"term_{side}").tolist()).items()))
                assert list(counts) == sorted(counts)
        index, labels = store.pair_labels(ids[2])
        assert index.shape == labels.shape == (0,)
        assert store.termination_counts(ids[2]) == {}
        with pytest.raises(InputError, match="side"):
            store.termination_counts(ids[0], "x")
