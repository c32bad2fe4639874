"""The viewer shows every added obstacle of a pair of several (`added_more`): pair page, JSON and image."""

from __future__ import annotations

import numpy as np

from tests.viewer.conftest import one_run_client
from vinadv.testing.store import random_records


def test_pair_page_json_and_image_show_every_added_obstacle(tmp_path):
    records = random_records(4, size=9, seed=2, n_added=3)
    with one_run_client(tmp_path, records) as (client, run_id):
        body = client.get(f"/api/pairs/{run_id}/2").get_json()
        assert body["added_cells"] == records.added[2].tolist() and body["added"] == records.added[2, 0].tolist()
        html = client.get(f"/pairs/{run_id}/2").get_data(as_text=True)
        assert "added obstacles" in html
        shown = html[html.index('id="added"') :].split("</span>")[0]
        assert all(str(cell) in shown for cell in records.added[2].tolist())
        image = client.get(f"/img/{run_id}/2/adversarial.png")
        assert image.status_code == 200 and image.mimetype == "image/png"
    assert np.array_equal(body["added_cells"], records.added[2])
