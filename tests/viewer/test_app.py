"""Flask test-client tests of every page and JSON endpoint of the viewer, against the stored records (numpy
oracles on the records written), and of bad input: unknown ids, malformed parameters, forged POSTs."""

from __future__ import annotations

import re
from io import BytesIO

import numpy as np
import pytest
from PIL import Image

from tests.viewer.conftest import N_RANDOM, csrf_from
from vinadv.store import LABELS, Store
from vinadv.testing.store import random_records
from vinadv.viewer.app import create_app
from vinadv.viewer.formats import fmt_cost as _fmt_cost
from vinadv.viewer.render import PATH_IMAGE_SCALE, PngCache

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _all_pages(client, run_id, query=""):
    """Every pair index of the grid, following next_after links of the JSON endpoint."""
    seen, after = [], None
    while True:
        sep = "&" if query else ""
        url = f"/api/runs/{run_id}/pairs?{query}{sep}size=37" + ("" if after is None else f"&after={after}")
        body = client.get(url).get_json()
        seen += [p["pair_index"] for p in body["pairs"]]
        after = body["next_after"]
        if after is None:
            return seen


# -------------------------------------------------------------------------------------------------- runs


def test_runs_page_and_api_counts(client, db):
    _, runs = db
    page = client.get("/")
    assert page.status_code == 200
    html = page.get_data(as_text=True)
    assert "random" in html and "crafted" in html
    body = client.get("/api/runs").get_json()
    assert [r["name"] for r in body["runs"]] == ["random", "crafted"]
    for run in body["runs"]:
        records = runs[run["name"]][1]
        expected = {lab: int(np.sum(records.label == lab)) for lab in LABELS}
        assert run["counts"] == expected
        assert run["n_pairs"] == len(records)
        valid = len(records) - expected["invalid"]
        assert run["success_rate"] == pytest.approx((expected["UrP"] + expected["FP"]) / valid)
        assert f"{100 * run['success_rate']:.1f}%" in html


def test_runs_page_empty_database(tmp_path):
    with Store.open(f"sqlite:///{tmp_path / 'empty.db'}") as store:
        client = create_app(store).test_client()
        assert "No runs" in client.get("/").get_data(as_text=True)
        assert client.get("/api/runs").get_json() == {"runs": []}


# -------------------------------------------------------------------------------------------------- grid


def test_grid_pages_cover_every_pair_in_order(client, db):
    run_id, records = db[1]["random"]
    assert _all_pages(client, run_id) == sorted(records.pair_index.tolist())
    crafted_id, _ = db[1]["crafted"]
    assert _all_pages(client, crafted_id) == [10, 20, 30]


@pytest.mark.parametrize(
    "query,mask",
    [
        ("label=FP", lambda r: r.label == "FP"),
        ("label=invalid", lambda r: r.label == "invalid"),
        ("attack=yes", lambda r: r.attack),
        ("attack=no", lambda r: ~r.attack),
        ("source=svm", lambda r: r.label_source == "svm"),
        ("label=UrP&source=rule", lambda r: (r.label == "UrP") & (r.label_source == "rule")),
        ("label=DP&attack=yes", lambda r: np.zeros(len(r), bool)),
        ("harm=harmful", lambda r: r.harm == "harmful"),
        ("harm=harmless&label=FP", lambda r: (r.harm == "harmless") & (r.label == "FP")),
    ],
)
def test_grid_filters(client, db, query, mask):
    run_id, records = db[1]["random"]
    assert _all_pages(client, run_id, query) == records.pair_index[mask(records)].tolist()


def test_grid_html_paging_links(client, db):
    run_id, records = db[1]["random"]
    first = client.get(f"/runs/{run_id}/pairs?label=FP&size=5")
    assert first.status_code == 200
    html = first.get_data(as_text=True)
    fp = records.pair_index[records.label == "FP"].tolist()
    assert f"after={fp[4]}" in html and "before=" not in html
    second = client.get(f"/runs/{run_id}/pairs?label=FP&size=5&after={fp[4]}").get_data(as_text=True)
    for i in fp[5:10]:
        assert f"/pairs/{run_id}/{i}?label=FP" in second
    assert f"before={fp[5]}" in second
    back = client.get(f"/api/runs/{run_id}/pairs?label=FP&size=5&before={fp[5]}").get_json()
    assert [p["pair_index"] for p in back["pairs"]] == fp[:5]
    assert back["prev_before"] is None and back["next_after"] == fp[4]


def test_grid_row_values_match_records(client, db):
    run_id, records = db[1]["crafted"]
    rows = client.get(f"/api/runs/{run_id}/pairs").get_json()["pairs"]
    assert [(r["label"], r["label_source"], r["score"], r["dh"], r["dv"], r["attack"]) for r in rows] == [
        ("FP", "svm", 0.9, 3, 0, True),
        ("DP", "svm", None, 1, 2, False),
        ("invalid", "rule", None, None, None, False),
    ]


def test_filter_form_redirect(client, db):
    run_id, _ = db[1]["random"]
    response = client.get(f"/pairs?run={run_id}&label=FP&attack=&source=")
    assert response.status_code == 303
    assert response.headers["Location"].endswith(f"/runs/{run_id}/pairs?label=FP")


def test_grid_empty_result(client, db):
    run_id, _ = db[1]["crafted"]
    response = client.get(f"/runs/{run_id}/pairs?label=UcP")
    assert response.status_code == 200 and "No pairs match" in response.get_data(as_text=True)


# -------------------------------------------------------------------------------------------- pair page


def test_pair_page_shows_labels_distances_images(client, db):
    run_id, _ = db[1]["crafted"]
    html = client.get(f"/pairs/{run_id}/10").get_data(as_text=True)
    for text in (
        "FP",
        "0.900",
        "3 / 0",
        f"/img/{run_id}/10/original.png",
        f"/img/{run_id}/10/adversarial.png",
        f"/img/{run_id}/10/pathimage.png",
        'id="next-pair"',
        "svm",
    ):
        assert text in html
    assert 'id="prev-pair"' not in html  # the first pair


def test_pair_navigation_follows_filters(client, db):
    run_id, records = db[1]["random"]
    fp = records.pair_index[records.label == "FP"].tolist()
    html = client.get(f"/pairs/{run_id}/{fp[1]}?label=FP").get_data(as_text=True)
    assert f'href="/pairs/{run_id}/{fp[2]}?label=FP"' in html
    assert f'href="/pairs/{run_id}/{fp[0]}?label=FP"' in html


def test_pair_json_matches_records(client, db):
    run_id, records = db[1]["random"]
    for i in (0, 17, N_RANDOM - 1):
        body = client.get(f"/api/pairs/{run_id}/{i}").get_json()
        row = int(np.flatnonzero(records.pair_index == i)[0])
        assert np.array_equal(np.array([[c == "1" for c in line] for line in body["map_o"]]), records.obstacles_o[row])
        assert np.array_equal(np.array([[c == "1" for c in line] for line in body["map_a"]]), records.obstacles_a[row])
        o = records.path_o[row]
        a = records.path_a[row]
        assert body["path_o"] == o.tolist() and body["path_a"] == a.tolist()
        assert body["added"] == records.added[row, 0].tolist() and body["added_cells"] == records.added[row].tolist()
        assert body["goal"] == records.goals[row].tolist()
        assert body["label"] == records.label[row] and body["attack"] == bool(records.attack[row])
        score = records.score[row]
        assert body["score"] == (None if np.isnan(score) else pytest.approx(score))
        assert body["dh"] == (None if records.dh[row] < 0 else int(records.dh[row]))
        assert body["human_labels"] == []
        assert body["harm"] == records.harm[row] and body["expert_label"] == records.expert_label[row]
        for name in ("opt_cost_o", "opt_cost_a", "cost_o", "cost_a", "regret_o", "regret_a"):
            value = getattr(records, name)[row]
            assert body[name] == (None if np.isnan(value) else pytest.approx(value)), name


def test_harm_and_regret_on_the_grid_and_the_pair_page(client, db):
    run_id, records = db[1]["random"]
    row = int(np.flatnonzero((records.harm == "harmful") & ~np.isnan(records.regret_a))[0])
    i = int(records.pair_index[row])
    rows = client.get(f"/api/runs/{run_id}/pairs?harm=harmful&size=200").get_json()["pairs"]
    got = next(r for r in rows if r["pair_index"] == i)
    assert got["harm"] == "harmful" and got["regret_a"] == pytest.approx(records.regret_a[row])
    html = client.get(f"/pairs/{run_id}/{i}?harm=harmful").get_data(as_text=True)
    assert 'id="harm">harmful' in html and f"{records.regret_a[row]:.3f}" in html
    assert client.get(f"/runs/{run_id}/pairs?harm=bad").status_code == 400
    assert 'id="filter-harm"' in client.get(f"/runs/{run_id}/pairs").get_data(as_text=True)


def test_grid_page_filtered_by_harm_lists_those_pairs_with_their_harm_and_regrets(client, db):
    run_id, records = db[1]["random"]
    html = client.get(f"/runs/{run_id}/pairs?harm=harmless&size=20").get_data(as_text=True)
    order = np.argsort(records.pair_index)
    rows = order[records.harm[order] == "harmless"][:20]
    body = html.split("<tbody>", 1)[1].split("</tbody>", 1)[0]
    assert [int(i) for i in re.findall(r'class="pair-link"[^>]*>(\d+)<', body)] == records.pair_index[rows].tolist()
    assert body.count("<td>harmless</td>") == len(rows) == 20
    for row in rows:
        assert f"{_fmt_cost(_nan_none(records.regret_o[row]))} / {_fmt_cost(_nan_none(records.regret_a[row]))}" in body
    assert '<option value="harmless" selected>' in html
    # float noise of a zero regret reads 0.000, not -0.000
    assert (_fmt_cost(-1.7e-15), _fmt_cost(1.41421356), _fmt_cost(None)) == ("0.000", "1.414", "—")


def _nan_none(value):
    return None if np.isnan(value) else float(value)


@pytest.mark.parametrize("kind", ["original", "adversarial", "pathimage"])
def test_images_png_cached_with_etag(client, app, db, kind):
    run_id, _ = db[1]["crafted"]
    url = f"/img/{run_id}/20/{kind}.png"
    first = client.get(url)
    assert first.status_code == 200 and first.mimetype == "image/png" and first.data.startswith(PNG_MAGIC)
    assert "max-age" in first.headers["Cache-Control"] and first.headers["ETag"]
    cache = app.extensions["vinadv"].images
    misses = cache.misses
    again = client.get(url)
    assert again.data == first.data and cache.misses == misses  # served from the LRU cache
    not_modified = client.get(url, headers={"If-None-Match": first.headers["ETag"]})
    assert not_modified.status_code == 304 and not_modified.data == b""


def test_path_image_pixels_follow_the_paper_colours(client, db):
    run_id, _ = db[1]["crafted"]
    image = np.asarray(Image.open(BytesIO(client.get(f"/img/{run_id}/10/pathimage.png").data)).convert("RGB"))
    cell = image[::PATH_IMAGE_SCALE, ::PATH_IMAGE_SCALE]
    assert cell.shape == (6, 6, 3)
    assert tuple(cell[3, 3]) == (255, 0, 0)  # original path only
    assert tuple(cell[1, 3]) == (0, 0, 255)  # adversarial path only
    assert tuple(cell[1, 1]) == (255, 0, 0)  # both: red on top
    assert tuple(cell[0, 0]) == (0, 0, 0)


def test_png_cache_evicts_least_recently_used():
    cache = PngCache(max_bytes=10)
    cache.put("a", b"1234")
    cache.put("b", b"1234")
    assert cache.get("a") == b"1234"  # a is now the most recent
    cache.put("c", b"1234")
    assert cache.get("b") is None and cache.get("a") == b"1234" and cache.get("c") == b"1234"


# --------------------------------------------------------------------------------------------- labelling


def test_label_post_stores_annotation_and_moves_on(client, store, db):
    run_id, records = db[1]["random"]
    fp = records.pair_index[records.label == "FP"].tolist()
    token = csrf_from(client.get(f"/pairs/{run_id}/{fp[0]}?label=FP").get_data(as_text=True))
    response = client.post(
        f"/pairs/{run_id}/{fp[0]}/label?label=FP", data={"csrf_token": token, "label": "DP", "annotator": "alice"}
    )
    assert response.status_code == 303
    assert response.headers["Location"].endswith(f"/pairs/{run_id}/{fp[1]}?label=FP")
    assert "vinadv_annotator=alice" in response.headers["Set-Cookie"]
    assert f"pair {fp[0]} labelled DP by alice" in client.get(response.headers["Location"]).get_data(as_text=True)
    got = [(a["pair_index"], a["label"], a["annotator"]) for a in store.read_annotations(run_id)]
    assert got == [(fp[0], "DP", "alice")]
    # the automatic label is untouched
    assert store.read_pairs(run_id, pair_indices=np.array([fp[0]])).label.tolist() == ["FP"]
    page = client.get(f"/pairs/{run_id}/{fp[0]}").get_data(as_text=True)
    assert "alice" in page and 'value="alice"' in page  # shown, and the name is remembered
    grid = client.get(f"/api/runs/{run_id}/pairs?label=FP&size=1").get_json()
    assert grid["pairs"][0]["label"] == "FP" and grid["pairs"][0]["human_labels"][0]["label"] == "DP"
    assert client.get(f"/api/pairs/{run_id}/{fp[0]}").get_json()["human_labels"][0]["annotator"] == "alice"


def test_label_last_pair_stays_and_default_annotator(client, store, db):
    run_id, _ = db[1]["crafted"]
    token = csrf_from(client.get(f"/pairs/{run_id}/30").get_data(as_text=True))
    response = client.post(f"/pairs/{run_id}/30/label", data={"csrf_token": token, "label": "UcP"})
    assert response.status_code == 303 and response.headers["Location"].endswith(f"/pairs/{run_id}/30")
    assert [(a["label"], a["annotator"]) for a in store.read_annotations(run_id)] == [("UcP", "anonymous")]
    assert "labelled UcP by anonymous" in client.get(f"/pairs/{run_id}/30").get_data(as_text=True)


# --------------------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("url", "status"),
    [
        # unknown ids: not found
        ("/runs/999/pairs", 404),
        ("/pairs/999/0", 404),
        ("/img/999/0/original.png", 404),
        ("/api/runs/999/pairs", 404),
        ("/api/pairs/999/0", 404),
        ("/pairs/{run}/5", 404),
        ("/pairs/{run}/99999999", 404),
        ("/img/{run}/5/original.png", 404),
        ("/api/pairs/{run}/5", 404),
        ("/img/{run}/10/other.png", 404),
        ("/pairs/{run}/99999999999999999999999", 404),
        ("/runs/99999999999999999999999/pairs", 404),
        ("/runs/abc/pairs", 404),
        ("/pairs/{run}/-1", 404),
        ("/nowhere", 404),
        ("/pairs?run=12345", 404),  # the filter form's redirect to an unknown run
        # parameters a page does not take, or values it cannot read: a bad request
        ("/?x=1", 400),
        ("/pairs/{run}/10?after=1", 400),
        ("/api/pairs/{run}/10?x=1", 400),
        ("/img/{run}/10/original.png?x=1", 400),
        ("/pairs", 400),
        ("/pairs?run=abc", 400),
        ("/pairs/{run}/10?label=X", 400),
    ],
)
def test_bad_urls_are_refused_with_their_status(client, db, url, status):
    run_id, _ = db[1]["crafted"]
    response = client.get(url.format(run=run_id))
    assert response.status_code == status
    if url.startswith("/api/"):  # the API answers in JSON, with the status in the body too
        assert response.is_json and response.get_json()["status"] == status


@pytest.mark.parametrize(
    "query,needle",
    [
        ("after=abc", "after"),
        ("after=-3", "after"),
        ("after=1.5", "after"),
        ("before=%EF%BC%91", "before"),
        ("size=0", "size"),
        ("size=100000", "size"),
        ("size=", None),
        ("label=XX", "label"),
        ("label=fp", "label"),
        ("attack=maybe", "attack"),
        ("colour=red", "colour"),
        ("after=1&before=5", "at most one"),
        ("label=FP&label=DP", "more than once"),
        ("after=99999999999999999999", "after"),
        ("source=%01", "source"),
        # the sort and its filters (their orders: tests/viewer/test_sort.py)
        ("sort=nope", "sort"),
        ("sort=effort", "sort"),  # the run holds no expansions
        ("min_effort=2", "min_effort"),
        ("min_regret=abc", "min_regret"),
        ("min_regret=nan", "min_regret"),
        ("sort=regret&after=99999", "no pair 99999"),
    ],
)
def test_malformed_grid_params_are_400_naming_the_parameter(client, db, query, needle):
    run_id, _ = db[1]["random"]
    html = client.get(f"/runs/{run_id}/pairs?{query}")
    api = client.get(f"/api/runs/{run_id}/pairs?{query}")
    if needle is None:  # an empty size means the default
        assert html.status_code == 200 and api.status_code == 200
        return
    assert html.status_code == 400 and needle in html.get_data(as_text=True)
    assert api.status_code == 400 and needle in api.get_json()["message"]


def _token(client, run_id, pair=10):
    return csrf_from(client.get(f"/pairs/{run_id}/{pair}").get_data(as_text=True))


def test_forged_posts_are_refused(client, app, store, db):
    run_id, _ = db[1]["crafted"]
    url = f"/pairs/{run_id}/10/label"
    # no session, no token
    assert client.post(url, data={"label": "FP"}).status_code == 403
    # a session but no token, an empty one, a wrong one
    token = _token(client, run_id)
    assert client.post(url, data={"label": "FP"}).status_code == 403
    assert client.post(url, data={"label": "FP", "csrf_token": ""}).status_code == 403
    assert client.post(url, data={"label": "FP", "csrf_token": token[:-2] + "xx"}).status_code == 403
    # the right token from another session (another client) does not carry over
    other = app.test_client()
    assert other.post(url, data={"label": "FP", "csrf_token": token}).status_code == 403
    # the right token, but posted from another site
    assert (
        client.post(
            url, data={"label": "FP", "csrf_token": token}, headers={"Origin": "http://evil.example"}
        ).status_code
        == 403
    )
    # labels change only by POST
    assert client.get(url + "?label=FP").status_code == 405
    assert store.read_annotations(run_id) == []
    # and the right token works
    assert (
        client.post(url, data={"label": "FP", "csrf_token": token}, headers={"Origin": "http://localhost"}).status_code
        == 303
    )


@pytest.mark.parametrize(
    "form,status",
    [
        ({"label": "invalid"}, 400),
        ({"label": "XX"}, 400),
        ({}, 400),
        ({"label": "FP", "annotator": "<script>"}, 400),
        ({"label": "FP", "annotator": "x" * 65}, 400),
        ({"label": "FP", "extra": "1"}, 400),
        ({"label": ["FP", "DP"]}, 400),  # two labels for one pair: refused, not the first taken
        ({"label": ["FP", "FP"]}, 400),
        ({"label": "FP", "annotator": ["ann", "bob"]}, 400),
    ],
)
def test_bad_label_forms_are_400(client, store, db, form, status):
    run_id, _ = db[1]["crafted"]
    token = _token(client, run_id)
    assert client.post(f"/pairs/{run_id}/10/label", data={"csrf_token": token, **form}).status_code == status
    assert store.read_annotations(run_id) == []


def test_label_unknown_pair_is_404(client, store, db):
    run_id, _ = db[1]["crafted"]
    token = _token(client, run_id)
    assert client.post(f"/pairs/{run_id}/11/label", data={"csrf_token": token, "label": "FP"}).status_code == 404
    assert client.post("/pairs/999/10/label", data={"csrf_token": token, "label": "FP"}).status_code == 404
    assert store.read_annotations(run_id) == []


def test_foreign_host_header_refused_unless_remote_allowed(store, db):
    run_id, _ = db[1]["crafted"]
    local = create_app(store).test_client()
    assert local.get("/", headers={"Host": "evil.example"}).status_code == 400
    assert local.get("/", headers={"Host": "127.0.0.1:8000"}).status_code == 200
    assert local.get("/", headers={"Host": "[::1]:8000"}).status_code == 200
    remote = create_app(store, allow_remote=True).test_client()
    assert remote.get(f"/pairs/{run_id}/10", headers={"Host": "viewer.lab:8000"}).status_code == 200


def test_html_escapes_stored_text(tmp_path):
    with Store.open(f"sqlite:///{tmp_path / 'x.db'}") as store:
        run_id = store.create_run("<script>alert(1)</script>")
        records = random_records(2, size=6)
        records.label_source[:] = "<b>src</b>"
        store.write_pairs(run_id, records)
        client = create_app(store).test_client()
        for url in ("/", f"/runs/{run_id}/pairs", f"/pairs/{run_id}/0"):
            html = client.get(url).get_data(as_text=True)
            assert "<script>alert" not in html and "<b>src" not in html


def test_pair_page_and_json_say_the_runs_movement_model(tmp_path):
    url = f"sqlite:///{tmp_path / 'm.db'}"
    with Store.open(url) as store:
        moore = store.create_run("m", moves="moore")
        store.write_pairs(moore, random_records(3, size=7, seed=2))
        octile = store.create_run("o")
        store.write_pairs(octile, random_records(3, size=7, seed=3))
    store = Store.open(url)
    client = create_app(store, secret_key="k").test_client()
    for run_id, moves in ((moore, "moore"), (octile, "octile")):
        assert client.get(f"/api/pairs/{run_id}/0").get_json()["moves"] == moves
        page = client.get(f"/pairs/{run_id}/0").get_data(as_text=True)
        assert f'<span class="hint" id="moves">({moves} moves)</span>' in page
    store.close()
