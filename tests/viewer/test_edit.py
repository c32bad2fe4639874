"""The viewer carries each pair's edit (`add` or `remove`): in the pair JSON and, as words, on the pair page."""

from __future__ import annotations

from tests.viewer.conftest import viewer_for_tests
from vinadv.store import Store
from vinadv.testing.store import random_records


def test_viewer_pair_json_carries_the_edit(tmp_path):
    db = f"sqlite:///{tmp_path / 'v.db'}"
    records = random_records(6, size=8, seed=1, removes=0.5)
    with Store.open(db) as store:
        run_id = store.create_run("v")
        store.write_pairs(run_id, records)
        client = viewer_for_tests(store).test_client()
        got = [client.get(f"/api/pairs/{run_id}/{i}").get_json()["edit"] for i in range(6)]
    assert got == list(records.edit)
