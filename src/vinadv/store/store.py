"""`Store`: open a vinadv database by URL, record runs, bulk-write and read identified map pairs.

`Store` is thin: it owns the engine and the URL (`connection.Database`) and takes its queries from one part per
table or job, each in its own module:

- `connection`: URLs (`--db`, env `VINADV_DB`, else `vinadv.db`), engines, the schema check and upgrades; a refused
  database is left byte-identical, a database error becomes a one-line `OutputError` naming it;
- `runs`: runs and their stored shards;
- `pairs`: the identified map pairs, written in all-or-nothing batches that a resumed run never repeats, and read
  back into `PairRecords` (the row codec is `codec`);
- `counts`: pairs counted per label, outcome, termination and harm (the report);
- `paging`: pages of pairs (the viewer);
- `annotations`, `evaluations`: human labels, classifier evaluations and robustness benchmarks.
"""

from __future__ import annotations

from vinadv.store.annotations import AnnotationQueries
from vinadv.store.connection import open_engine, resolve_url
from vinadv.store.counts import CountQueries
from vinadv.store.evaluations import EvaluationQueries
from vinadv.store.paging import PagingQueries
from vinadv.store.pairs import PairQueries
from vinadv.store.runs import RunQueries


# RunQueries last: `EvaluationQueries` builds on it (an evaluation checks its run), so it comes first in the MRO
class Store(PairQueries, CountQueries, PagingQueries, AnnotationQueries, EvaluationQueries, RunQueries):
    """A vinadv database. Use `Store.open(url)`; close with `.close()` or a `with` block.

    `create=True` creates the tables in an empty database; a database that holds other tables with the same
    names, or another schema version, is refused with `InputError` (nothing is changed).
    """

    @classmethod
    def open(cls, url: str | None = None, *, create: bool = True, readonly: bool = False) -> Store:
        """Open (and with `create`, initialise) the database at `url` (see `resolve_url`).

        `readonly`: never write (implies `create=False`); a SQLite file is opened with `mode=ro`, so a file the
        user may only read can still be exported, reported and browsed.
        """
        url = resolve_url(url)
        engine, absent = open_engine(url, create=create, readonly=readonly)
        return cls(engine, url, readonly=readonly, absent_columns=absent)

    def close(self) -> None:
        self.engine.dispose()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
