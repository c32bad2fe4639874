"""The viewer and annotation tool: a small Flask app over one vinadv database.

Pages (server-rendered Jinja, a little JavaScript for keyboard shortcuts):
  GET  /                                  runs, their category counts and attack success rate
  GET  /pairs?run=ID&...                  redirect to the grid of run ID (the filter form's target)
  GET  /runs/<run>/pairs?label=&attack=&source=&after=|before=&size=
                                          the pair grid, keyset-paged by pair index
  GET  /pairs/<run>/<index>?<filters>     one pair: maps, paths, path image, dh/dv, labels; n/p follow the filters
  POST /pairs/<run>/<index>/label         store a human label (form: csrf_token, label, annotator)
  GET  /img/<run>/<index>/<kind>.png      kind: original | adversarial | pathimage
JSON: GET /api/runs, /api/runs/<run>/pairs?<filters and paging>, /api/pairs/<run>/<index>.

Security: meant for 127.0.0.1. Unless `allow_remote`, requests whose Host header is not a loopback name are
refused (DNS rebinding). Labels change only by POST with the per-session CSRF token kept in Flask's signed
session cookie (SameSite=Strict); a POST with a foreign Origin is refused too. Every path and query parameter
is validated: an unknown run or pair is a 404, a malformed or unknown parameter a 400 naming it.
Human labels go to the `annotations` table; the automatic label in `map_pairs` is never written.
"""

from __future__ import annotations

import hashlib
import ipaddress
import math
import re
import secrets
import threading
import time
from collections import OrderedDict
from urllib.parse import urlencode, urlsplit

import numpy as np
from flask import (
    Flask,
    Response,
    abort,
    flash,
    jsonify,
    redirect,
    render_template,
    request,
    session,
    url_for,
)
from werkzeug.exceptions import BadRequest, Forbidden, HTTPException

from vinadv.errors import InputError
from vinadv.plot.palette import PALETTE
from vinadv.store import LABELS, Store
from vinadv.store.records import PairRecords
from vinadv.viewer.render import KINDS, PngCache, render_pair_png
from vinadv.vocabulary import HARM_FLOAT_FIELDS, HARMS, SUCCESS_LABELS

#: labels a person can set (the automatic 'invalid' is a fact about the original path, not a judgement)
HUMAN_LABELS = ("FP", "DP", "UrP", "UcP")
#: keyboard shortcut of each human label
LABEL_KEYS = {"FP": "f", "DP": "d", "UrP": "u", "UcP": "c"}
DEFAULT_PAGE_SIZE = 50
MAX_PAGE_SIZE = 500
ANNOTATOR_COOKIE = "vinadv_annotator"
DEFAULT_ANNOTATOR = "anonymous"
#: the pages use their own scripts, styles and images only (the templates hold no inline script or style)
CONTENT_SECURITY_POLICY = (
    "default-src 'self'; img-src 'self' data:; style-src 'self'; "
    "script-src 'self'; object-src 'none'; base-uri 'none'; form-action 'self'; "
    "frame-ancestors 'none'"
)
_ANNOTATOR_RE = re.compile(r"^[\w .@+\-]{1,64}$")
_MAX_ID = 2**63 - 1
_COUNTS_TTL_S = 10.0
_LOOPBACK_NAMES = {"localhost", "127.0.0.1", "::1", "[::1]"}
_FILTER_PARAMS = ("label", "attack", "source", "harm")
_GRID_PARAMS = frozenset(_FILTER_PARAMS + ("after", "before", "size"))


def create_app(
    store: Store,
    *,
    secret_key: bytes | str | None = None,
    allow_remote: bool = False,
    image_cache_bytes: int = 64 * 2**20,
) -> Flask:
    """The viewer app over an open `store`. `secret_key` signs the session cookie (random per process if
    None, so sessions end with the server); `allow_remote` lifts the loopback-only Host check."""
    app = Flask(__name__)
    app.config.update(
        SECRET_KEY=secret_key or secrets.token_bytes(32),
        SESSION_COOKIE_SAMESITE="Strict",
        SESSION_COOKIE_HTTPONLY=True,
        MAX_CONTENT_LENGTH=64 * 1024,
    )
    app.json.sort_keys = False
    app.extensions["vinadv"] = state = _ViewerState(store, image_cache_bytes)
    app.jinja_env.globals.update(
        PALETTE=PALETTE,
        LABELS=LABELS,
        HUMAN_LABELS=HUMAN_LABELS,
        LABEL_KEYS=LABEL_KEYS,
        HARMS=HARMS,
        fmt_score=_fmt_score,
        fmt_dist=_fmt_dist,
        fmt_cost=_fmt_cost,
        csrf_token=_csrf_token,
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

    # ------------------------------------------------------------------------------------------ pages

    @app.get("/")
    def runs_page():
        _only_params(set())
        return render_template("runs.html", runs=state.runs_summary())

    @app.get("/pairs")
    def pairs_redirect():
        _only_params(_GRID_PARAMS | {"run"})
        run_id = _int_param("run", required=True)
        state.require_run(run_id)
        query = {k: v for k, v in request.args.items() if k != "run" and v != ""}
        return redirect(url_for("pairs_page", run_id=run_id) + (f"?{urlencode(query)}" if query else ""), 303)

    @app.get("/runs/<int:run_id>/pairs")
    def pairs_page(run_id: int):
        run = state.require_run(run_id)
        grid = state.grid(run_id)
        return render_template("pairs.html", run=run, runs=state.runs_summary(), **grid)

    @app.get("/pairs/<int:run_id>/<int:pair_index>")
    def pair_page(run_id: int, pair_index: int):
        _only_params(set(_FILTER_PARAMS))
        run = state.require_run(run_id)
        filters = _filters()
        pair = state.pair_json(run_id, pair_index)
        nav = state.neighbours(run_id, pair_index, filters)
        return render_template(
            "pair.html",
            run=run,
            pair=pair,
            filters=filters,
            nav=nav,
            filter_query=_filter_query(filters),
            annotator=_annotator_from_cookie(),
        )

    @app.post("/pairs/<int:run_id>/<int:pair_index>/label")
    def label_pair(run_id: int, pair_index: int):
        _check_csrf()
        _only_params(set(_FILTER_PARAMS))
        state.require_run(run_id)
        state.require_pair(run_id, pair_index)
        if state.store.readonly:
            abort(403, description=f"database {state.store.url} is opened read-only: labels cannot be stored")
        for name in request.form:
            if name not in ("csrf_token", "label", "annotator"):
                raise BadRequest(f"unknown form field {name!r}")
            if len(request.form.getlist(name)) > 1:  # which one was meant? (the first would be taken silently)
                raise BadRequest(f"form field {name!r} given more than once")
        label = request.form.get("label", "")
        if label not in HUMAN_LABELS:
            raise BadRequest(f"label: {label!r} is not one of {'|'.join(HUMAN_LABELS)}")
        annotator = _valid_annotator(request.form.get("annotator", DEFAULT_ANNOTATOR))
        state.store.add_annotations(run_id, [pair_index], [label], annotator)
        filters = _filters()
        nav = state.neighbours(run_id, pair_index, filters)
        flash(f"pair {pair_index} labelled {label} by {annotator}")
        target = nav["next"] if nav["next"] is not None else pair_index
        response = redirect(url_for("pair_page", run_id=run_id, pair_index=target) + _filter_query(filters), 303)
        response.set_cookie(ANNOTATOR_COOKIE, annotator, max_age=365 * 86400, samesite="Strict", httponly=True)
        return response

    @app.get("/img/<int:run_id>/<int:pair_index>/<kind>.png")
    def pair_image(run_id: int, pair_index: int, kind: str):
        _only_params(set())
        if kind not in KINDS:
            abort(404, description=f"no image kind {kind!r}; kinds: {', '.join(KINDS)}")
        png, etag = state.image(run_id, pair_index, kind)
        if etag in request.if_none_match:
            response = Response(status=304)
        else:
            response = Response(png, mimetype="image/png")
        response.set_etag(etag)
        # stored pairs never change; revalidate after 10 minutes in case the database is swapped under us
        response.headers["Cache-Control"] = "private, max-age=600"
        return response

    # ------------------------------------------------------------------------------------------- JSON

    @app.get("/api/runs")
    def api_runs():
        _only_params(set())
        return jsonify(runs=[_run_json(r) for r in state.runs_summary()])

    @app.get("/api/runs/<int:run_id>/pairs")
    def api_pairs(run_id: int):
        state.require_run(run_id)
        grid = state.grid(run_id)
        return jsonify(
            run_id=run_id,
            filters=grid["filters"],
            size=grid["size"],
            pairs=grid["pairs"],
            next_after=grid["next_after"],
            prev_before=grid["prev_before"],
        )

    @app.get("/api/pairs/<int:run_id>/<int:pair_index>")
    def api_pair(run_id: int, pair_index: int):
        _only_params(set())
        state.require_run(run_id)
        return jsonify(state.pair_json(run_id, pair_index))

    return app


# ------------------------------------------------------------------------------------------------ state


class _ViewerState:
    """What the app shares between requests: the store, the image cache, a small row cache and cached counts."""

    def __init__(self, store: Store, image_cache_bytes: int) -> None:
        self.store = store
        self.images = PngCache(image_cache_bytes)
        self._rows: OrderedDict = OrderedDict()
        self._rows_lock = threading.Lock()
        self._counts: tuple[float, dict] | None = None
        self._sources: dict[int, tuple[float, list[str]]] = {}

    # counts change only when a pipeline writes pairs, and a count of 1,000,000 rows costs ~0.1 s: keep it briefly
    def counts(self) -> dict[int, dict[str, int]]:
        now = time.monotonic()
        if self._counts is None or now - self._counts[0] > _COUNTS_TTL_S:
            self._counts = (now, self.store.label_counts_by_run())
        return self._counts[1]

    def sources(self, run_id: int) -> list[str]:
        now = time.monotonic()
        cached = self._sources.get(run_id)
        if cached is None or now - cached[0] > _COUNTS_TTL_S:
            cached = self._sources[run_id] = (now, self.store.label_sources(run_id))
        return cached[1]

    def runs_summary(self) -> list[dict]:
        counts = self.counts()
        out = []
        for run in self.store.list_runs(with_counts=False):
            c = counts.get(int(run["id"]), {lab: 0 for lab in LABELS})
            n = sum(c.values())
            valid = n - c["invalid"]
            successes = sum(c[lab] for lab in SUCCESS_LABELS)
            out.append(
                {
                    **run,
                    "planner": run_planner(run),
                    "counts": c,
                    "n_pairs": n,
                    "n_valid": valid,
                    "n_success": successes,
                    "success_rate": successes / valid if valid else None,
                }
            )
        return out

    def require_run(self, run_id: int) -> dict:
        if run_id > _MAX_ID:
            abort(404, description=f"no run {run_id}")
        try:
            return self.store.run_info(run_id)
        except InputError:
            abort(404, description=f"no run {run_id} in this database")

    def require_pair(self, run_id: int, pair_index: int) -> PairRecords:
        if pair_index > _MAX_ID or run_id > _MAX_ID:
            abort(404, description=f"no pair {pair_index} in run {run_id}")
        key = (run_id, pair_index)
        with self._rows_lock:
            row = self._rows.get(key)
            if row is not None:
                self._rows.move_to_end(key)
                return row
        row = self.store.read_pairs(run_id, pair_indices=np.array([pair_index]))
        if len(row) == 0:
            abort(404, description=f"no pair {pair_index} in run {run_id}")
        with self._rows_lock:
            self._rows[key] = row
            while len(self._rows) > 256:
                self._rows.popitem(last=False)
        return row

    def image(self, run_id: int, pair_index: int, kind: str) -> tuple[bytes, str]:
        key = (run_id, pair_index, kind)
        cached = self.images.get(key)
        if cached is not None:
            return cached
        row = self.require_pair(run_id, pair_index)
        png = render_pair_png(row, 0, kind)
        entry = (png, hashlib.sha256(png).hexdigest()[:20])
        self.images.put(key, entry)
        return entry

    def grid(self, run_id: int) -> dict:
        """The page of the grid the query string asks for (validated here)."""
        _only_params(set(_GRID_PARAMS))
        filters = _filters()
        after, before = _int_param("after"), _int_param("before")
        if after is not None and before is not None:
            raise BadRequest("give at most one of 'after' and 'before'")
        size = _int_param("size", default=DEFAULT_PAGE_SIZE)
        if not 1 <= size <= MAX_PAGE_SIZE:
            raise BadRequest(f"size: must be 1 to {MAX_PAGE_SIZE}, got {size}")
        kw = dict(
            label=filters["label"], attack=filters["attack"], label_source=filters["source"], harm=filters["harm"]
        )
        rows = self.store.page_pairs(run_id, after=after, before=before, limit=size + 1, **kw)
        if before is not None:
            has_prev = len(rows) > size
            rows = rows[-size:]
            has_next = bool(rows) and bool(self.store.page_pairs(run_id, after=rows[-1]["pair_index"], limit=1, **kw))
        else:
            has_next = len(rows) > size
            rows = rows[:size]
            has_prev = (
                bool(rows)
                and after is not None
                and bool(self.store.page_pairs(run_id, before=rows[0]["pair_index"], limit=1, **kw))
            )
        humans = self.human_labels(run_id, [r["pair_index"] for r in rows])
        pairs = [_pair_row_json(r, humans.get(r["pair_index"], [])) for r in rows]
        return {
            "filters": filters,
            "size": size,
            "pairs": pairs,
            "next_after": rows[-1]["pair_index"] if has_next else None,
            "prev_before": rows[0]["pair_index"] if has_prev else None,
            "filter_query": _filter_query(filters),
            "page_query": _page_query(filters, size),
            "sources": self.sources(run_id),
        }

    def neighbours(self, run_id: int, pair_index: int, filters: dict) -> dict:
        kw = dict(
            label=filters["label"], attack=filters["attack"], label_source=filters["source"], harm=filters["harm"]
        )
        nxt = self.store.page_pairs(run_id, after=pair_index, limit=1, **kw)
        prv = self.store.page_pairs(run_id, before=pair_index, limit=1, **kw)
        return {"next": nxt[0]["pair_index"] if nxt else None, "prev": prv[0]["pair_index"] if prv else None}

    def human_labels(self, run_id: int, pair_indices: list[int]) -> dict[int, list[dict]]:
        out: dict[int, list[dict]] = {}
        if not pair_indices:
            return out
        for a in self.store.read_annotations(run_id, pair_indices=pair_indices):
            out.setdefault(int(a["pair_index"]), []).append(
                {"label": a["label"], "annotator": a["annotator"], "created": a["created"].isoformat() + "Z"}
            )
        return out

    def pair_json(self, run_id: int, pair_index: int) -> dict:
        r = self.require_pair(run_id, pair_index)
        o, a = r.path_o[0], r.path_a[0]
        return {
            "run_id": run_id,
            "pair_index": pair_index,
            "no": int(r.no[0]),
            "size": r.size,
            "label": r.label[0],
            "attack": bool(r.attack[0]),
            "label_source": r.label_source[0],
            "score": _none_if_nan(r.score[0]),
            "dh": _none_if_negative(r.dh[0]),
            "dv": _none_if_negative(r.dv[0]),
            "term_o": r.term_o[0],
            "term_a": r.term_a[0],
            **{name: _none_if_nan(float(getattr(r, name)[0])) for name in HARM_FLOAT_FIELDS},
            "expert_label": r.expert_label[0],
            "harm": r.harm[0],
            "moves": self.store.run_moves(run_id),  # the run's movement model: what the costs count
            "start": r.starts[0].tolist(),
            "goal": r.goals[0].tolist(),
            "added": r.added[0, 0].tolist(),
            "added_cells": r.added[0].tolist(),  # every added obstacle, in the order added (`added`: the first)
            "edit": str(r.edit[0]),  # add | remove: `added` are then the freed cells
            "path_o": o.tolist(),
            "path_a": a.tolist(),
            "map_o": ["".join("1" if v else "0" for v in row) for row in r.obstacles_o[0]],
            "map_a": ["".join("1" if v else "0" for v in row) for row in r.obstacles_a[0]],
            "human_labels": self.human_labels(run_id, [pair_index]).get(pair_index, []),
            "images": {k: url_for("pair_image", run_id=run_id, pair_index=pair_index, kind=k) for k in KINDS},
        }


# ------------------------------------------------------------------------------------ request helpers


def _only_params(allowed: set) -> None:
    unknown = sorted(set(request.args) - set(allowed))
    if unknown:
        raise BadRequest(
            f"unknown query parameter {unknown[0]!r}"
            + (f"; allowed: {', '.join(sorted(allowed))}" if allowed else "; this page takes none")
        )
    for name in request.args:
        if len(request.args.getlist(name)) > 1:
            raise BadRequest(f"query parameter {name!r} given more than once")


def _int_param(name: str, *, default: int | None = None, required: bool = False) -> int | None:
    raw = request.args.get(name)
    if raw is None or raw == "":
        if required:
            raise BadRequest(f"query parameter {name!r} is required")
        return default
    if not raw.isascii() or not raw.isdigit() or len(raw) > 19 or int(raw) > _MAX_ID:
        raise BadRequest(f"{name}: expected a non-negative integer, got {raw[:40]!r}")
    return int(raw)


def _filters() -> dict:
    label = request.args.get("label") or None
    if label is not None and label not in LABELS:
        raise BadRequest(f"label: {label[:40]!r} is not one of {'|'.join(LABELS)}")
    raw_attack = request.args.get("attack") or None
    attack = None
    if raw_attack is not None:
        lowered = raw_attack.lower()
        if lowered in ("1", "true", "yes"):
            attack = True
        elif lowered in ("0", "false", "no"):
            attack = False
        else:
            raise BadRequest(f"attack: expected yes or no, got {raw_attack[:40]!r}")
    source = request.args.get("source") or None
    if source is not None and (len(source) > 255 or not source.isprintable()):
        raise BadRequest("source: expected a label source name of at most 255 printable characters")
    harm = request.args.get("harm") or None
    if harm is not None and harm not in HARMS:
        raise BadRequest(f"harm: {harm[:40]!r} is not one of {'|'.join(HARMS)}")
    return {"label": label, "attack": attack, "source": source, "harm": harm}


def _filter_query(filters: dict) -> str:
    query = _filter_items(filters)
    return f"?{urlencode(query)}" if query else ""


def _page_query(filters: dict, size: int) -> str:
    """Filters and page size as a query string prefix that ends ready for `after=`/`before=`."""
    query = _filter_items(filters)
    if size != DEFAULT_PAGE_SIZE:
        query["size"] = size
    return "?" + (urlencode(query) + "&" if query else "")


def _filter_items(filters: dict) -> dict:
    query = {}
    if filters["label"] is not None:
        query["label"] = filters["label"]
    if filters["attack"] is not None:
        query["attack"] = "yes" if filters["attack"] else "no"
    if filters["source"] is not None:
        query["source"] = filters["source"]
    if filters["harm"] is not None:
        query["harm"] = filters["harm"]
    return query


def _csrf_token() -> str:
    """The session's CSRF token (made on first use)."""
    token = session.get("csrf")
    if not token:
        token = session["csrf"] = secrets.token_urlsafe(32)
    return token


def _check_csrf() -> None:
    origin = request.headers.get("Origin")
    if origin and origin != "null" and urlsplit(origin).netloc != request.host:
        raise Forbidden(f"cross-origin POST from {origin[:80]!r} refused")
    expected = session.get("csrf")
    given = request.form.get("csrf_token", "")
    if not expected or not given or not secrets.compare_digest(str(expected), given):
        raise Forbidden("missing or invalid CSRF token: reload the page and label again")


def _valid_annotator(raw: str) -> str:
    name = (raw or "").strip() or DEFAULT_ANNOTATOR
    if not _ANNOTATOR_RE.match(name):
        raise BadRequest("annotator: 1 to 64 letters, digits, spaces or . @ + - _")
    return name


def _annotator_from_cookie() -> str:
    raw = request.cookies.get(ANNOTATOR_COOKIE, "").strip()
    return raw if _ANNOTATOR_RE.match(raw) else DEFAULT_ANNOTATOR


# ---------------------------------------------------------------------------------------------- JSON


def _none_if_nan(value) -> float | None:
    return None if value is None or (isinstance(value, float) and math.isnan(value)) else float(value)


def _none_if_negative(value) -> int | None:
    return None if value is None or value < 0 else int(value)


def _pair_row_json(row: dict, humans: list[dict]) -> dict:
    return {
        "pair_index": int(row["pair_index"]),
        "label": row["label"],
        "attack": bool(row["attack"]),
        "label_source": row["label_source"],
        "score": _none_if_nan(row["score"]),
        "dh": _none_if_negative(row["dh"]),
        "dv": _none_if_negative(row["dv"]),
        "term_o": row["term_o"],
        "term_a": row["term_a"],
        "human_labels": humans,
        "harm": row["harm"],
        "regret_o": _none_if_nan(row["regret_o"]),
        "regret_a": _none_if_nan(row["regret_a"]),
    }


def run_planner(run: dict) -> str:
    """The planner a run's pairs were planned by (its config's `planner`; `vin` where the config names none)."""
    return (run.get("config") or {}).get("planner") or "vin"


def _run_json(run: dict) -> dict:
    return {
        "id": int(run["id"]),
        "name": run["name"],
        "created": run["created"].isoformat() + "Z",
        "status": run["status"],
        "attack": run["attack"],
        "planner": run["planner"],
        "classifier": run["classifier"],
        "seed": run["seed"],
        "n_pairs": run["n_pairs"],
        "counts": run["counts"],
        "n_valid": run["n_valid"],
        "n_success": run["n_success"],
        "success_rate": run["success_rate"],
    }


def _fmt_score(value) -> str:
    return "—" if value is None else f"{value:.3f}"


def _fmt_cost(value) -> str:
    """`1.414`; float noise around 0 (a regret of -2e-15) as `0.000`, not `-0.000`."""
    return "—" if value is None else f"{round(float(value), 3) + 0.0:.3f}"


def _fmt_dist(value) -> str:
    return "—" if value is None else str(value)


def is_loopback(host: str) -> bool:
    """Whether `host` (a name or an address) is a loopback address the server may bind without --allow-remote."""
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


__all__ = ["HUMAN_LABELS", "LABEL_KEYS", "create_app", "is_loopback"]
