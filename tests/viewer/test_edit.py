"""The viewer carries each pair's edit (`add` or `remove`): in the pair JSON and, as words, on the pair page."""

from __future__ import annotations

from tests.viewer.conftest import one_run_client
from vinadv.testing.store import random_records


def test_viewer_pair_json_carries_the_edit(tmp_path):
    records = random_records(6, size=8, seed=1, removes=0.5)
    with one_run_client(tmp_path, records) as (client, run_id):
        got = [client.get(f"/api/pairs/{run_id}/{i}").get_json()["edit"] for i in range(6)]
    assert got == list(records.edit)
