"""Store reads for the report (`pair_labels`, `termination_counts`) on every backend, against plain Python counts
of the records written (pair indices shuffled and with gaps, two runs side by side)."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

from tests.store.test_store_harm import _make_version_1
from vinadv.errors import InputError
from vinadv.store import Store
from vinadv.testing.store import random_records


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


def test_harm_counts_and_regret_changes_match_the_records_written(db_url):
    records = random_records(200, size=8, seed=7)
    # 25 FP pairs, harmless, whose regret change is one value reached by different float sums: one group
    same = np.arange(25)
    records.label[same], records.harm[same] = "FP", "harmless"
    records.regret_o[same] = 1.0 + math.sqrt(2) - math.sqrt(2) - 1.0 + np.arange(25) * 1e-13
    records.regret_a[same] = 2 * math.sqrt(2) - 2.0 + 0.5 - 0.5
    with Store.open(db_url) as store:
        run_id, other = store.create_run("h"), store.create_run("other")
        store.write_pairs(run_id, records)
        store.write_pairs(other, random_records(30, size=8, seed=8))
        counts = store.harm_counts(run_id)
        changes = store.regret_changes(run_id)
        only_dp = store.regret_changes(run_id, ["DP"])
    expected = Counter(zip(records.label.tolist(), records.harm.tolist()))
    assert {(label, harm): n for label, row in counts.items() for harm, n in row.items()} == dict(expected)
    # plain Python: the pairs of each (label, harm) with both regrets and a harm, their regret_a - regret_o
    plain: dict = {}
    for label, harm, ro, ra in zip(records.label, records.harm, records.regret_o, records.regret_a):
        if label in ("FP", "DP") and harm is not None and not (math.isnan(ro) or math.isnan(ra)):
            plain.setdefault((label, harm), []).append(ra - ro)
    assert set(changes) == set(plain) and set(only_dp) == {k for k in plain if k[0] == "DP"}
    for key, (values, k) in changes.items():
        assert values.dtype == np.float64 and k.dtype == np.int64 and np.all(np.diff(values) > 0)
        assert np.allclose(np.repeat(values, k), sorted(plain[key]), rtol=0, atol=1e-6)
        assert np.array_equal(only_dp.get(key, (values, k))[1], k)
    values, k = changes[("FP", "harmless")]
    assert k.max() == 25 and values[k.argmax()] == pytest.approx(2 * math.sqrt(2) - 2, abs=1e-6)


def test_harm_reads_of_a_version_1_database_opened_without_create(db_url):
    run_id = _make_version_1(db_url)
    with Store.open(db_url, readonly=True) as store:
        counts = store.harm_counts(run_id)
        assert store.regret_changes(run_id) == {}
        labels = Counter(store.pair_labels(run_id)[1].tolist())
    assert counts == {label: {None: n} for label, n in labels.items()}
