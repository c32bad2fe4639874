"""The pair grid sorted by label, harm, regret added and search effort and filtered by regret added and effort,
paged forwards and backwards, against orders computed in plain Python from the records written; the effort of a
database whose pairs hold expanded cells (the columns added here as schema version 8 has them)."""

from __future__ import annotations

import math
import re
from io import BytesIO

import numpy as np
import pytest
import sqlalchemy as sa
from PIL import Image

from tests.viewer.conftest import viewer_for_tests
from vinadv.plot.palette import PALETTE
from vinadv.store import Store
from vinadv.store.codec import encode_paths
from vinadv.testing.store import random_records
from vinadv.vocabulary import HARMS, LABELS


def walk(client, run_id, query: str, size: int = 37) -> tuple[list[int], list[int]]:
    """Every pair index of the grid in order, following `next_after` to the end, then `prev_before` back to the
    start (that list reversed back into order)."""
    forward, after, last = [], None, None
    while True:
        url = f"/api/runs/{run_id}/pairs?{query}&size={size}" + ("" if after is None else f"&after={after}")
        body = client.get(url).get_json()
        assert "pairs" in body, body
        forward += [p["pair_index"] for p in body["pairs"]]
        last = body
        after = body["next_after"]
        if after is None:
            break
    backward = [p["pair_index"] for p in last["pairs"]]
    before = last["prev_before"]
    while before is not None:
        body = client.get(f"/api/runs/{run_id}/pairs?{query}&size={size}&before={before}").get_json()
        backward = [p["pair_index"] for p in body["pairs"]] + backward
        before = body["prev_before"]
    return forward, backward


def oracle(records, sort: str, keep=None) -> list[int]:
    """The pair indices in the grid's order for `sort`, in plain Python (ties by pair index)."""
    rows = []
    for i in range(len(records)):
        change = float(records.regret_a[i]) - float(records.regret_o[i])
        harm = records.harm[i]
        key = {
            "pair": (0, 0),
            "label": (0, LABELS.index(records.label[i])),
            "harm": (1, 0) if harm is None else (0, HARMS.index(harm)),
            "regret": (1, 0) if math.isnan(change) else (0, -change),
        }[sort]
        if keep is None or keep(i, change):
            rows.append((key, int(records.pair_index[i])))
    return [index for _, index in sorted(rows)]


@pytest.mark.parametrize("sort", ["label", "harm", "regret"])
def test_sorted_grid_pages_forwards_and_back_in_the_oracles_order(client, db, sort):
    run_id, records = db[1]["random"]
    forward, backward = walk(client, run_id, f"sort={sort}")
    expected = oracle(records, sort)
    assert forward == expected and backward == expected


def test_sort_and_filters_together(client, db):
    run_id, records = db[1]["random"]
    forward, backward = walk(client, run_id, "sort=regret&min_regret=-5&label=FP", size=7)
    expected = oracle(records, "regret", keep=lambda i, change: change >= -5 and records.label[i] == "FP")
    assert expected and forward == expected and backward == expected
    # the pair page's n/p follow the sort within the filter
    html = client.get(f"/pairs/{run_id}/{expected[1]}?sort=regret&min_regret=-5&label=FP").get_data(as_text=True)
    assert f"/pairs/{run_id}/{expected[2]}?" in html and f"/pairs/{run_id}/{expected[0]}?" in html


def test_grid_page_shows_the_sort_and_the_regret_filter(client, db):
    run_id, records = db[1]["random"]
    html = client.get(f"/runs/{run_id}/pairs?sort=regret&size=5").get_data(as_text=True)
    first = oracle(records, "regret")[:5]
    shown = [int(i) for i in re.findall(r'class="pair-link"[^>]*>(\d+)<', html)]
    assert shown == first
    assert '<option value="regret" selected>' in html
    assert 'value="effort"' not in html  # no pair of this run holds expanded cells
    assert "next ›" in html and "sort=regret" in html


# a bad sort or filter is a 400 naming it: test_malformed_grid_params_are_400_naming_the_parameter in test_app.py


# ------------------------------------------------------------------------------------------- search effort


def add_expansions(url: str, run_id: int, expanded: dict[int, tuple[list, list]]) -> None:
    """Store expanded cells `{pair_index: (cells_o, cells_a)}` of the run's pairs as schema version 8 does: path text
    in `map_pairs.expanded_o` and `expanded_a`, the columns added where this schema has none."""
    engine = sa.create_engine(url)
    with engine.begin() as conn:
        have = {c["name"] for c in sa.inspect(conn).get_columns("map_pairs")}
        for name in ("expanded_o", "expanded_a"):
            if name not in have:
                conn.exec_driver_sql(f"ALTER TABLE map_pairs ADD COLUMN {name} TEXT")
        for index, sides in expanded.items():
            texts = [encode_paths(np.array(cells).reshape(-1, 2), np.array([0, len(cells)]))[0] for cells in sides]
            conn.exec_driver_sql(
                "UPDATE map_pairs SET expanded_o = ?, expanded_a = ? WHERE run_id = ? AND pair_index = ?",
                (texts[0] or None, texts[1] or None, run_id, index),
            )
    engine.dispose()


@pytest.fixture
def effort_run(tmp_path):
    """A run of 40 random 10x10 pairs, 30 of them with expanded cells (random counts, some equal), the rest none:
    (client, run_id, {pair_index: (expansions_o, expansions_a)}, expanded cells of pair 0)."""
    url = f"sqlite:///{tmp_path / 'effort.db'}"
    rng = np.random.default_rng(5)
    records = random_records(40, size=10, seed=2)
    with Store.open(url) as store:
        run_id = store.create_run("search")
        store.write_pairs(run_id, records)
    every = [(r, c) for r in range(10) for c in range(10)]
    expanded = {}
    for index in range(30):
        n_o, n_a = int(rng.integers(1, 20)), int(rng.integers(1, 60)) if index % 7 else 10
        expanded[index] = (every[:n_o], every[-n_a:])
    expanded[0] = (every[:50], every[50:])  # free cells on both maps, whatever the obstacles
    add_expansions(url, run_id, expanded)
    store = Store.open(url, create=False)
    yield viewer_for_tests(store).test_client(), run_id, expanded
    store.close()


def test_effort_sort_and_filter_follow_the_expansion_counts(effort_run):
    client, run_id, expanded = effort_run
    counts = {i: (len(o), len(a)) for i, (o, a) in expanded.items()}
    ratio = {i: a / o for i, (o, a) in counts.items()}
    expected = sorted(ratio, key=lambda i: (-ratio[i], i)) + list(range(30, 40))  # none stored: last
    forward, backward = walk(client, run_id, "sort=effort", size=6)
    assert forward == expected and backward == expected
    forward, _ = walk(client, run_id, "sort=effort&min_effort=2.5", size=6)
    assert forward == [i for i in expected if i in ratio and ratio[i] >= 2.5]
    rows = client.get(f"/api/runs/{run_id}/pairs?size=40").get_json()["pairs"]
    for row in rows:
        o, a = counts.get(row["pair_index"], (None, None))
        assert (row["expansions_o"], row["expansions_a"]) == (o, a)
        assert row["effort_ratio"] == (None if o is None else pytest.approx(a / o))
    html = client.get(f"/runs/{run_id}/pairs?sort=effort").get_data(as_text=True)
    assert '<option value="effort" selected>' in html and 'id="filter-min-effort"' in html


def test_pair_page_draws_the_expanded_cells(effort_run):
    client, run_id, expanded = effort_run
    body = client.get(f"/api/pairs/{run_id}/0").get_json()
    assert body["expanded_o"] == [list(c) for c in expanded[0][0]]
    assert body["expanded_a"] == [list(c) for c in expanded[0][1]]
    html = client.get(f"/pairs/{run_id}/0").get_data(as_text=True)
    assert f"cells the search expanded {PALETTE.expanded.name}" in html
    assert f"{len(expanded[0][0])} / {len(expanded[0][1])}" in html
    tint = np.array(PALETTE.expanded.rgb)
    for kind in ("original", "adversarial"):
        image = np.asarray(Image.open(BytesIO(client.get(f"/img/{run_id}/0/{kind}.png").data)).convert("RGB"))
        assert (np.abs(image.astype(int) - tint).sum(axis=2) == 0).any(), kind
    # a pair without them: no tint, no caption
    image = np.asarray(Image.open(BytesIO(client.get(f"/img/{run_id}/35/adversarial.png").data)).convert("RGB"))
    assert not (np.abs(image.astype(int) - tint).sum(axis=2) == 0).any()
    assert "cells the search expanded" not in client.get(f"/pairs/{run_id}/35").get_data(as_text=True)
    assert client.get(f"/api/pairs/{run_id}/35").get_json()["expanded_a"] is None
