"""End to end in a real browser: headless Chromium (Debian's package, /usr/bin/chromium) driven by Playwright's
Python package, against the viewer served from a thread on 127.0.0.1. Open the runs list, filter to FP, open a
pair, label it with the keyboard, and find the label in the database.

Skipped when Chromium or Playwright is missing, except with env CI=true, where that fails the test.
"""

from __future__ import annotations

import threading

import pytest
from werkzeug.serving import make_server

from tests import needs
from tests.needs import CHROMIUM_ARGS
from vinadv.store import Store
from vinadv.viewer.app import create_app

pytestmark = pytest.mark.slow


@pytest.fixture
def served(db):
    """(base URL, url of the database, runs) with the viewer served from a thread on a free 127.0.0.1 port."""
    url, runs = db
    store = Store.open(url, create=False)
    server = make_server("127.0.0.1", 0, create_app(store), threaded=True)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_port}", url, runs
    finally:
        server.shutdown()
        thread.join(10)
        server.server_close()
        store.close()


def test_label_a_pair_with_the_keyboard(served):
    chromium = needs.chromium()
    from playwright.sync_api import sync_playwright  # noqa: PLC0415 (the dev extra: needs.chromium() skips or fails without it)

    base, url, runs = served
    run_id, records = runs["random"]
    fp = records.pair_index[records.label == "FP"].tolist()
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, headless=True, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page()
            page.set_default_timeout(20_000)
            # the runs list
            page.goto(base + "/")
            assert page.locator("#runs").is_visible()
            page.click(f'a.run-link[href="/runs/{run_id}/pairs"]')
            page.wait_for_url(f"**/runs/{run_id}/pairs")
            # filter to FP with the form
            page.select_option("#filter-label", "FP")
            page.click("#filter-apply")
            page.wait_for_url(f"**/runs/{run_id}/pairs?label=FP")
            shown = page.locator("#pairs tbody tr td:nth-child(2)").all_inner_texts()
            assert shown and set(shown) == {"FP"}
            first = page.locator("a.pair-link").first
            assert first.inner_text() == str(fp[0])
            # open the pair: both maps and the path image load
            first.click()
            page.wait_for_url(f"**/pairs/{run_id}/{fp[0]}?label=FP")
            page.wait_for_load_state("load")
            widths = page.eval_on_selector_all(".images img", "imgs => imgs.map(i => i.naturalWidth)")
            assert len(widths) == 3 and all(w > 0 for w in widths)
            assert page.inner_text("#auto-label") == "FP"
            # name the annotator, leave the field, label with the keyboard: d = DP
            page.fill("#annotator", "e2e tester")
            page.locator("#auto-label").click()
            with page.expect_navigation():
                page.keyboard.press("d")
            page.wait_for_url(f"**/pairs/{run_id}/{fp[1]}?label=FP")  # moved on within the filter
            assert f"pair {fp[0]} labelled DP by e2e tester" in page.inner_text("#flash")
            # p goes back, and the pair shows the human label beside the automatic one
            with page.expect_navigation():
                page.keyboard.press("p")
            page.wait_for_url(f"**/pairs/{run_id}/{fp[0]}?label=FP")
            assert "DP" in page.inner_text("#human-labels") and "e2e tester" in page.inner_text("#human-labels")
            assert page.input_value("#annotator") == "e2e tester"  # remembered in a cookie
        finally:
            browser.close()
    with Store.open(url, create=False) as store:
        stored = [(a["pair_index"], a["label"], a["annotator"]) for a in store.read_annotations(run_id)]
        assert stored == [(fp[0], "DP", "e2e tester")]
        assert store.read_pairs(run_id, pair_indices=[fp[0]]).label.tolist() == ["FP"]
