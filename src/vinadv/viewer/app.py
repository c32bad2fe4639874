"""The viewer and annotation tool: a small Flask app over one vinadv database.

Pages (server-rendered Jinja, a little JavaScript for keyboard shortcuts):
  GET  /                                  runs: category counts, attack success rate, harmful rate with its interval
  GET  /pairs?run=ID&...                  redirect to the grid of run ID (the filter form's target)
  GET  /runs/<run>/pairs?label=&attack=&source=&harm=&min_regret=&min_effort=&sort=&after=|before=&size=
                                          the pair grid with thumbnails, keyset-paged in the order of `sort`
  GET  /pairs/<run>/<index>?<filters>     one pair: maps, paths, expanded cells, path image, labels; n/p follow them
  POST /pairs/<run>/<index>/label         store a human label (form: csrf_token, label, annotator)
  GET  /img/<run>/<index>/<kind>.png      kind: original | adversarial | pathimage
  GET  /thumb/<run>/<index>.png           the pair's thumbnail
  GET  /robustness                        the database's robustness benchmarks (`vinadv robustness`)
  GET  /bench                             the leaderboard of the entries in `bench_dir` (`vinadv serve --bench DIR`)
JSON: GET /api/runs, /api/runs/<run>/pairs?<filters and paging>, /api/pairs/<run>/<index>, /api/robustness,
/api/bench.

The routes live by concern: `routes_pairs` (runs, pairs, images), `routes_results` (robustness, bench); what they
share between requests is `state.ViewerState`, their parameters are read by `params`.

Security: meant for 127.0.0.1. Unless `allow_remote`, requests whose Host header is not a loopback name are
refused (DNS rebinding). Labels change only by POST with the per-session CSRF token kept in Flask's signed
session cookie (SameSite=Strict); a POST with a foreign Origin is refused too. Every path and query parameter
is validated: an unknown run or pair is a 404, a malformed or unknown parameter a 400 naming it.
Human labels go to the `annotations` table; the automatic label in `map_pairs` is never written.
"""

from __future__ import annotations

import ipaddress
import os
import secrets

from flask import Flask, abort, jsonify, render_template, request
from werkzeug.exceptions import HTTPException

from vinadv.plot.palette import PALETTE
from vinadv.store import LABELS, Store
from vinadv.viewer import formats, params, routes_pairs, routes_results
from vinadv.viewer.routes_pairs import HUMAN_LABELS, LABEL_KEYS
from vinadv.viewer.state import ViewerState
from vinadv.vocabulary import HARMS

#: the pages use their own scripts, styles and images only (the templates hold no inline script or style)
CONTENT_SECURITY_POLICY = (
    "default-src 'self'; img-src 'self' data:; style-src 'self'; "
    "script-src 'self'; object-src 'none'; base-uri 'none'; form-action 'self'; "
    "frame-ancestors 'none'"
)
_LOOPBACK_NAMES = {"localhost", "127.0.0.1", "::1", "[::1]"}


def create_app(
    store: Store,
    *,
    secret_key: bytes | str | None = None,
    allow_remote: bool = False,
    image_cache_bytes: int = 64 * 2**20,
    bench_dir: str | os.PathLike | None = None,
) -> Flask:
    """The viewer app over an open `store`. `secret_key` signs the session cookie (random per process if
    None, so sessions end with the server); `allow_remote` lifts the loopback-only Host check; `bench_dir`: a folder
    of bench entries whose leaderboard `/bench` shows (None: no bench page)."""
    app = Flask(__name__)
    app.config.update(
        SECRET_KEY=secret_key or secrets.token_bytes(32),
        SESSION_COOKIE_SAMESITE="Strict",
        SESSION_COOKIE_HTTPONLY=True,
        MAX_CONTENT_LENGTH=64 * 1024,
    )
    app.json.sort_keys = False
    app.extensions["vinadv"] = state = ViewerState(store, image_cache_bytes, bench_dir)
    app.jinja_env.globals.update(
        PALETTE=PALETTE,
        LABELS=LABELS,
        HUMAN_LABELS=HUMAN_LABELS,
        LABEL_KEYS=LABEL_KEYS,
        HARMS=HARMS,
        SORT_NAMES=params.SORT_NAMES,
        has_bench=bench_dir is not None,
        fmt_score=formats.fmt_score,
        fmt_dist=formats.fmt_dist,
        fmt_cost=formats.fmt_cost,
        fmt_ratio=formats.fmt_ratio,
        fmt_pct=formats.fmt_pct,
        fmt_pct_ci=formats.fmt_pct_ci,
        csrf_token=params.csrf_token,
    )

    @app.before_request
    def _check_host():
        if allow_remote:
            return None
        host = request.host
        host = host[: host.find("]") + 1] if host.startswith("[") else host.rsplit(":", 1)[0]
        if host.lower() not in _LOOPBACK_NAMES:
            abort(
                400,
                description=f"Host {request.host!r} refused: this server only answers on loopback "
                "addresses (start it with --allow-remote to serve other hosts)",
            )
        return None

    @app.after_request
    def _security_headers(response):
        # every response: no framing (clickjacking of the label buttons), scripts and styles from this server only
        response.headers.setdefault("Content-Security-Policy", CONTENT_SECURITY_POLICY)
        response.headers.setdefault("X-Frame-Options", "DENY")
        response.headers.setdefault("X-Content-Type-Options", "nosniff")
        return response

    @app.errorhandler(HTTPException)
    def _error(exc: HTTPException):
        if request.path.startswith("/api/"):
            return jsonify(error=exc.name, status=exc.code, message=exc.description), exc.code
        return render_template("error.html", error=exc), exc.code

    routes_pairs.register(app, state)
    routes_results.register(app, state)
    return app


def is_loopback(host: str) -> bool:
    """Whether `host` (a name or an address) is a loopback address the server may bind without --allow-remote."""
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


__all__ = ["HUMAN_LABELS", "LABEL_KEYS", "create_app", "is_loopback"]
