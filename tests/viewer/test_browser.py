"""End to end in a real browser: headless Chromium (Debian's package, /usr/bin/chromium) driven by Playwright's
Python package, against the viewer served from a thread on 127.0.0.1. Open the runs list, filter to FP, open a
pair, label it with the keyboard, and find the label in the database; sort and filter the grid with its form and
see its thumbnails load; open the robustness and bench pages from the header.

Skipped when Chromium or Playwright is missing, except with env CI=true, where that fails the test.
"""

from __future__ import annotations

import contextlib
import math
import threading
from pathlib import Path

import pytest
from werkzeug.serving import make_server

from tests import needs
from tests.needs import CHROMIUM_ARGS
from vinadv.store import Store
from vinadv.viewer.app import create_app

pytestmark = pytest.mark.slow

#: the committed bench entries: the bench page's folder
BENCH = Path(__file__).resolve().parents[2] / "docs" / "results" / "bench"


@pytest.fixture
def served(db):
    """(base URL, url of the database, runs) with the viewer served from a thread on a free 127.0.0.1 port."""
    url, runs = db
    store = Store.open(url, create=False)
    worst = {"k": 1, "valid": 9, "broken": 1, "harmful": 3, "paper_success_rate": 1 / 9, "harmful_rate": 3 / 9}
    settings = {"n": 10, "size": 8, "maps_seed": 1, "objective": "harm", "strategies": ["random"]}
    store.add_robustness("wastar", None, settings, {"clean": {}, "overall": [worst]})
    server = make_server("127.0.0.1", 0, create_app(store, bench_dir=BENCH), threaded=True)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_port}", url, runs
    finally:
        server.shutdown()
        thread.join(10)
        server.server_close()
        store.close()


@contextlib.contextmanager
def browser_page():
    """A page of headless Chromium (20 s timeouts), closed after; skips (or fails on CI) without Chromium."""
    chromium = needs.chromium()
    from playwright.sync_api import sync_playwright  # noqa: PLC0415 (the dev extra: needs.chromium() skips or fails without it)

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, headless=True, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page()
            page.set_default_timeout(20_000)
            yield page
        finally:
            browser.close()


def test_label_a_pair_with_the_keyboard(served):
    base, url, runs = served
    run_id, records = runs["random"]
    fp = records.pair_index[records.label == "FP"].tolist()
    with browser_page() as page:
        # the runs list
        page.goto(base + "/")
        assert page.locator("#runs").is_visible()
        page.click(f'a.run-link[href="/runs/{run_id}/pairs"]')
        page.wait_for_url(f"**/runs/{run_id}/pairs")
        # filter to FP with the form
        page.select_option("#filter-label", "FP")
        page.click("#filter-apply")
        page.wait_for_url(f"**/runs/{run_id}/pairs?label=FP")
        shown = page.locator("#pairs tbody tr td.auto-label").all_inner_texts()
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
    with Store.open(url, create=False) as store:
        stored = [(a["pair_index"], a["label"], a["annotator"]) for a in store.read_annotations(run_id)]
        assert stored == [(fp[0], "DP", "e2e tester")]
        assert store.read_pairs(run_id, pair_indices=[fp[0]]).label.tolist() == ["FP"]


def test_sort_filter_thumbnails_and_results_pages(served):
    base, _, runs = served
    run_id, records = runs["random"]
    change = records.regret_a - records.regret_o
    # regret added, largest first; pairs without it last; ties by pair index
    by_regret = sorted(
        range(len(records)),
        key=lambda i: (math.isnan(change[i]), 0 if math.isnan(change[i]) else -change[i], records.pair_index[i]),
    )
    harmful = {int(i) for i in records.pair_index[records.harm == "harmful"]}
    with browser_page() as page:
        page.goto(base + "/")
        assert "%" in page.locator("#runs tbody tr").first.locator("td.harmful-rate").inner_text()
        page.goto(f"{base}/runs/{run_id}/pairs")
        page.wait_for_load_state("load")
        before = page.locator("a.pair-link").all_inner_texts()
        # the thumbnails load lazily: scrolled to, every one of them arrives
        page.locator("img.thumbnail").last.scroll_into_view_if_needed()
        page.wait_for_function(
            "() => [...document.querySelectorAll('img.thumbnail')].every(i => i.complete && i.naturalWidth > 0)"
        )
        assert page.locator("img.thumbnail").count() == len(before)
        # sort by regret added with the form: the order changes to the oracle's
        page.select_option("#sort", "regret")
        page.click("#filter-apply")
        page.wait_for_url(f"**/runs/{run_id}/pairs?sort=regret")
        shown = [int(t) for t in page.locator("a.pair-link").all_inner_texts()]
        assert shown == [int(records.pair_index[i]) for i in by_regret[: len(shown)]]
        assert shown != [int(t) for t in before]
        # and filter to harmful pairs: only those are shown, still by regret
        page.select_option("#filter-harm", "harmful")
        page.click("#filter-apply")
        page.wait_for_url(f"**/runs/{run_id}/pairs?harm=harmful&sort=regret")
        shown = [int(t) for t in page.locator("a.pair-link").all_inner_texts()]
        assert shown and set(shown) <= harmful
        assert (
            shown == [int(records.pair_index[i]) for i in by_regret if records.pair_index[i] in harmful][: len(shown)]
        )
        # the results pages, from the header
        page.click("#nav-robustness")
        page.wait_for_url("**/robustness")
        assert "33.3%" in page.locator("#robustness td.harmful-rate").first.inner_text()
        page.click("#nav-bench")
        page.wait_for_url("**/bench")
        assert page.locator("table.bench").count() >= 1
        assert page.locator("table.bench tbody tr").count() >= 2
