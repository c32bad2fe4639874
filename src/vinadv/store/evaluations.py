"""Benchmark results kept in a `Store`: classifier evaluations of a run (`evaluations`), the evaluation stage's
other measurements of a run (`measurements`: planner quality, processing time) and robustness benchmarks of planners
(`robustness`). `evaluations` and `robustness` are additive: created on first write; every one of the three reads as
empty where missing (`measurements` in an older database opened read-only)."""

from __future__ import annotations

import json
from collections.abc import Sequence

import sqlalchemy as sa
from sqlalchemy import exc as sa_exc

from vinadv import __version__
from vinadv.errors import InputError, one_line
from vinadv.records import BENCH_CHUNK, ROBUSTNESS, ROBUSTNESS_SETTINGS, upgrade
from vinadv.store.connection import utcnow
from vinadv.store.runs import RunQueries
from vinadv.store.schema import bench_chunks, evaluations, measurements, robustness
from vinadv.vocabulary import MEASUREMENTS


class EvaluationQueries(RunQueries):
    """Add and read evaluations and robustness benchmarks (a part of `Store`; an evaluation needs its run)."""

    def add_evaluations(self, run_id: int, rows: Sequence[dict]) -> int:
        """Store classifier evaluations of a run (`vinadv evaluate`), all in one transaction; return how many.

        Each row: classifier, setting, training ('balanced'|'imbalanced'), train_fraction, train_size,
        test_size, seed, metrics (JSON dict), curves (JSON dict or None), batch (id shared by one call).
        """
        self.run_info(run_id)  # InputError for an unknown run
        if not rows:
            return 0
        self.ensure_table(evaluations)
        now = utcnow()
        keys = (
            "batch",
            "classifier",
            "setting",
            "training",
            "train_fraction",
            "train_size",
            "test_size",
            "seed",
            "metrics",
            "curves",
        )
        values = [{"run_id": int(run_id), "created": now, **{k: row.get(k) for k in keys}} for row in rows]
        with self.engine.begin() as conn:
            conn.execute(evaluations.insert(), values)
        return len(values)

    def read_evaluations(self, run_id: int) -> list[dict]:
        """The run's stored evaluations, oldest first (`[]` when none, or when the table does not exist yet)."""
        with self.engine.connect() as conn:
            if not sa.inspect(conn).has_table(evaluations.name):
                return []
            rows = (
                conn.execute(
                    sa.select(evaluations).where(evaluations.c.run_id == int(run_id)).order_by(evaluations.c.id)
                )
                .mappings()
                .all()
            )
        return [dict(r) for r in rows]

    def add_measurement(self, run_id: int, kind: str, result: dict, version: str = __version__) -> int:
        """Store what the evaluation stage measured of a run: `kind` one of `vinadv.vocabulary.MEASUREMENTS`,
        `result` a JSON dict; return its row id. The newest of a run and kind is the one `read_measurement` gives."""
        if kind not in MEASUREMENTS:
            raise InputError(f"kind: {kind!r} not in {', '.join(MEASUREMENTS)}", "kind")
        self.run_info(run_id)  # InputError for an unknown run
        return self.insert_row(
            measurements, run_id=int(run_id), created=utcnow(), kind=kind, result=result, version=version
        )

    def read_measurement(self, run_id: int, kind: str) -> dict | None:
        """The newest stored `kind` measurement of the run (the `result` dict), None when there is none (or the
        database has no such table)."""
        with self.engine.connect() as conn:
            if not sa.inspect(conn).has_table(measurements.name):
                return None
            return conn.execute(
                sa.select(measurements.c.result)
                .where(measurements.c.run_id == int(run_id), measurements.c.kind == kind)
                .order_by(measurements.c.id.desc())
                .limit(1)
            ).scalar_one_or_none()

    def add_robustness(
        self,
        planner: str,
        weights_checksum: str | None,
        settings: dict,
        result: dict,
        version: str = __version__,
        run_name: str | None = None,
    ) -> int:
        """Store one robustness benchmark (`vinadv robustness`): the planner's full spec (`wastar:w=3`) and weights
        checksum, the benchmark's settings and its figures (`vinadv.robustness.RobustnessResult.to_dict()`), JSON, and
        its run name (`--name`, None: none); return its id."""
        self.refuse_outdated()
        self.ensure_table(robustness)
        return self.insert_row(
            robustness,
            created=utcnow(),
            planner=str(planner),
            weights_checksum=weights_checksum,
            settings=settings,
            result=result,
            version=version,
            run_name=run_name,
        )

    def add_bench_chunk(
        self, entry: str, chunk: int, result: dict, version: str = __version__, check=None
    ) -> dict | None:
        """Store the finished chunk `chunk` of benchmark entry `entry` (`vinadv.bench.scoring`), in one transaction: a
        run killed before it commits leaves nothing of the chunk, one killed after leaves all of it. Returns None, or,
        where the chunk is stored already (another process resuming the same entry stored it first, or a remote
        executor delivered it twice), that stored result as `read_bench_chunks` gives it (`check` as there), leaving
        it as it is: the caller compares the two."""
        self.ensure_table(bench_chunks)
        try:
            with self.engine.begin() as conn:
                conn.execute(
                    bench_chunks.insert().values(
                        created=utcnow(), entry=str(entry), chunk=int(chunk), result=result, version=version
                    )
                )
            return None
        except sa_exc.IntegrityError:  # the unique (entry, chunk): stored first by another writer
            stored = self.read_bench_chunks(entry, check, chunks=[int(chunk)])
            if int(chunk) not in stored:  # another constraint: a bug, raised as it is
                raise
            return stored[int(chunk)]

    def read_bench_chunks(self, entry: str, check=None, chunks: Sequence[int] | None = None) -> dict[int, dict]:
        """The stored chunks of benchmark entry `entry` (those numbered in `chunks`, if given): {chunk: result} (`{}`
        when none, or no table yet). Each result is parsed here from its stored text and read in today's form
        (`vinadv.records`), then `check(chunk, result)` (the bench schema,
        `vinadv.bench.validate`) names its first problem or None: InputError (one line naming the chunk and the
        problem) for a result that is not JSON or that `check` refuses."""
        with self.engine.connect() as conn:
            if not sa.inspect(conn).has_table(bench_chunks.name):
                return {}
            text = sa.cast(bench_chunks.c.result, sa.Text).label("result")  # parsed here: a bad one is one line
            query = sa.select(bench_chunks.c.chunk, text).where(bench_chunks.c.entry == str(entry))
            if chunks is not None:
                query = query.where(bench_chunks.c.chunk.in_([int(c) for c in chunks]))
            stored = [(int(r.chunk), r.result) for r in conn.execute(query)]
        out = {}
        for chunk, raw in stored:
            where = f"stored chunk {chunk} of benchmark entry {str(entry)[:12]}"
            try:
                result = json.loads(raw) if isinstance(raw, (str, bytes)) else raw
            except (ValueError, RecursionError):
                raise InputError(f"{where}: its result is not JSON ({one_line(str(raw)[:40])!r})") from None
            if isinstance(result, dict):
                result = upgrade(BENCH_CHUNK, result)
            problem = None if check is None else check(chunk, result)
            if problem is not None:
                raise InputError(f"{where}: {problem}")
            out[chunk] = result
        return out

    def read_robustness(self, ids: Sequence[int] | None = None) -> list[dict]:
        """The stored robustness benchmarks (of `ids` only, if given), oldest first: dicts of the table's columns, the
        settings and the result in today's form (`vinadv.records`; `[]` when none, or when the table does not exist
        yet)."""
        with self.engine.connect() as conn:
            if not sa.inspect(conn).has_table(robustness.name):
                return []
            columns = [sa.null().label(c.name) if c.name in self.absent_columns else c for c in robustness.columns]
            query = sa.select(*columns).order_by(robustness.c.id)
            if ids is not None:
                query = query.where(robustness.c.id.in_([int(i) for i in ids]))
            rows = [dict(r) for r in conn.execute(query).mappings().all()]
        for row in rows:
            row["settings"] = upgrade(ROBUSTNESS_SETTINGS, row["settings"])
            row["result"] = upgrade(ROBUSTNESS, row["result"])
        return rows
