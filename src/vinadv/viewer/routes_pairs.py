"""The runs, the pair grid, a pair's page and its labelling, the pair images and thumbnails, and their JSON."""

from __future__ import annotations

from urllib.parse import urlencode

from flask import Flask, Response, abort, flash, jsonify, redirect, render_template, request, url_for
from werkzeug.exceptions import BadRequest

from vinadv.viewer import params
from vinadv.viewer.formats import run_json
from vinadv.viewer.render import KINDS
from vinadv.viewer.state import ViewerState

#: labels a person can set (the automatic 'invalid' is a fact about the original path, not a judgement)
HUMAN_LABELS = ("FP", "DP", "UrP", "UcP")
#: keyboard shortcut of each human label
LABEL_KEYS = {"FP": "f", "DP": "d", "UrP": "u", "UcP": "c"}


def _png(png: bytes, etag: str) -> Response:
    response = Response(status=304) if etag in request.if_none_match else Response(png, mimetype="image/png")
    response.set_etag(etag)
    # stored pairs never change; revalidate after 10 minutes in case the database is swapped under us
    response.headers["Cache-Control"] = "private, max-age=600"
    return response


def register(app: Flask, state: ViewerState) -> None:
    """Add the routes of runs and pairs to `app`."""

    @app.get("/")
    def runs_page():
        params.only_params(set())
        return render_template("runs.html", runs=state.runs_summary())

    @app.get("/pairs")
    def pairs_redirect():
        params.only_params(params.GRID_PARAMS | {"run"})
        run_id = params.int_param("run", required=True)
        state.require_run(run_id)
        query = {k: v for k, v in request.args.items() if k != "run" and v != "" and not (k == "sort" and v == "pair")}
        return redirect(url_for("pairs_page", run_id=run_id) + (f"?{urlencode(query)}" if query else ""), 303)

    @app.get("/runs/<int:run_id>/pairs")
    def pairs_page(run_id: int):
        run = state.require_run(run_id)
        grid = state.grid(run_id)
        # the page's thumbnails in one batch now, so that its image requests are all served from the cache
        state.prefetch_thumbnails(run_id, [p["pair_index"] for p in grid["pairs"]])
        return render_template("pairs.html", run=run, runs=state.runs_summary(), **grid)

    @app.get("/pairs/<int:run_id>/<int:pair_index>")
    def pair_page(run_id: int, pair_index: int):
        params.only_params(set(params.FILTER_PARAMS))
        run = state.require_run(run_id)
        f = params.filters(state.sorts(run_id))
        pair = state.pair_json(run_id, pair_index)
        nav = state.neighbours(run_id, pair_index, f)
        return render_template(
            "pair.html",
            run=run,
            pair=pair,
            filters=f,
            nav=nav,
            filter_query=params.filter_query(f),
            annotator=params.annotator_from_cookie(),
        )

    @app.post("/pairs/<int:run_id>/<int:pair_index>/label")
    def label_pair(run_id: int, pair_index: int):
        params.check_csrf()
        params.only_params(set(params.FILTER_PARAMS))
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
        annotator = params.valid_annotator(request.form.get("annotator", params.DEFAULT_ANNOTATOR))
        state.store.add_annotations(run_id, [pair_index], [label], annotator)
        f = params.filters(state.sorts(run_id))
        nav = state.neighbours(run_id, pair_index, f)
        flash(f"pair {pair_index} labelled {label} by {annotator}")
        target = nav["next"] if nav["next"] is not None else pair_index
        response = redirect(url_for("pair_page", run_id=run_id, pair_index=target) + params.filter_query(f), 303)
        response.set_cookie(params.ANNOTATOR_COOKIE, annotator, max_age=365 * 86400, samesite="Strict", httponly=True)
        return response

    @app.get("/img/<int:run_id>/<int:pair_index>/<kind>.png")
    def pair_image(run_id: int, pair_index: int, kind: str):
        params.only_params(set())
        if kind not in KINDS:
            abort(404, description=f"no image kind {kind!r}; kinds: {', '.join(KINDS)}")
        return _png(*state.image(run_id, pair_index, kind))

    @app.get("/thumb/<int:run_id>/<int:pair_index>.png")
    def pair_thumbnail(run_id: int, pair_index: int):
        params.only_params(set())
        return _png(*state.thumbnail(run_id, pair_index))

    # ------------------------------------------------------------------------------------------- JSON

    @app.get("/api/runs")
    def api_runs():
        params.only_params(set())
        return jsonify(runs=[run_json(r) for r in state.runs_summary()])

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
        params.only_params(set())
        state.require_run(run_id)
        return jsonify(state.pair_json(run_id, pair_index))
