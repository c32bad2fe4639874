"""`vinadv bench run` (a planner on a frozen benchmark suite: one result entry) and `vinadv bench leaderboard` (the
entries of a folder as a leaderboard); `vinadv.bench`."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from vinadv.bench.index import index_json, make_index
from vinadv.commands import (
    add_actions,
    add_cluster_arguments,
    add_planner_arguments,
    db_file,
    open_args_executor,
    option_values,
    planner_device,
    planner_inputs,
)
from vinadv.commands.output import add_output_options, emit, shows_progress
from vinadv.errors import InputError, one_line
from vinadv.outfile import atomic_output, check_output_path


def register(subparsers) -> None:
    sub = add_actions(
        subparsers, "bench", help="the standard robustness benchmark: frozen suites, result entries, a leaderboard"
    )
    # named here, not read from the registry: `vinadv --help` does not import the suites (tests/test_cli_imports.py)
    suites = "vin28-v1, vin28-quick-v1, mpd32-v1, mpd32-quick-v1"
    run = sub.add_parser(
        "run",
        help="run a planner on a frozen benchmark suite and write its result entry",
        description=f"Run a planner on a frozen, versioned benchmark suite ({suites}): the attack ensemble on the "
        "suite's maps, worst case per map, and write one schema-versioned result entry (JSON).",
    )
    run.add_argument("--suite", required=True, help=f"the suite: {suites} (docs/guide/bench.md)")
    add_planner_arguments(run)
    run.add_argument(
        "--data",
        metavar="DIR",
        help="the MP suites: the folder holding the MP dataset's six <family>_032_moore_c8.npz files "
        "(docs/guide/mpd.md)",
    )
    run.add_argument("--db", help="store each finished chunk of maps in this database (URL or SQLite file)")
    run.add_argument("--resume", action="store_true", help="with --db: continue, computing only the chunks not stored")
    run.add_argument("--out", help="write the entry to this file (.json; default: print it)")
    add_cluster_arguments(run)
    add_output_options(run, json="the entry", quiet=True)
    run.set_defaults(func=cmd_bench_run)

    board = sub.add_parser(
        "leaderboard",
        help="render the entries of a folder as a leaderboard (HTML and Markdown)",
        description="Read every result entry (*.json) of DIR and write OUT/leaderboard.html and OUT/leaderboard.md, "
        "one table per suite sorted by the worst-case harmful rate, each row linking to its entry, with a legend of "
        "the columns (with --figures, each suite's k curve too). Each entry is "
        "checked against the entry schema: a file that is not a valid entry is one line naming it and the field, the "
        "rest still rendered, and the status is 2.",
    )
    board.add_argument("dir", metavar="DIR", help="folder of result entries (*.json)")
    board.add_argument("--out", required=True, metavar="OUT", help="folder to write leaderboard.html and .md to")
    board.add_argument(
        "--figures",
        action="store_true",
        help="also draw each suite's k curve (the worst-case harmful rate against k, its 95%% interval as a bar, one "
        "line per planner) as OUT/k-curve.SUITE.png and .svg, shown in leaderboard.html",
    )
    board.add_argument(
        "--index",
        metavar="FILE",
        help="also write the entries' index (JSON) to FILE: what the model zoo lists (`vinadv planners`); the shipped "
        "one is src/vinadv/bench/entries.json, of docs/results/bench",
    )
    add_output_options(board, json="the rows", quiet=True)
    board.set_defaults(func=cmd_bench_leaderboard)


def cmd_bench_run(args: argparse.Namespace) -> int:
    from vinadv.bench.job import BenchConfig, run

    config = BenchConfig(**option_values(args, "suite", "planner", "weights", "data"))  # an unknown suite: one line
    if args.resume and args.db is None:
        raise InputError("--resume: only with --db")
    if args.out:  # before the suite is computed: writable, and not the database or a file the planner reads
        data = sorted(Path(args.data).glob("*.npz")) if args.data and Path(args.data).is_dir() else args.data
        inputs = {"--db": db_file(args.db) if args.db else None, "--data": data, **planner_inputs(args)}
        check_output_path(args.out, inputs=inputs)
    device = planner_device(args)
    suite = config.frozen_suite
    with open_args_executor(args) as executor:
        result = run(config, executor, db=args.db, resume=args.resume, progress=shows_progress(args), device=device)
    entry = result.to_dict()
    text = result.json()
    if args.out:
        with atomic_output(args.out, "w", encoding="utf-8") as fh:
            fh.write(text)

    def report() -> None:
        if not args.out:
            print(text, end="")
            return
        worst = entry["worst_case"][0]
        flags = [name for name, f in entry["flags"].items() if f["raised"]]
        print(
            f"{suite.name} on planner {entry['planner']['name']}: clean success "
            f"{entry['clean']['success_rate']:.1%}, worst-case harmful rate {worst['harmful_rate'] or 0:.1%} "
            f"at one cell, flags: {', '.join(flags) or 'none'}, in {entry['time']['wall_s']:.1f} s -> {args.out}"
        )

    return emit(args, entry, report)


def cmd_bench_leaderboard(args: argparse.Namespace) -> int:
    from vinadv.bench.leaderboard import read_entries_checked, render_html, render_markdown, rows, write_k_curves

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out: {out} exists and is not a folder")
    if not Path(args.dir).is_dir():  # named as the command line names it: the argument DIR
        what = "is not a folder" if Path(args.dir).exists() else "no such folder"
        raise InputError(f"DIR {args.dir}: {what} (the folder of result entries)")
    entries_read = sorted(Path(args.dir).glob("*.json")) if Path(args.dir).is_dir() else []
    if args.index:  # not one of the entries it indexes
        check_output_path(args.index, inputs={"DIR": entries_read})
    entries, problems = read_entries_checked(args.dir)
    table = rows(entries)
    if args.index:  # the folder as given: the index names the files the way the user does
        with atomic_output(args.index, "w", encoding="utf-8") as fh:
            fh.write(index_json(make_index(entries, Path(args.dir).as_posix())))
    out.mkdir(parents=True, exist_ok=True)
    prefix = os.path.relpath(Path(args.dir), out).replace(os.sep, "/") + "/"
    for name, text in (
        ("leaderboard.md", render_markdown(table, prefix, legend=True)),
        ("leaderboard.html", render_html(table, prefix, figures=args.figures)),
    ):
        with atomic_output(out / name, "w", encoding="utf-8") as fh:
            fh.write(text)
    figures = []
    if args.figures:
        import matplotlib  # noqa: PLC0415 (only to draw the k curves)

        matplotlib.use("Agg")  # no display: the figures go to files
        figures = write_k_curves(table, out)

    def report() -> None:
        n = sum(len(r) for r in table.values())
        drawn = f" and {len(figures)} k-curve figures" if figures else ""
        print(f"{n} entries of {len(table)} suites -> {out / 'leaderboard.html'}, {out / 'leaderboard.md'}{drawn}")

    for problem in problems:  # one line per file that is not a valid entry; the others are rendered
        print(f"vinadv: error: {one_line(problem)}", file=sys.stderr)
    code = emit(args, {"suites": table, "problems": problems}, report)
    return 2 if problems else code
