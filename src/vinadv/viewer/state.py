"""What the viewer shares between requests: the store, the image caches, a small row cache and cached counts."""

from __future__ import annotations

import hashlib
import threading
import time
from collections import OrderedDict

import numpy as np
from flask import abort, url_for
from werkzeug.exceptions import BadRequest

from vinadv.errors import InputError
from vinadv.intervals import rate_interval
from vinadv.store import LABELS, Store
from vinadv.store.codec import decode_paths
from vinadv.store.paging import SORTS
from vinadv.store.records import PairRecords
from vinadv.viewer import params
from vinadv.viewer.formats import none_if_nan, none_if_negative, pair_row_json, run_planner
from vinadv.viewer.render import KINDS, PngCache, render_pair_png, render_thumbnails
from vinadv.vocabulary import HARM_FLOAT_FIELDS, SUCCESS_LABELS

_COUNTS_TTL_S = 10.0


class ViewerState:
    """The store, its caches and the reads of the pages (validated by `params`)."""

    def __init__(self, store: Store, image_cache_bytes: int, bench_dir=None) -> None:
        self.store = store
        self.bench_dir = bench_dir
        self.images = PngCache(image_cache_bytes)
        self._rows: OrderedDict = OrderedDict()
        self._rows_lock = threading.Lock()
        self._counts: tuple[float, dict, dict] | None = None
        self._sources: dict[int, tuple[float, list[str]]] = {}
        self._sorts: dict[int, tuple[float, tuple[str, ...]]] = {}

    # counts change only when a pipeline writes pairs, and a count of 1,000,000 rows costs ~0.1 s: keep it briefly
    def counts(self) -> tuple[dict[int, dict[str, int]], dict[int, dict]]:
        """({run: {label: n}}, {run: {harm: n}}), at most `_COUNTS_TTL_S` old."""
        now = time.monotonic()
        if self._counts is None or now - self._counts[0] > _COUNTS_TTL_S:
            self._counts = (now, self.store.label_counts_by_run(), self.store.harm_counts_by_run())
        return self._counts[1], self._counts[2]

    def sources(self, run_id: int) -> list[str]:
        now = time.monotonic()
        cached = self._sources.get(run_id)
        if cached is None or now - cached[0] > _COUNTS_TTL_S:
            cached = self._sources[run_id] = (now, self.store.label_sources(run_id))
        return cached[1]

    def sorts(self, run_id: int) -> tuple[str, ...]:
        """The grid's sorts for the run: the effort only where its pairs hold expanded cells (cached briefly: for a
        run without them, finding none reads the whole run)."""
        now = time.monotonic()
        cached = self._sorts.get(run_id)
        if cached is None or now - cached[0] > _COUNTS_TTL_S:
            effort = self.store.run_has_expansions(run_id)
            cached = self._sorts[run_id] = (now, tuple(s for s in SORTS if effort or s != "effort"))
        return cached[1]

    def runs_summary(self) -> list[dict]:
        labels, harms = self.counts()
        out = []
        for run in self.store.list_runs(with_counts=False):
            c = labels.get(int(run["id"]), {lab: 0 for lab in LABELS})
            h = harms.get(int(run["id"]), {})
            n = sum(c.values())
            valid = n - c["invalid"]
            successes = sum(c[lab] for lab in SUCCESS_LABELS)
            # the harmful rate as the report's: harmful over the valid pairs with harm computed
            harmful, judged = h.get("harmful", 0), h.get("harmful", 0) + h.get("harmless", 0)
            low, high = rate_interval(harmful, judged)
            out.append(
                {
                    **run,
                    "planner": run_planner(run),
                    "counts": c,
                    "n_pairs": n,
                    "n_valid": valid,
                    "n_success": successes,
                    "success_rate": successes / valid if valid else None,
                    "harm_counts": {"not computed" if k is None else k: v for k, v in h.items()},
                    "harmful_rate": harmful / judged if judged else None,
                    "harmful_rate_low": low,
                    "harmful_rate_high": high,
                }
            )
        return out

    def require_run(self, run_id: int) -> dict:
        if run_id > params.MAX_ID:
            abort(404, description=f"no run {run_id}")
        try:
            return self.store.run_info(run_id)
        except InputError:
            abort(404, description=f"no run {run_id} in this database")

    def require_pair(self, run_id: int, pair_index: int) -> PairRecords:
        if pair_index > params.MAX_ID or run_id > params.MAX_ID:
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

    def expanded(self, run_id: int, pair_index: int) -> tuple[np.ndarray | None, np.ndarray | None]:
        """The cells the planner's search expanded on the original and adversarial map, `(k, 2)` each, or None."""
        texts = self.store.pair_expansions(run_id, [pair_index]).get(pair_index, (None, None))
        out = []
        for text in texts:
            if text is None:
                out.append(None)
            else:
                cells, _ = decode_paths([text])
                out.append(cells.astype(np.int64))
        return out[0], out[1]

    def image(self, run_id: int, pair_index: int, kind: str) -> tuple[bytes, str]:
        key = (run_id, pair_index, kind)
        cached = self.images.get(key)
        if cached is not None:
            return cached
        row = self.require_pair(run_id, pair_index)
        expanded = self.expanded(run_id, pair_index) if kind != "pathimage" else (None, None)
        png = render_pair_png(row, 0, kind, expanded=expanded[0 if kind == "original" else 1])
        entry = (png, hashlib.sha256(png).hexdigest()[:20])
        self.images.put(key, entry)
        return entry

    def thumbnail(self, run_id: int, pair_index: int) -> tuple[bytes, str]:
        """The pair's thumbnail (rendered with those of the grid's page when it was shown: `prefetch_thumbnails`)."""
        cached = self.images.get((run_id, pair_index, "thumbnail"))
        if cached is not None:
            return cached
        if pair_index > params.MAX_ID or run_id > params.MAX_ID:
            abort(404, description=f"no pair {pair_index} in run {run_id}")
        self.prefetch_thumbnails(run_id, [pair_index])
        cached = self.images.get((run_id, pair_index, "thumbnail"))
        if cached is None:
            abort(404, description=f"no pair {pair_index} in run {run_id}")
        return cached

    def prefetch_thumbnails(self, run_id: int, pair_indices: list[int]) -> None:
        """Render the thumbnails of `pair_indices` not cached yet in one batch: one read, one drawing pass."""
        missing = [i for i in pair_indices if (run_id, i, "thumbnail") not in self.images]
        if not missing:
            return
        records = self.store.read_pairs(run_id, pair_indices=np.array(missing))
        stored = self.store.pair_expansions(run_id, missing)
        texts = [stored.get(int(i), (None, None))[1] for i in records.pair_index]
        expanded = decode_paths([t or "" for t in texts]) if any(t is not None for t in texts) else None
        for index, png in zip(records.pair_index.tolist(), render_thumbnails(records, expanded)):
            self.images.put((run_id, index, "thumbnail"), (png, hashlib.sha256(png).hexdigest()[:20]))

    def grid(self, run_id: int) -> dict:
        """The page of the grid the query string asks for (validated here)."""
        params.only_params(params.GRID_PARAMS)
        f = params.filters(self.sorts(run_id))
        after, before = params.int_param("after"), params.int_param("before")
        if after is not None and before is not None:
            raise BadRequest("give at most one of 'after' and 'before'")
        size = params.int_param("size", default=params.DEFAULT_PAGE_SIZE)
        if not 1 <= size <= params.MAX_PAGE_SIZE:
            raise BadRequest(f"size: must be 1 to {params.MAX_PAGE_SIZE}, got {size}")
        kw = params.store_filters(f)
        try:
            rows = self.store.page_pairs(run_id, after=after, before=before, limit=size + 1, **kw)
        except InputError as exc:  # a cursor pair that is not stored, in a sorted grid
            raise BadRequest(str(exc)) from None
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
        pairs = [pair_row_json(r, humans.get(r["pair_index"], [])) for r in rows]
        return {
            "filters": f,
            "size": size,
            "pairs": pairs,
            "next_after": rows[-1]["pair_index"] if has_next else None,
            "prev_before": rows[0]["pair_index"] if has_prev else None,
            "filter_query": params.filter_query(f),
            "page_query": params.page_query(f, size),
            "sources": self.sources(run_id),
            "sorts": self.sorts(run_id),
        }

    def neighbours(self, run_id: int, pair_index: int, f: dict) -> dict:
        kw = params.store_filters(f)
        try:
            nxt = self.store.page_pairs(run_id, after=pair_index, limit=1, **kw)
            prv = self.store.page_pairs(run_id, before=pair_index, limit=1, **kw)
        except InputError:  # the pair is not stored: the page answers 404 for it
            nxt = prv = []
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
        expanded_o, expanded_a = self.expanded(run_id, pair_index)
        return {
            "run_id": run_id,
            "pair_index": pair_index,
            "no": int(r.no[0]),
            "size": r.size,
            "label": r.label[0],
            "attack": bool(r.attack[0]),
            "label_source": r.label_source[0],
            "score": none_if_nan(r.score[0]),
            "dh": none_if_negative(r.dh[0]),
            "dv": none_if_negative(r.dv[0]),
            "term_o": r.term_o[0],
            "term_a": r.term_a[0],
            **{name: none_if_nan(float(getattr(r, name)[0])) for name in HARM_FLOAT_FIELDS},
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
            # the search's expanded cells (a search planner's pairs, where stored), None where not
            "expanded_o": None if expanded_o is None else expanded_o.tolist(),
            "expanded_a": None if expanded_a is None else expanded_a.tolist(),
            "human_labels": self.human_labels(run_id, [pair_index]).get(pair_index, []),
            "images": {k: url_for("pair_image", run_id=run_id, pair_index=pair_index, kind=k) for k in KINDS},
        }
