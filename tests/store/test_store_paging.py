"""Store additions for the viewer: keyset pages of a run's pairs (`page_pairs`) against NumPy on the records
written, per-run label counts in one query, label sources, runs without counts, annotations of some pairs."""

from __future__ import annotations

import numpy as np
import pytest

from vinadv.errors import InputError
from vinadv.store import LABELS, PairRecords, Store
from vinadv.testing.store import random_records


@pytest.fixture
def filled(tmp_path):
    store = Store.open(f"sqlite:///{tmp_path / 'p.db'}")
    first = random_records(150, size=8, seed=1)
    # a second run with gaps in its pair indices
    second = random_records(40, size=8, seed=2, first_index=1000).take(np.arange(0, 40, 3))
    ids = [store.create_run("a"), store.create_run("b")]
    store.write_pairs(ids[0], first)
    store.write_pairs(ids[1], second)
    yield store, ids, (first, second)
    store.close()


@pytest.mark.parametrize(
    "filters",
    [
        {},
        {"label": "FP"},
        {"label": "invalid"},
        {"attack": True},
        {"attack": False},
        {"label_source": "svm"},
        {"label": "DP", "label_source": "rule"},
        {"label": "UcP", "attack": True},
    ],
)
@pytest.mark.parametrize("limit", [1, 7, 500])
def test_page_pairs_forward_and_back(filled, filters, limit):
    store, ids, all_records = filled
    for run_id, records in zip(ids, all_records):
        mask = np.ones(len(records), bool)
        if "label" in filters:
            mask &= records.label == filters["label"]
        if "attack" in filters:
            mask &= records.attack == filters["attack"]
        if "label_source" in filters:
            mask &= records.label_source == filters["label_source"]
        expected = np.sort(records.pair_index[mask]).tolist()
        # forward through every page
        seen, after = [], None
        while True:
            page = store.page_pairs(run_id, after=after, limit=limit, **filters)
            seen += [r["pair_index"] for r in page]
            if len(page) < limit:
                break
            after = page[-1]["pair_index"]
        assert seen == expected
        # backward from past the end
        seen, before = [], 10**9
        while True:
            page = store.page_pairs(run_id, before=before, limit=limit, **filters)
            assert [r["pair_index"] for r in page] == sorted(r["pair_index"] for r in page)
            seen = [r["pair_index"] for r in page] + seen
            if len(page) < limit:
                break
            before = page[0]["pair_index"]
        assert seen == expected


def test_page_rows_hold_the_stored_values(filled):
    store, ids, (first, _) = filled
    rows = store.page_pairs(ids[0], limit=500)
    assert [r["label"] for r in rows] == first.label.tolist()
    assert [r["attack"] for r in rows] == first.attack.tolist()
    assert [r["label_source"] for r in rows] == first.label_source.tolist()
    assert [-1 if r["dh"] is None else r["dh"] for r in rows] == first.dh.tolist()
    scores = np.array([np.nan if r["score"] is None else r["score"] for r in rows])
    assert np.array_equal(scores, first.score, equal_nan=True)


def test_counts_sources_runs_annotations(filled):
    store, ids, records = filled
    counts = store.label_counts_by_run()
    for run_id, rec in zip(ids, records):
        assert counts[run_id] == {lab: int(np.sum(rec.label == lab)) for lab in LABELS}
        assert counts[run_id] == store.label_counts(run_id)
        assert store.label_sources(run_id) == sorted(set(rec.label_source.tolist()))
    plain = store.list_runs(with_counts=False)
    assert [r["id"] for r in plain] == ids and "n_pairs" not in plain[0]
    store.add_annotations(ids[0], [3, 4, 3], ["FP", "DP", "UcP"], "a")
    got = [(a["pair_index"], a["label"]) for a in store.read_annotations(ids[0], pair_indices=[3, 99])]
    assert got == [(3, "FP"), (3, "UcP")]
    assert len(store.read_annotations(ids[0])) == 3


@pytest.mark.parametrize("chunk", [1, 7, 150, 1000])
def test_iter_pairs_reads_the_run_in_chunks_of_records(filled, chunk):
    store, ids, (first, _) = filled
    chunks = list(store.iter_pairs(ids[0], chunk=chunk))
    assert [len(c) for c in chunks[:-1]] == [chunk] * (len(chunks) - 1) and 0 < len(chunks[-1]) <= chunk
    assert PairRecords.concat(chunks).equals(first)
    attacks = list(store.iter_pairs(ids[0], chunk=chunk, successful_only=True))
    assert np.concatenate([c.pair_index for c in attacks]).tolist() == np.flatnonzero(first.attack).tolist()
    with pytest.raises(InputError, match="chunk"):
        next(store.iter_pairs(ids[0], chunk=0))
