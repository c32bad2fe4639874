"""The report opens in headless Chromium: every image loads, no console error, no failed request, nothing wider than
the window (no table needs its scroll box at 1280 px); a screenshot.

Skipped with a message where Chromium or Playwright is missing, except under CI=true, where that fails.
"""

from __future__ import annotations

import functools
import http.server
import os
import threading
from pathlib import Path

import pytest
from tests import needs
from tests.needs import CHROMIUM_ARGS

from vinadv.report.render import PAGE_SECTIONS

pytestmark = pytest.mark.slow

#: screenshots are kept here when set (say, as CI artefacts); else in the test's tmp_path
SCREENSHOT_DIR = os.environ.get("VINADV_SCREENSHOT_DIR")


@pytest.fixture
def served(evaluated):
    """The evaluated report served by a tiny http.server on 127.0.0.1 (a random port)."""
    _, _, out = evaluated
    handler = functools.partial(_QuietHandler, directory=str(out))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/index.html", out
    finally:
        server.shutdown()
        server.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):  # keep pytest's output clean
        pass


def _open_and_check(url: str, screenshot: Path, chromium: str) -> dict:
    from playwright.sync_api import sync_playwright  # noqa: PLC0415 (the dev extra: needs.chromium() skips or fails without it)

    errors, failed, bad_status = [], [], []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS, headless=True)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.on("console", lambda msg: errors.append(msg.text) if msg.type == "error" else None)
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.on("requestfailed", lambda req: failed.append(req.url))
            page.on("response", lambda resp: bad_status.append((resp.url, resp.status)) if resp.status >= 400 else None)
            page.goto(url, wait_until="load")
            images = page.evaluate(
                "() => Array.from(document.images).map(i => ({src: i.getAttribute('src'), complete: i.complete,"
                " width: i.naturalWidth}))"
            )
            sections = page.evaluate("() => Array.from(document.querySelectorAll('section')).map(s => s.id)")
            widths = page.evaluate(
                "() => ({page: document.documentElement.scrollWidth, window: window.innerWidth,"
                " overflowing: Array.from(document.querySelectorAll('table')).filter("
                "t => t.getBoundingClientRect().right > document.body.getBoundingClientRect().right + 1)"
                ".map(t => t.querySelector('caption') ? t.querySelector('caption').textContent : '?')})"
            )
            page.screenshot(path=str(screenshot), full_page=True)
        finally:
            browser.close()
    return {
        "errors": errors,
        "failed": failed,
        "bad_status": bad_status,
        "images": images,
        "sections": sections,
        "widths": widths,
    }


@pytest.mark.parametrize("via", ["http", "file"])
def test_report_opens_in_headless_chromium_without_errors(served, tmp_path, via):
    chromium = needs.chromium()
    http_url, out = served
    url = http_url if via == "http" else out.joinpath("index.html").resolve().as_uri()
    folder = Path(SCREENSHOT_DIR) if SCREENSHOT_DIR else tmp_path
    folder.mkdir(parents=True, exist_ok=True)
    screenshot = folder / f"report-{via}.png"
    seen = _open_and_check(url, screenshot, chromium)
    assert seen["errors"] == [] and seen["failed"] == [] and seen["bad_status"] == []
    assert seen["sections"] == [sid for sid, _ in PAGE_SECTIONS]
    assert seen["widths"]["page"] <= seen["widths"]["window"], seen["widths"]
    assert seen["widths"]["overflowing"] == []
    assert len(seen["images"]) >= 7
    missing = [img["src"] for img in seen["images"] if not img["complete"] or img["width"] == 0]
    assert missing == []
    data = screenshot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 50_000
