"""The robustness results of the database (`vinadv robustness`) and the bench leaderboard of a folder of entries
(`vinadv serve --bench DIR`), as pages and JSON."""

from __future__ import annotations

from flask import Flask, abort, jsonify, render_template

from vinadv.intervals import figure_intervals, interval_fields
from vinadv.viewer import params
from vinadv.viewer.state import ViewerState


def robustness_rows(stored: list[dict]) -> list[dict]:
    """The worst case over the strategies of each stored benchmark (`Store.read_robustness`), one dict per benchmark:
    what was measured (planner, weights, maps, objective, strategies, edit) and its figures by k, each rate with its
    Wilson 95% interval computed from the counts (a result stored before intervals has them too)."""
    out = []
    for row in stored:
        settings, result = row.get("settings") or {}, row.get("result") or {}
        clean = result.get("clean") or {}
        out.append(
            {
                "id": row.get("id"),
                "created": row.get("created"),
                "planner": settings.get("planner") or row.get("planner"),  # the full spec where stored
                "name": settings.get("name"),
                "weights": row.get("weights_checksum"),
                "maps": settings.get("maps"),
                "n": settings.get("n"),
                "size": settings.get("size"),
                "maps_seed": settings.get("maps_seed"),
                "objective": settings.get("objective"),
                "edit": settings.get("edit") or "add",
                "strategies": list(settings.get("strategies") or []),
                "clean_success": clean.get("success_rate"),
                **interval_fields("clean_success", clean.get("reached"), clean.get("maps")),
                "worst": [{**f, **figure_intervals(f)} for f in result.get("overall") or []],
            }
        )
    return out


def bench_table(folder) -> tuple[dict[str, list[dict]], list[str]]:
    """({suite: leaderboard rows}, one line per file that is not a valid entry) of the entries in `folder`
    (`vinadv.bench.leaderboard`)."""
    from vinadv.bench.leaderboard import read_entries_checked, rows  # noqa: PLC0415 (the registry: only to render)

    entries, problems = read_entries_checked(folder)
    return rows(entries), problems


def register(app: Flask, state: ViewerState) -> None:
    """Add the robustness and bench routes to `app`."""

    @app.get("/robustness")
    def robustness_page():
        params.only_params(set())
        return render_template("robustness.html", benchmarks=robustness_rows(state.store.read_robustness()))

    @app.get("/api/robustness")
    def api_robustness():
        params.only_params(set())
        benchmarks = robustness_rows(state.store.read_robustness())
        for b in benchmarks:
            b["created"] = None if b["created"] is None else b["created"].isoformat() + "Z"
        return jsonify(benchmarks=benchmarks)

    def _bench():
        if state.bench_dir is None:
            abort(404, description="no bench results: start the viewer with --bench DIR (a folder of entries)")
        return bench_table(state.bench_dir)

    @app.get("/bench")
    def bench_page():
        params.only_params(set())
        table, problems = _bench()
        return render_template("bench.html", table=table, problems=problems, folder=str(state.bench_dir))

    @app.get("/api/bench")
    def api_bench():
        params.only_params(set())
        table, problems = _bench()
        return jsonify(suites=table, problems=problems)
