"""`vinadv export`: stored map pairs of one run out of the database, as CSV, JSON lines, an npz or a Parquet file."""

from __future__ import annotations

import argparse
import contextlib
import csv
import json
import sys

from vinadv.commands import add_db_argument, db_file
from vinadv.commands.output import add_output_options, note, progress_bar
from vinadv.errors import InputError
from vinadv.outfile import atomic_output, check_output_path

EXPORT_FORMAT = "vinadv.labelled_pairs/1"
#: the formats written to a file only (--out required)
BINARY_FORMATS = ("npz", "parquet")
#: the first text columns of an exported row: the paper's Table 2, then the attack flag, the run and the pair index
LEADING_COLUMNS = ("no", "map_o", "map_a", "path_o", "path_a", "label", "attack", "run_id", "pair_index")


def export_columns() -> tuple[str, ...]:
    """The text columns of an exported row, in order: `LEADING_COLUMNS`, then every other column the store reads
    back (`PAIR_COLUMNS`), in the store's order."""
    from vinadv.store.codec import PAIR_COLUMNS  # imported here so `vinadv --help` stays fast

    return (*LEADING_COLUMNS, *(name for name in PAIR_COLUMNS if name not in LEADING_COLUMNS), *DERIVED_COLUMNS)


#: the columns a text export computes from the stored ones: the search effort's counts and figures
#: (`vinadv.classify.effort`; empty where the planner reports no expansions)
DERIVED_COLUMNS = (
    "expansions_o",
    "expansions_a",
    "effort_ratio",
    "astar_effort_ratio",
    "relative_effort",
    "effort_harmful",
)


def _with_effort(chunk: list[dict]) -> None:
    """Add the `DERIVED_COLUMNS` to the rows of `chunk` (text rows of one run), in place, the chunk at once."""
    import numpy as np

    from vinadv.classify.effort import effort_figures

    def count(text: str | None) -> float:
        return np.nan if not text else text.count(";") + 1.0

    counts = {name: np.array([count(r[f"expanded_{side}"]) for r in chunk]) for name, side in (("o", "o"), ("a", "a"))}
    astar = {
        side: np.array(
            [np.nan if r[f"astar_expansions_{side}"] is None else r[f"astar_expansions_{side}"] for r in chunk],
            dtype=np.float64,
        )
        for side in ("o", "a")
    }
    valid = np.array([r["term_o"] == "goal" for r in chunk], dtype=bool)
    figures = effort_figures(counts["o"], counts["a"], astar["o"], astar["a"], valid=valid)
    for i, row in enumerate(chunk):
        row["expansions_o"] = None if np.isnan(counts["o"][i]) else int(counts["o"][i])
        row["expansions_a"] = None if np.isnan(counts["a"][i]) else int(counts["a"][i])
        for name in ("effort_ratio", "astar_effort_ratio", "relative_effort"):
            value = figures[name][i]
            row[name] = None if np.isnan(value) else float(value)
        row["effort_harmful"] = None if figures["effort_harmful"][i] is None else bool(figures["effort_harmful"][i])


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "export",
        help="export the stored pairs of a run (csv, jsonl, npz or parquet)",
        description="Export the stored map pairs of one run. csv/jsonl keep the database's text formats "
        "(maps as 0/1 rows joined by ';', paths as row,col cells joined by ';'); npz decodes them into "
        f"arrays ({EXPORT_FORMAT}: the pairs-file fields plus labels); parquet writes one typed row per pair, "
        "maps and paths as list columns, the run and its config in the file's metadata (for pandas and pyarrow).",
    )
    add_db_argument(p)
    p.add_argument("--run", required=True, help="run id, or run name (its latest run)")
    p.add_argument("--format", choices=("csv", "jsonl", "npz", "parquet"), default="csv")
    p.add_argument("--successful-only", action="store_true", help="only successful attacks (UrP or FP)")
    p.add_argument(
        "--out", default=None, help="output file (default: stdout for csv/jsonl; required for npz and parquet)"
    )
    add_output_options(p, quiet=True)
    p.set_defaults(func=run_export)


def run_export(args: argparse.Namespace) -> int:
    from vinadv.store import Store  # imported here so `vinadv --help` stays fast

    if args.format in BINARY_FORMATS and not args.out:
        raise InputError(f"--out: required with --format {args.format}")
    if args.out:
        # a directory, a missing folder, a read-only file or the database itself: refused before the database is read
        check_output_path(args.out, inputs={"--db": db_file(args.db)})
    with Store.open(args.db, readonly=True) as store:
        run_id = store.resolve_run(args.run)
        if args.format == "npz":
            n = _export_npz(store, run_id, args.out, args.successful_only)
        elif args.format == "parquet":
            n = _export_parquet(store, run_id, args.out, args.successful_only, args)
        else:
            n = _export_text(store, run_id, args.format, args.out, args.successful_only, args)
    note(args, f"exported {n} pairs of run {run_id} to {args.out or 'stdout'}")
    return 0


def _export_npz(store, run_id: int, out: str, successful_only: bool) -> int:
    import numpy as np

    from vinadv.store.schema import HARM_FLOAT_COLUMNS

    info = store.run_info(run_id)
    records = store.read_pairs(run_id, successful_only=successful_only)
    arrays = {
        "format": np.array(EXPORT_FORMAT),
        "run_id": np.array(run_id, dtype=np.int64),
        "strategy": np.array(info.get("attack") or ""),
        "moves": np.array(info["moves"]),  # the run's movement model: what the costs count
        "size": np.array(records.size if len(records) else 0, dtype=np.int64),
        "no": records.no,
        "pair_index": records.pair_index,
        "obstacles_o": records.obstacles_o,
        "obstacles_a": records.obstacles_a,
        "starts": records.starts,
        "goals": records.goals,
        # (n, 2) for one-obstacle pairs, as ever; (n, K, 2) for K added obstacles
        "added": records.added[:, 0] if records.n_added == 1 else records.added,
        **records.path_o.to_fields("path_o"),
        **records.path_a.to_fields("path_a"),
        "term_o": records.term_o.astype(str),
        "term_a": records.term_a.astype(str),
        "label": records.label.astype(str),
        "attack": records.attack,
        "label_source": records.label_source.astype(str),
        "score": records.score,
        "dh": records.dh,
        "dv": records.dv,
        # harm: NaN = NULL for the costs, "" = NULL for the two labels (an npz holds no None)
        **{name: getattr(records, name) for name in HARM_FLOAT_COLUMNS},
        "expert_label": np.where(np.equal(records.expert_label, None), "", records.expert_label).astype(str),
        "harm": np.where(np.equal(records.harm, None), "", records.harm).astype(str),
        "edit": records.edit,  # add | remove (vocabulary.EDITS)
        **_npz_effort(records),
    }
    with atomic_output(out, "wb") as fh:  # a failed export never leaves a half-written file behind
        np.savez_compressed(fh, **arrays)
    return len(records)


def _npz_effort(records) -> dict:
    """The search effort of an npz export: the expanded cells as the paths are (an empty list: none reported) and
    A*'s counts (-1: none), where any pair has them (`vinadv.pairs/4`'s fields)."""
    out = {}
    for side in ("o", "a"):
        expanded, astar = getattr(records, f"expanded_{side}"), getattr(records, f"astar_expansions_{side}")
        if expanded is not None:
            out.update(expanded.to_fields(f"expanded_{side}"))
        if astar is not None:
            out[f"astar_expansions_{side}"] = astar
    return out


def _export_parquet(store, run_id: int, out: str, successful_only: bool, args: argparse.Namespace) -> int:
    from vinadv.analysis import write_parquet  # pyarrow: imported here so `vinadv --help` stays fast

    total = store.count_pairs(run_id)
    with progress_bar(args, total=total, unit="pair", file=sys.stderr) as bar:
        return write_parquet(store, run_id, out, successful_only=successful_only, progress=bar.update)


def _export_text(store, run_id: int, fmt: str, out: str | None, successful_only: bool, args: argparse.Namespace) -> int:
    total = store.count_pairs(run_id)
    n = 0
    columns = export_columns()
    target = atomic_output(out, "w", newline="", encoding="utf-8") if out else contextlib.nullcontext(sys.stdout)
    with target as stream:
        writer = csv.writer(stream) if fmt == "csv" else None
        if writer is not None:
            writer.writerow(columns)
        # no bar while the rows themselves go to standard output
        with progress_bar(args, hidden=out is None, total=total, unit="pair", file=sys.stderr) as bar:
            for chunk in store.iter_pair_rows(run_id, successful_only=successful_only):
                for row in chunk:
                    row["run_id"] = run_id
                    row["attack"] = bool(row["attack"])
                    row["edit"] = row["edit"] or "add"  # NULL (a row of schema 6 or below) reads as add
                _with_effort(chunk)
                if writer is not None:
                    writer.writerows(
                        [
                            [
                                "" if r[c] is None else int(r[c]) if c in ("attack", "effort_harmful") else r[c]
                                for c in columns
                            ]
                            for r in chunk
                        ]
                    )
                else:
                    stream.write("".join(json.dumps({c: r[c] for c in columns}) + "\n" for r in chunk))
                n += len(chunk)
                bar.update(len(chunk))
    return n
