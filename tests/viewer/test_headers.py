"""Every viewer response carries Content-Security-Policy and X-Frame-Options (issue 21); a read-only database is
browsed, and labelling it is refused."""

from __future__ import annotations

from tests.viewer.conftest import csrf_from, viewer_for_tests
from vinadv.store import Store


def _assert_headers(response):
    csp = response.headers.get("Content-Security-Policy", "")
    assert "default-src 'self'" in csp and "frame-ancestors 'none'" in csp and "script-src 'self'" in csp
    assert "unsafe-inline" not in csp and "unsafe-eval" not in csp
    assert response.headers.get("X-Frame-Options") == "DENY"
    assert response.headers.get("X-Content-Type-Options") == "nosniff"


def test_security_headers_on_every_kind_of_response(client, db):
    run_id = db[1]["random"][0]
    for url in (
        "/",
        f"/runs/{run_id}/pairs",
        f"/pairs/{run_id}/0",
        f"/img/{run_id}/0/original.png",
        "/static/viewer.css",
        "/no/such/page",
        f"/api/pairs/{run_id}/0",
        "/api/runs",
        "/api/nothing",
    ):
        response = client.get(url)
        _assert_headers(response)
    _assert_headers(client.post(f"/pairs/{run_id}/0/label", data={"label": "FP"}))  # refused: no CSRF token


def test_read_only_store_is_browsed_and_labelling_refused(db):
    url, runs = db
    run_id = runs["random"][0]
    with Store.open(url, readonly=True) as store:
        client = viewer_for_tests(store).test_client()
        page = client.get(f"/pairs/{run_id}/0")
        assert page.status_code == 200
        response = client.post(
            f"/pairs/{run_id}/0/label",
            data={"label": "FP", "annotator": "me", "csrf_token": csrf_from(page.get_data(as_text=True))},
        )
        assert response.status_code == 403 and b"read-only" in response.get_data()
        assert store.read_annotations(run_id) == []
