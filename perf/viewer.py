"""Viewer speed on a large run: pair grid pages, the runs list, pair pages and images, through the Flask app.

    .venv/bin/python perf/viewer.py [--n 1000000] [--size 28] [--db /tmp/vinadv-viewer-bench.db] [--rounds 5] [--json]

Builds (once; reused while --n and --size match) a SQLite database with one run of `--n` random pairs
(`vinadv.testing.store.random_records`, maps and paths included), then times whole requests of the Flask test
client (query + template + response), best of --rounds, side by side in one run:
- grid pages: first page, and a page deep in the run (after 90% of the pairs), unfiltered and filtered by label,
  attack, label source and label + source, with the viewer's keyset paging (`after=`) and, for the ratio, the same
  page fetched by LIMIT/OFFSET (what a naive pager does);
- the runs list (label counts of every pair: uncached, then from the viewer's 10 s cache);
- grid pages sorted by label, harm and regret added (first and at 90%: each reads and sorts the run's pairs);
- the grid page with its thumbnails drawn (one batch) and cached, and one cached thumbnail;
- a pair page, and its three PNG images rendered cold and then served from the LRU cache.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import sqlalchemy as sa

from common import add_output_arguments  # perf/common.py
from vinadv.store import Store
from vinadv.store.schema import map_pairs
from vinadv.testing.store import random_records
from vinadv.viewer.app import create_app

CHUNK = 50_000


def build(path: Path, n: int, size: int) -> int:
    """A database at `path` holding one run 'bench-<n>-<size>' of n pairs; reused if it is already there."""
    name = f"bench-{n}-{size}"
    url = f"sqlite:///{path}"
    if path.exists():
        with Store.open(url, create=False) as store:
            run_id = store.find_run(name)
            if run_id is not None and store.count_pairs(run_id) == n:
                return run_id
        path.unlink()
        for extra in ("-wal", "-shm"):
            Path(str(path) + extra).unlink(missing_ok=True)
    start = time.perf_counter()
    with Store.open(url) as store:
        run_id = store.create_run(name, attack="random")
        for lo in range(0, n, CHUNK):
            records = random_records(min(CHUNK, n - lo), size=size, seed=lo, max_path=2 * size, first_index=lo)
            store.write_pairs(run_id, records, skip_stored=False)
            print(f"  wrote {lo + len(records):,} / {n:,} pairs", flush=True)
        store.finish_run(run_id, {})
    print(f"built {path} in {time.perf_counter() - start:.0f} s ({path.stat().st_size / 2**30:.2f} GiB)")
    return run_id


def best_ms(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return 1000 * best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--size", type=int, default=28)
    parser.add_argument("--db", default="/tmp/vinadv-viewer-bench.db")
    add_output_arguments(parser, rounds=5)
    args = parser.parse_args()

    run_id = build(Path(args.db), args.n, args.size)
    store = Store.open(f"sqlite:///{args.db}", create=False)
    store.ensure_indexes()
    app = create_app(store)
    client = app.test_client()
    state = app.extensions["vinadv"]

    def get(url: str) -> None:
        response = client.get(url)
        assert response.status_code == 200, (url, response.status_code, response.data[:300])

    def offset_page(filters: dict, offset: int) -> None:
        # the same page as the grid shows, fetched the naive way: ORDER BY pair_index LIMIT 51 OFFSET k
        c = map_pairs.c
        query = sa.select(
            c.pair_index, c.label, c.attack, c.label_source, c.score, c.dh, c.dv, c.term_o, c.term_a, c.added_obstacle
        ).where(c.run_id == run_id)
        for key, value in filters.items():
            query = query.where(c[key] == value)
        with store.engine.connect() as conn:
            conn.execute(query.order_by(c.pair_index).limit(51).offset(offset)).all()

    results: dict = {"n": args.n, "size": args.size, "grid": {}}
    cases = [
        ("all", "", {}),
        ("label=FP", "label=FP", {"label": "FP"}),
        ("attack=yes", "attack=yes", {"attack": True}),
        ("source=svm", "source=svm", {"label_source": "svm"}),
        ("label=UrP&source=rule", "label=UrP&source=rule", {"label": "UrP", "label_source": "rule"}),
    ]
    for name, query, filters in cases:
        # the pair index at 90% of this filter's pairs, and its position, for the deep page
        pages = store.page_pairs(run_id, limit=1, **filters)
        with store.engine.connect() as conn:
            c = map_pairs.c
            matching = sa.select(c.pair_index).where(c.run_id == run_id)
            for key, value in filters.items():
                matching = matching.where(c[key] == value)
            total = conn.execute(sa.select(sa.func.count()).select_from(matching.subquery())).scalar_one()
            deep_offset = int(total * 0.9)
            deep_after = conn.execute(matching.order_by(c.pair_index).limit(1).offset(deep_offset - 1)).scalar_one()
        assert pages
        sep = "&" if query else ""
        first = best_ms(lambda: get(f"/runs/{run_id}/pairs?{query}"), args.rounds)
        deep = best_ms(lambda: get(f"/runs/{run_id}/pairs?{query}{sep}after={deep_after}"), args.rounds)
        api = best_ms(lambda: get(f"/api/runs/{run_id}/pairs?{query}{sep}after={deep_after}"), args.rounds)
        naive = best_ms(lambda: offset_page(filters, deep_offset), max(1, args.rounds // 2))
        keyset = best_ms(lambda: store.page_pairs(run_id, after=deep_after, limit=51, **filters), args.rounds)
        results["grid"][name] = {
            "matching": int(total),
            "first_page_ms": first,
            "deep_page_ms": deep,
            "deep_api_ms": api,
            "deep_query_keyset_ms": keyset,
            "deep_query_offset_ms": naive,
            "offset_over_keyset": naive / keyset,
        }

    # sorted grids: every page reads and sorts the run's pairs (no index serves the key): first and deep page (JSON)
    results["sorted"] = {}
    for sort in ("label", "harm", "regret"):
        rows = store.page_pairs(run_id, sort=sort, limit=int(args.n * 0.9))
        deep_after = rows[-1]["pair_index"]
        results["sorted"][sort] = {
            "first_page_ms": best_ms(lambda: get(f"/api/runs/{run_id}/pairs?sort={sort}"), args.rounds),
            "deep_page_ms": best_ms(
                lambda: get(f"/api/runs/{run_id}/pairs?sort={sort}&after={deep_after}"), args.rounds
            ),
        }
    # the grid page with its 50 thumbnails drawn in one batch (the cache emptied each time), and once they are cached
    deep = args.n // 3

    def cold_grid() -> None:
        state.images = type(state.images)(state.images.max_bytes)
        get(f"/runs/{run_id}/pairs?after={deep}")

    results["grid_thumbnails_cold_ms"] = best_ms(cold_grid, args.rounds)
    results["grid_thumbnails_cached_ms"] = best_ms(lambda: get(f"/runs/{run_id}/pairs?after={deep}"), args.rounds)
    results["thumbnail_cached_ms"] = best_ms(lambda: get(f"/thumb/{run_id}/{deep + 1}.png"), args.rounds)

    state._counts = None
    results["runs_list_uncached_ms"] = best_ms(lambda: (setattr(state, "_counts", None), get("/")), 2)
    results["runs_list_cached_ms"] = best_ms(lambda: get("/"), args.rounds)
    pair = args.n // 2
    state._rows.clear()
    start = time.perf_counter()
    get(f"/pairs/{run_id}/{pair}")
    results["pair_page_cold_ms"] = 1000 * (time.perf_counter() - start)
    results["pair_page_ms"] = best_ms(lambda: get(f"/pairs/{run_id}/{pair}"), args.rounds)
    images = {}
    for kind in ("original", "adversarial", "pathimage"):
        # the first pair image ever also pays for imports (matplotlib; torch behind vinadv.classify): warm up
        get(f"/img/{run_id}/{pair + 1}/{kind}.png")
        start = time.perf_counter()
        get(f"/img/{run_id}/{pair}/{kind}.png")
        cold = 1000 * (time.perf_counter() - start)
        cached = best_ms(lambda: get(f"/img/{run_id}/{pair}/{kind}.png"), args.rounds)
        images[kind] = {"cold_ms": cold, "cached_ms": cached, "cold_over_cached": cold / cached}
    results["images"] = images
    store.close()

    if args.json:
        print(json.dumps(results, indent=1))
        return
    print(
        f"viewer on one run of {args.n:,} pairs ({args.size}x{args.size}), SQLite, Flask test client, best of "
        f"{args.rounds}"
    )
    print(
        f"{'grid filter':<24}{'matching':>10}{'first page':>12}{'page @90%':>11}{'API @90%':>10}"
        f"{'query keyset':>14}{'query OFFSET':>14}{'OFFSET/keyset':>15}"
    )
    for name, g in results["grid"].items():
        print(
            f"{name:<24}{g['matching']:>10,}{g['first_page_ms']:>10.1f}ms{g['deep_page_ms']:>9.1f}ms"
            f"{g['deep_api_ms']:>8.1f}ms{g['deep_query_keyset_ms']:>12.2f}ms{g['deep_query_offset_ms']:>12.1f}ms"
            f"{g['offset_over_keyset']:>14.0f}x"
        )
    for sort, g in results["sorted"].items():
        print(f"grid sorted by {sort:<8} first page {g['first_page_ms']:.1f} ms, page @90% {g['deep_page_ms']:.1f} ms")
    cold, cached = results["grid_thumbnails_cold_ms"], results["grid_thumbnails_cached_ms"]
    print(
        f"grid page with 50 thumbnails: {cold:.1f} ms drawing them, {cached:.1f} ms cached ({cold / cached:.1f}x); "
        f"a cached thumbnail {results['thumbnail_cached_ms']:.2f} ms"
    )
    print(
        f"runs list: {results['runs_list_uncached_ms']:.0f} ms counting every pair, "
        f"{results['runs_list_cached_ms']:.1f} ms from the cache"
    )
    print(f"pair page: {results['pair_page_cold_ms']:.1f} ms first, {results['pair_page_ms']:.1f} ms again")
    for kind, im in images.items():
        print(
            f"image {kind:<12} {im['cold_ms']:.1f} ms rendered, {im['cached_ms']:.2f} ms cached "
            f"({im['cold_over_cached']:.0f}x)"
        )


if __name__ == "__main__":
    main()
