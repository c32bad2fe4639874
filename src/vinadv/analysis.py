"""Results as DataFrames: `vinadv.open(url)` reads a vinadv database into pandas, `write_parquet` exports a run.

`open(url)` gives a `Results`: `.runs()`, `.pairs(run)` and `.robustness()` return pandas DataFrames,
`.iter_pairs(run, batch_size)` yields a run's pairs a DataFrame at a time (for runs larger than memory),
`.to_parquet(path, run)` exports a run. Nothing is written to the database (it is opened read-only).

A run's pairs have one layout, as an Arrow table (`pairs_table`), in a Parquet file (`write_parquet`,
`vinadv export --format parquet`) and as a DataFrame (`Results.pairs`: the DataFrame `pandas.read_parquet` makes of
the exported file as `read_parquet` reads it). One row per pair, in pair-index order (`pair_schema()`):

- `no` int64, `run_id` int64, `pair_index` int64 (unique in a run);
- `label` string, `attack` bool (success: UrP or FP), `term_o`, `term_a`, `label_source` string;
- `score` float64, `dh`, `dv` int32, the harm costs (`opt_cost_o` ... `regret_a`, move units) float64,
  `expert_label`, `harm` string: null where the database holds NULL (in pandas NaN, or None for the strings);
- `start`, `goal`: a cell, fixed_size_list<int16>[2] (row, col);
- `edit` string: `add` (the pair's cells were obstacles added to the original map) or `remove` (obstacles freed);
- `added`: the edited cells, list<fixed_size_list<int16>[2]> (one cell per added, or freed, obstacle, in order);
- `map_o`, `map_a`: the maps, list<list<bool>>, N rows of N cells (True = obstacle);
- `path_o`, `path_a`: the paths, list<fixed_size_list<int16>[2]>, the (row, col) cells in order (empty: no path).
- the search effort (DESIGN.md "Search effort", `vinadv.classify.effort`; null for a planner that reports no
  expansions): `expanded_o`, `expanded_a`, the cells the planner's search expanded on each map (as the paths);
  `expansions_o`, `expansions_a`, their counts, and `astar_expansions_o`, `astar_expansions_a`, the exact A*'s, int64;
  `effort_ratio`, `astar_effort_ratio`, `relative_effort` float64 and `effort_harmful` bool (null for an invalid
  pair), computed from the counts.

In the DataFrames of `Results` and `read_parquet` the list columns stay Arrow arrays (`pandas.ArrowDtype`: no
conversion, a value is a Python list); `pandas.read_parquet` makes them object columns of NumPy arrays instead (20
times slower to read). Either way `grid(value)` makes a map value an (N, N) bool array, `cells(value)` a cell list
an (L, 2) int16 array.

The Parquet file's metadata holds the run under the key `vinadv` (JSON, `parquet_metadata`): the format
(`PARQUET_FORMAT`), the run's row (id, name, created, config, seed, weights checksum, attack, classifier,
version, status, timings), the map size N and whether only successful attacks were exported.

pyarrow and pandas are imported when first used, so `import vinadv` and the command line stay light.
"""

from __future__ import annotations

import contextlib
import datetime
import itertools
import json
import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from vinadv import __version__
from vinadv.classify.effort import EFFORT_FIELDS, effort_figures
from vinadv.errors import InputError, one_line
from vinadv.intervals import figure_intervals, interval_columns, rate_interval
from vinadv.outfile import atomic_output
from vinadv.robustness import WORST_CASE
from vinadv.store import PairRecords, Store
from vinadv.store.schema import HARM_COLUMNS, HARM_FLOAT_COLUMNS
from vinadv.store.schema import runs as runs_table

if TYPE_CHECKING:
    import pandas as pd
    import pyarrow as pa

#: the layout of an exported Parquet file, in its metadata (`parquet_metadata(path)["format"]`)
PARQUET_FORMAT = "vinadv.pairs.parquet/3"
#: the Parquet file metadata key that holds the run (JSON)
METADATA_KEY = "vinadv"
#: pairs read from the database at a time: one Parquet row group, one DataFrame of `iter_pairs`
DEFAULT_BATCH = 10_000
#: the expansion counts of a run's pairs (the planner's, then the exact A*'s, on each map; null: not reported)
SEARCH_COUNT_COLUMNS = ("expansions_o", "expansions_a", "astar_expansions_o", "astar_expansions_a")
#: the columns of a run's pairs, in order (see the module doc for their types)
PAIR_COLUMNS = (
    "no",
    "run_id",
    "pair_index",
    "label",
    "attack",
    "term_o",
    "term_a",
    "label_source",
    "score",
    "dh",
    "dv",
    *HARM_COLUMNS,
    "start",
    "goal",
    "edit",
    "added",
    "map_o",
    "map_a",
    "path_o",
    "path_a",
    "expanded_o",
    "expanded_a",
    *SEARCH_COUNT_COLUMNS,
    *EFFORT_FIELDS,
)
#: the columns of `Results.robustness()`: the benchmark, then one strategy's figures at k added obstacles; each rate
#: with its Wilson 95% interval (`{rate}_low`, `{rate}_high`, computed from the counts: `vinadv.intervals`)
ROBUSTNESS_COLUMNS = (
    "benchmark",
    "name",
    "created",
    "version",
    "planner",
    "weights_checksum",
    "maps_file",
    "maps_sha256",
    "size",
    "maps_seed",
    "objective",
    *interval_columns("clean_success"),
    *interval_columns("clean_regret"),
    "strategy",
    "k",
    "maps",
    "attacked",
    "valid",
    "broken",
    *interval_columns("paper_success_rate"),
    "harmful",
    *interval_columns("harmful_rate"),
    "reached",
    *interval_columns("mean_regret"),
    "effort_harmful",
    *interval_columns("effort_harmful_rate"),
    "seconds",
)


def pair_schema() -> pa.Schema:
    """The Arrow schema of a run's pairs (`PAIR_COLUMNS`; nullable only where the database column is)."""
    import pyarrow as pa

    cell = pa.list_(pa.int16(), 2)
    types = {
        "no": pa.int64(),
        "run_id": pa.int64(),
        "pair_index": pa.int64(),
        "label": pa.string(),
        "attack": pa.bool_(),
        "label_source": pa.string(),
        "score": pa.float64(),
        "term_o": pa.string(),
        "term_a": pa.string(),
        "dh": pa.int32(),
        "dv": pa.int32(),
        **{name: pa.float64() for name in HARM_FLOAT_COLUMNS},
        "expert_label": pa.string(),
        "harm": pa.string(),
        "start": cell,
        "goal": cell,
        "edit": pa.string(),
        "added": pa.list_(cell),
        "map_o": pa.list_(pa.list_(pa.bool_())),
        "map_a": pa.list_(pa.list_(pa.bool_())),
        "path_o": pa.list_(cell),
        "path_a": pa.list_(cell),
        "expanded_o": pa.list_(cell),
        "expanded_a": pa.list_(cell),
        **{name: pa.int64() for name in SEARCH_COUNT_COLUMNS},
        **{name: pa.float64() for name in EFFORT_FIELDS[:-1]},
        "effort_harmful": pa.bool_(),
    }
    nullable = {
        "score",
        "dh",
        "dv",
        *HARM_FLOAT_COLUMNS,
        "expert_label",
        "harm",
        "expanded_o",
        "expanded_a",
        *SEARCH_COUNT_COLUMNS,
        *EFFORT_FIELDS,
    }
    return pa.schema([pa.field(name, types[name], nullable=name in nullable) for name in PAIR_COLUMNS])


def pairs_table(records: PairRecords, run_id: int) -> pa.Table:
    """`records` of run `run_id` as an Arrow table of `pair_schema()` (built from the arrays, no loop over pairs)."""
    import pyarrow as pa

    n = len(records)
    schema = pair_schema()

    def offsets(lengths: np.ndarray | int, count: int) -> pa.Array:
        """int32 list offsets of `count` lists of `lengths` items each."""
        ends = np.cumsum(np.broadcast_to(lengths, (count,)), dtype=np.int64)
        if len(ends) and ends[-1] > np.iinfo(np.int32).max:
            raise InputError(f"records: {ends[-1]} list items in one batch; read fewer pairs at a time")
        return pa.array(np.concatenate([[0], ends]).astype(np.int32))

    def cell_lists(cells: np.ndarray, lengths: np.ndarray | int) -> pa.Array:
        """Lists of (row, col) cells: `cells` (T, 2), list i the next `lengths[i]` of them."""
        flat = pa.array(np.ascontiguousarray(cells, dtype=np.int16).reshape(-1))
        return pa.ListArray.from_arrays(offsets(lengths, n), pa.FixedSizeListArray.from_arrays(flat, 2))

    def maps(obstacles: np.ndarray) -> pa.Array:
        size = obstacles.shape[-1]
        rows = pa.ListArray.from_arrays(offsets(size, n * size), pa.array(obstacles.reshape(-1)))
        return pa.ListArray.from_arrays(offsets(size, n), rows)

    def nullable(values: np.ndarray, null: np.ndarray, dtype) -> pa.Array:
        return pa.array(values.astype(dtype), mask=null)

    def cell(cells: np.ndarray) -> pa.Array:
        return pa.FixedSizeListArray.from_arrays(pa.array(cells.astype(np.int16).reshape(-1)), 2)

    if records.no is None:
        raise InputError("records: no `no` column (pairs read back from a store have one)", "records")
    columns = {
        "no": pa.array(records.no, pa.int64()),
        "run_id": pa.array(np.full(n, int(run_id), np.int64)),
        "pair_index": pa.array(records.pair_index, pa.int64()),
        "label": pa.array(records.label.tolist(), pa.string()),
        "attack": pa.array(records.attack, pa.bool_()),
        "label_source": pa.array(records.label_source.tolist(), pa.string()),
        "score": nullable(records.score, np.isnan(records.score), np.float64),
        "term_o": pa.array(records.term_o.tolist(), pa.string()),
        "term_a": pa.array(records.term_a.tolist(), pa.string()),
        "dh": nullable(records.dh, records.dh < 0, np.int32),
        "dv": nullable(records.dv, records.dv < 0, np.int32),
        **{
            name: nullable(getattr(records, name), np.isnan(getattr(records, name)), np.float64)
            for name in HARM_FLOAT_COLUMNS
        },
        "expert_label": pa.array(records.expert_label.tolist(), pa.string()),
        "harm": pa.array(records.harm.tolist(), pa.string()),
        "start": cell(records.starts),
        "goal": cell(records.goals),
        "edit": pa.array(records.edit.tolist(), pa.string()),
        "added": cell_lists(records.added.reshape(-1, 2), records.added.shape[1]),
        "map_o": maps(records.obstacles_o),
        "map_a": maps(records.obstacles_a),
        "path_o": cell_lists(records.path_o.cells, np.diff(records.path_o.offsets)),
        "path_a": cell_lists(records.path_a.cells, np.diff(records.path_a.offsets)),
        **_effort_columns(records, cell_lists),
    }
    return pa.Table.from_arrays([columns[name] for name in PAIR_COLUMNS], schema=schema)


def search_effort(records: PairRecords) -> dict[str, np.ndarray]:
    """The search effort of `records` (`vinadv.classify.effort`): `SEARCH_COUNT_COLUMNS` as float64 (NaN: not
    reported) and the `effort_figures` (the verdict None for an invalid pair), one value per pair."""
    n = len(records)
    counts = {}
    for name in SEARCH_COUNT_COLUMNS:
        values = getattr(records, name)
        counts[name] = np.full(n, np.nan) if values is None else np.where(values >= 1, values, np.nan)
    valid = records.reached_o
    return {**counts, **effort_figures(*counts.values(), valid=valid)}


def _effort_columns(records: PairRecords, cell_lists) -> dict:
    """The search-effort columns of `pairs_table` (nulls where not reported)."""
    import pyarrow as pa

    n = len(records)
    out = {}
    for side in ("o", "a"):
        expanded = getattr(records, f"expanded_{side}")
        if expanded is None:
            out[f"expanded_{side}"] = pa.nulls(n, pa.list_(pa.list_(pa.int16(), 2)))
        else:
            lists = cell_lists(expanded.cells, expanded.lengths)
            out[f"expanded_{side}"] = pa.ListArray.from_arrays(
                lists.offsets, lists.values, mask=pa.array(expanded.lengths == 0)
            )
    effort = search_effort(records)
    for name in SEARCH_COUNT_COLUMNS:
        out[name] = pa.array(np.nan_to_num(effort[name], nan=-1).astype(np.int64), mask=np.isnan(effort[name]))
    for name in EFFORT_FIELDS[:-1]:
        out[name] = pa.array(effort[name], mask=np.isnan(effort[name]))
    out["effort_harmful"] = pa.array(effort["effort_harmful"].tolist(), pa.bool_())
    return out


def grid(value) -> np.ndarray:
    """A map value of a pairs DataFrame (`map_o`, `map_a`: N rows of N cells) as a bool (N, N) array."""
    rows = list(value)
    return np.array([np.asarray(r, dtype=bool) for r in rows], dtype=bool).reshape(len(rows), -1)


def cells(value) -> np.ndarray:
    """A cell list of a pairs DataFrame (`path_o`, `path_a`, `added`) as an int16 (L, 2) array of (row, col)."""
    return np.array([np.asarray(c) for c in value], dtype=np.int16).reshape(-1, 2)


def run_metadata(store: Store, run_id: int, *, size: int | None, successful_only: bool) -> dict:
    """What an exported file says of its run (JSON-able): the format, the run's row, the map size N."""
    info = store.run_info(run_id)
    run = {key: value.isoformat() if isinstance(value, datetime.datetime) else value for key, value in info.items()}
    return {
        "format": PARQUET_FORMAT,
        "run": run,
        "size": size,
        "successful_only": bool(successful_only),
        "exported_by": f"vinadv {__version__}",
    }


def write_parquet(
    store: Store,
    run_id: int,
    out: str | Path,
    *,
    successful_only: bool = False,
    batch_size: int = DEFAULT_BATCH,
    progress: Callable[[int], Any] | None = None,
) -> int:
    """Write the stored pairs of run `run_id` to the Parquet file `out` (see the module doc); return how many.

    The pairs are read, converted and written `batch_size` at a time (one row group each), so a run larger than
    memory is exported in constant memory. `progress(n)` is called after each batch of n pairs. A failed export
    leaves no file behind.
    """
    import pyarrow.parquet as pq

    _check_batch_size(batch_size)
    metadata = run_metadata(store, run_id, size=None, successful_only=successful_only)  # InputError: no such run
    n = 0
    # closed (the database read ended) whether the export finishes or fails
    with contextlib.closing(store.iter_pairs(run_id, successful_only=successful_only, chunk=batch_size)) as batches:
        # the first batch gives the map size, which the file's metadata holds, and the writer needs it from the start
        first = next(batches, None)
        metadata["size"] = None if first is None else int(first.obstacles_o.shape[-1])
        schema = pair_schema().with_metadata({METADATA_KEY: json.dumps(metadata, default=str)})
        with atomic_output(out, "wb") as fh, pq.ParquetWriter(fh, schema, compression="zstd") as writer:
            if first is None:
                writer.write_table(schema.empty_table())  # a file of the schema and no rows
            for records in itertools.chain([first] if first is not None else [], batches):
                writer.write_table(pairs_table(records, run_id))
                n += len(records)
                if progress is not None:
                    progress(len(records))
    return n


def to_frame(table: pa.Table) -> pd.DataFrame:
    """A pairs table as a pandas DataFrame: numbers and strings as `Table.to_pandas` makes them (null: NaN, or a
    missing string), the list columns (cells, maps, paths) kept as Arrow arrays (`pandas.ArrowDtype`), which costs
    nothing, where NumPy object arrays would cost a Python object per map row and path cell."""
    import pandas as pd
    import pyarrow as pa

    def keep_lists(arrow_type: pa.DataType):
        return (
            pd.ArrowDtype(arrow_type)
            if pa.types.is_list(arrow_type) or pa.types.is_fixed_size_list(arrow_type)
            else None
        )

    return table.to_pandas(types_mapper=keep_lists)


def read_parquet(path: str | Path) -> pd.DataFrame:
    """An exported Parquet file as the DataFrame `Results.pairs` gives of its run (`to_frame`), the file's metadata
    (`parquet_metadata`) in `attrs["vinadv"]`."""
    import pyarrow.parquet as pq

    frame = to_frame(pq.read_table(path))
    frame.attrs[METADATA_KEY] = parquet_metadata(path)
    return frame


def parquet_metadata(path: str | Path) -> dict:
    """The run an exported Parquet file holds (`run_metadata`), read from its metadata."""
    import pyarrow.parquet as pq

    metadata = pq.read_schema(path).metadata or {}
    raw = metadata.get(METADATA_KEY.encode())
    if raw is None:
        raise InputError(f"path: {path} is not a Parquet file vinadv exported (no '{METADATA_KEY}' metadata)", "path")
    return json.loads(raw)


def _check_batch_size(batch_size: int) -> None:
    if isinstance(batch_size, bool) or not isinstance(batch_size, int | np.integer) or batch_size < 1:
        raise InputError(f"batch_size: {batch_size!r}, need a whole number of pairs, at least 1", "batch_size")


class Results:
    """The results in a vinadv database as pandas DataFrames (read-only). Use `vinadv.open(url)`; close with
    `.close()` or a `with` block.

    A run is named by its id or its name (its latest run), as on the command line; None is the latest run.
    """

    def __init__(self, store: Store):
        self.store = store

    @property
    def url(self) -> str:
        return self.store.url

    def __repr__(self) -> str:
        return f"Results({self.url!r})"

    def __enter__(self) -> Results:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the database (its connections); the DataFrames already read stay."""
        self.store.close()

    def run_id(self, run: int | str | None = None) -> int:
        """The id of run `run` (an id or a name; None: the latest run). InputError when there is none."""
        if run is None:
            runs = self.store.list_runs(with_counts=False)
            if not runs:
                raise InputError(f"run: database {self.url} holds no run", "run")
            return int(runs[-1]["id"])
        return self.store.resolve_run(run, "run")

    def runs(self) -> pd.DataFrame:
        """One row per run, oldest first: run_id, name, created, config (a dict), seed, weights_checksum, attack,
        classifier, version, timings (a dict), status, moves (its movement model: `octile` where the column is NULL,
        `vinadv.store`), and n_pairs (its stored pairs)."""
        import pandas as pd

        rows = self.store.list_runs(with_counts=True)
        frame = pd.DataFrame(rows, columns=[*runs_table.c.keys(), "n_pairs"])
        return frame.rename(columns={"id": "run_id"})

    def pairs(self, run: int | str | None = None, *, successful_only: bool = False) -> pd.DataFrame:
        """The run's stored pairs, one row each, in pair-index order (the module doc lists the columns); the same
        DataFrame as `read_parquet` of the run's Parquet export. `attrs["vinadv"]`: the run's metadata."""
        import pyarrow as pa

        run_id = self.run_id(run)
        tables, size = [], None
        for records in self.store.iter_pairs(run_id, successful_only=successful_only):
            tables.append(pairs_table(records, run_id))
            size = int(records.obstacles_o.shape[-1])
        frame = to_frame(pa.concat_tables(tables) if tables else pair_schema().empty_table())
        frame.attrs[METADATA_KEY] = run_metadata(self.store, run_id, size=size, successful_only=successful_only)
        return frame

    def iter_pairs(
        self, run: int | str | None = None, *, batch_size: int = DEFAULT_BATCH, successful_only: bool = False
    ) -> Iterator[pd.DataFrame]:
        """The run's stored pairs as DataFrames of `batch_size` rows (the last one fewer), in pair-index order, read
        a batch at a time: for runs larger than memory. Columns as `pairs`."""
        _check_batch_size(batch_size)
        run_id = self.run_id(run)
        return (
            to_frame(pairs_table(records, run_id))
            for records in self.store.iter_pairs(run_id, successful_only=successful_only, chunk=int(batch_size))
        )

    def to_parquet(
        self,
        path: str | Path,
        run: int | str | None = None,
        *,
        successful_only: bool = False,
        batch_size: int = DEFAULT_BATCH,
    ) -> int:
        """Write the run's pairs to the Parquet file `path` (`write_parquet`: what `vinadv export --format parquet`
        writes); return how many."""
        return write_parquet(self.store, self.run_id(run), path, successful_only=successful_only, batch_size=batch_size)

    def robustness(self) -> pd.DataFrame:
        """The stored robustness benchmarks (`vinadv robustness`), long form: one row per benchmark, strategy and
        number of added obstacles k, the worst case over the strategies as the strategy 'worst case'
        (`ROBUSTNESS_COLUMNS`; rates are shares of the valid maps, None/NaN where no map is valid, each with its
        Wilson 95% interval as `{rate}_low` and `{rate}_high`, what `vinadv.plot.k_curve` draws as bands). Each
        row says which run it is: the run's `name` (`--name`), the planner's full spec (`wastar:w=3`), its weights'
        SHA-256 and the maps file with its SHA-256 (None for generated maps, and the effort-harmful count and rate
        None for a planner that reports no expansions); each mean regret with its bootstrap 95% interval as stored,
        None for a benchmark stored before it."""
        import pandas as pd

        rows = [row for stored in self.store.read_robustness() for row in robustness_rows(stored)]
        return pd.DataFrame(rows, columns=list(ROBUSTNESS_COLUMNS))


def robustness_rows(stored: dict) -> list[dict]:
    """The rows of `Results.robustness()` of one stored benchmark (a row of `Store.read_robustness`)."""
    settings, result = stored["settings"], stored["result"]
    clean = result.get("clean", {})
    benchmark = {
        "benchmark": stored.get("id"),
        "name": settings.get("name"),
        "created": stored.get("created"),
        "version": stored.get("version"),
        "planner": settings.get("planner") or stored.get("planner"),  # the full spec (older rows: the name)
        "weights_checksum": stored.get("weights_checksum"),
        "maps_file": settings.get("maps"),
        "maps_sha256": settings.get("maps_sha256"),
        "size": settings.get("size"),
        "maps_seed": settings.get("maps_seed"),
        "objective": settings.get("objective"),
        "clean_success": clean.get("success_rate"),
        **{
            f"clean_success_{end}": value
            for end, value in zip(("low", "high"), rate_interval(clean.get("reached"), clean.get("maps")))
        },
        "clean_regret": clean.get("mean_regret"),
        # bootstrap intervals need the per-map regrets: None for a benchmark stored before them
        "clean_regret_low": clean.get("mean_regret_low"),
        "clean_regret_high": clean.get("mean_regret_high"),
    }
    strategies = [
        (name, s.get("by_obstacles", []), s.get("seconds")) for name, s in result.get("strategies", {}).items()
    ]
    strategies.append((WORST_CASE, result.get("overall", []), result.get("seconds")))
    figures = ROBUSTNESS_COLUMNS[ROBUSTNESS_COLUMNS.index("k") : ROBUSTNESS_COLUMNS.index("seconds")]
    return [
        {
            **benchmark,
            "strategy": name,
            **{key: f.get(key) for key in figures},
            **figure_intervals(f),  # from the counts: a benchmark stored before intervals has them too
            "seconds": seconds,
        }
        for name, by_k, seconds in strategies
        for f in by_k
    ]


# named as the builtin it shadows in this module only (which never opens a file itself): `vinadv.open(url)`
def open(url: str | os.PathLike | None = None) -> Results:
    """Open the vinadv database at `url` (a SQLAlchemy URL or a SQLite file, a `str` or a path object; default
    `$VINADV_DB`, else `vinadv.db`) for reading: `with vinadv.open("results.db") as db: db.pairs(run="demo")`.
    Anything else is an InputError naming the argument."""
    if isinstance(url, os.PathLike):
        url = os.fspath(url)
    if url is not None and not isinstance(url, str):
        raise InputError(
            f"url: vinadv.open takes a database URL or a SQLite file (str or path), got {type(url).__name__} "
            f"{one_line(repr(url))[:80]}",
            "url",
        )
    return Results(Store.open(url, readonly=True))


__all__ = [
    "DEFAULT_BATCH",
    "METADATA_KEY",
    "PAIR_COLUMNS",
    "PARQUET_FORMAT",
    "ROBUSTNESS_COLUMNS",
    "Results",
    "cells",
    "grid",
    "open",
    "pair_schema",
    "pairs_table",
    "parquet_metadata",
    "read_parquet",
    "robustness_rows",
    "run_metadata",
    "to_frame",
    "write_parquet",
]
