"""`vinadv bench run` (a planner on a frozen benchmark suite: one result entry), `vinadv bench verify` (does an
entry hold what it says), `vinadv bench compare` (two planners on the same maps: a paired test) and `vinadv bench
leaderboard` (the entries of folders and files as a leaderboard); `vinadv.bench`."""

from __future__ import annotations

import argparse
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
from vinadv.display import number
from vinadv.errors import InputError, one_line
from vinadv.outfile import atomic_output, check_output_path


def register(subparsers) -> None:
    sub = add_actions(
        subparsers, "bench", help="the standard robustness benchmark: frozen suites, result entries, a leaderboard"
    )
    # named here, not read from the registry: `vinadv --help` does not import the suites (tests/test_cli_imports.py)
    suites = (
        "vin28-v1, vin28-quick-v1, mpd32-v1, mpd32-quick-v1, vin28-v2, vin28-quick-v2, mpd32-v2, mpd32-quick-v2, "
        "movingai64-v1, movingai64-quick-v1"
    )
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
        help="the data suites' files: for the MP suites the folder holding the MP dataset's six "
        "<family>_032_moore_c8.npz files (docs/guide/mpd.md); for the Moving AI suites the one holding the four city "
        "maps and the three 64x64 MAPF maps (docs/guide/movingai.md)",
    )
    run.add_argument("--db", help="store each finished chunk of maps in this database (URL or SQLite file)")
    run.add_argument("--resume", action="store_true", help="with --db: continue, computing only the chunks not stored")
    run.add_argument(
        "--reuse",
        metavar="ENTRY",
        help="recompute from this older entry of the suite and planner (.json, format 2): its attacks whose "
        "strategies did not change are taken from it, the others computed (docs/guide/bench.md)",
    )
    run.add_argument("--out", help="write the entry (with --chunks, the part) to this file (.json; default: print it)")
    parts = run.add_argument_group(
        "an entry in parts (machines or sittings that share no database; docs/guide/bench.md)"
    )
    parts.add_argument(
        "--chunks",
        metavar="LIST",
        help="compute only these chunks of maps (numbers and ranges: 0-4,9) and write them as a part of the entry, "
        "not the entry",
    )
    parts.add_argument(
        "--parts",
        nargs="+",
        default=[],
        metavar="PART",
        help="take the chunks of these parts (files written with --chunks); the chunks none of them holds are computed",
    )
    share = run.add_argument_group("sharing (entries of the -v2 suites; docs/guide/submit.md)")
    share.add_argument("--display-name", metavar="TEXT", help="the name the leaderboard shows (default: the planner's)")
    share.add_argument(
        "--author", action="append", default=[], metavar="NAME", dest="authors", help="an author (repeat for each)"
    )
    share.add_argument("--paper", metavar="URL", help="the paper's link (http or https)")
    share.add_argument("--code", metavar="URL", help="the code's link (http or https)")
    share.add_argument("--external", action="store_true", help="the entry is submitted from outside the project")
    add_cluster_arguments(run)
    add_output_options(run, json="the entry", quiet=True)
    run.set_defaults(func=cmd_bench_run)

    verify = sub.add_parser(
        "verify",
        help="check that a result entry holds what it says: its figures, and chunks of it recomputed",
        description="Check a vinadv.bench_entry/2 entry: every figure (clean, per attack, worst case, flags) "
        "recomputed from the per-map outcomes it holds, and --chunks K chunks of maps (drawn with --seed) recomputed "
        "with its planner and compared byte for byte. One line per difference, naming the field; exit status 1 on a "
        "difference, 2 on bad input (not an entry of format 2, another suite, another planner).",
    )
    verify.add_argument("entry", metavar="ENTRY", help="the entry file (.json)")
    verify.add_argument(
        "--chunks", type=int, default=0, metavar="K", help="recompute K chunks of maps (default 0: the figures only)"
    )
    verify.add_argument("--seed", type=int, default=0, help="the draw of the chunks (default 0)")
    verify.add_argument("--data", metavar="DIR", help="the MP suites: the folder of the MP dataset's files")
    add_planner_arguments(
        verify,
        weights_help="the entry's weights file or zoo name (default: the planner's shipped weights; checked against "
        "the entry's weights sha256)",
    )
    add_output_options(verify, json="the differences", quiet=True)
    verify.set_defaults(func=cmd_bench_verify)

    compare = sub.add_parser(
        "compare",
        help="is one planner more robust than another on the same maps: McNemar's exact test per k",
        description="Compare two vinadv.bench_entry/2 entries of one suite map by map: at each k, the maps valid for "
        "both planners, those harmful (worst case) for A only and for B only, and the two-sided p-value of McNemar's "
        "exact test (binomial on the discordant maps); A is more (less) robust than B where p < 0.05. Also each "
        "entry's mean regrets (clean, and worst case per k) with their bootstrap 95% intervals over the maps.",
    )
    compare.add_argument("entry_a", metavar="ENTRY_A", help="the first entry file (.json)")
    compare.add_argument("entry_b", metavar="ENTRY_B", help="the second entry file (.json), of the same suite")
    add_output_options(compare, json="the tests and the means")
    compare.set_defaults(func=cmd_bench_compare)

    board = sub.add_parser(
        "leaderboard",
        help="render the entries of folders and files as a leaderboard (HTML and Markdown)",
        description="Read every result entry (*.json) of each folder SOURCE, and each entry file SOURCE, and write "
        "OUT/leaderboard.html and OUT/leaderboard.md, one table per suite sorted by the worst-case harmful rate, each "
        "row linking to its entry, with a legend of the columns (with --figures, each suite's k curve too). Each "
        "entry is checked against the entry schema: a file that is not a valid entry is one line naming it and the "
        "field, the rest still rendered, and the status is 2.",
    )
    board.add_argument(
        "sources", nargs="+", metavar="SOURCE", help="folders of result entries (*.json), or entry files"
    )
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
    from vinadv.bench.reuse import ReusedEntry

    names = ("suite", "planner", "weights", "data", "display_name", "authors", "paper", "code", "external")
    config = BenchConfig(**option_values(args, *names))  # an unknown suite, a bad link: one line
    if args.resume and args.db is None:
        raise InputError("--resume: only with --db")
    if args.out:  # before the suite is computed: writable, and not the database or a file the planner reads
        folder = args.data and Path(args.data).is_dir()
        data = sorted([*Path(args.data).glob("*.npz"), *Path(args.data).glob("*.map")]) if folder else args.data
        inputs = {
            "--db": db_file(args.db) if args.db else None,
            "--data": data,
            "--parts": args.parts,
            **planner_inputs(args),
        }
        check_output_path(args.out, inputs=inputs)
    device = planner_device(args)
    suite = config.frozen_suite
    reuse = None
    if args.reuse:  # a file that is not an entry to reuse: one line before the work
        reuse = ReusedEntry.read(args.reuse)
    with open_args_executor(args) as executor:
        result = run(
            config,
            executor,
            db=args.db,
            resume=args.resume,
            progress=shows_progress(args),
            device=device,
            reuse=reuse,
            chunks=args.chunks,
            parts=args.parts,
        )
    entry = result.to_dict()
    text = result.json()
    if args.out:
        with atomic_output(args.out, "w", encoding="utf-8") as fh:
            fh.write(text)

    def report() -> None:
        if not args.out:
            print(text, end="")
            return
        if args.chunks is not None:
            n_maps = sum(c["maps"] for c in entry["chunks"].values())
            print(
                f"{suite.name} on planner {entry['planner']['name']}: chunks {args.chunks} ({n_maps} maps) in "
                f"{entry['wall_s']:.1f} s -> {args.out} (a part: `vinadv bench run --parts` makes the entry)"
            )
            return
        worst = entry["worst_case"][0]
        flags = [name for name, f in entry["flags"].items() if f["raised"]]
        print(
            f"{suite.name} on planner {entry['planner']['name']}: clean success "
            f"{entry['clean']['success_rate']:.1%}, worst-case harmful rate {worst['harmful_rate'] or 0:.1%} "
            f"at one cell, flags: {', '.join(flags) or 'none'}, in {entry['time']['wall_s']:.1f} s -> {args.out}"
        )

    return emit(args, entry, report)


def cmd_bench_verify(args: argparse.Namespace) -> int:
    from vinadv.bench.leaderboard import planner_label
    from vinadv.bench.suites import get_suite
    from vinadv.bench.verify import read_entry, verify_entry
    from vinadv.planners.registry.loading import load_planner

    entry = read_entry(args.entry)
    if args.chunks < 0:
        raise InputError(f"--chunks must be >= 0, got {args.chunks}")
    planner = None
    if args.chunks > 0:
        suite = get_suite(entry["suite"]["name"])
        spec = args.planner or planner_label(entry["planner"])
        device = planner_device(args)
        planner = load_planner(spec, suite.size, weights=args.weights, device=device, moves=suite.movement())
    result = verify_entry(entry, args.chunks, args.seed, data=args.data, planner=planner, progress=shows_progress(args))

    def report() -> None:
        for line in result["differences"]:
            print(line)
        if not result["differences"]:
            chunks = ", ".join(map(str, result["chunks"])) or "none"
            print(f"{args.entry}: every figure follows from its per-map outcomes; chunks recomputed equal: {chunks}")

    code = emit(args, {"entry": args.entry, **result}, report)
    return 1 if result["differences"] else code


def cmd_bench_compare(args: argparse.Namespace) -> int:
    from vinadv.bench.comparison import compare_entries, mean_intervals, p_text
    from vinadv.bench.leaderboard import planner_label
    from vinadv.bench.verify import read_entry

    a, b = (read_entry(path, reader="bench compare") for path in (args.entry_a, args.entry_b))
    tests = compare_entries(a, b)
    names = [planner_label(e["planner"]) for e in (a, b)]
    result = {
        "suite": a["suite"],
        "a": {"entry": args.entry_a, "planner": names[0], "means": mean_intervals(a)},
        "b": {"entry": args.entry_b, "planner": names[1], "means": mean_intervals(b)},
        "tests": tests,
    }

    def report() -> None:
        print(f"{a['suite']['name']}: A = {names[0]} ({args.entry_a}), B = {names[1]} ({args.entry_b})")
        for t in tests:
            print(
                f"k = {t['k']}: {t['maps']} maps valid for both, harmful for A only {t['a_only']}, for B only "
                f"{t['b_only']}, both {t['both']}; McNemar {p_text(t['p_value'])}: "
                + (
                    "A and B not distinguishable"
                    if t["verdict"] == "not distinguishable"
                    else f"A {t['verdict']} than B"
                )
            )
        for side in ("a", "b"):
            means = result[side]["means"]
            parts = [("clean", means["clean_regret"])] + [(f"k = {m['k']}", m) for m in means["worst_regret"]]
            shown = ", ".join(f"{k} {number(m['mean'])} [{number(m['low'])}, {number(m['high'])}]" for k, m in parts)
            print(f"{side.upper()} mean regret (95% bootstrap interval over the maps): {shown}")
            if "worst_effort" in means:  # a search planner's entry: its worst effort ratio per map at each k
                shown = ", ".join(
                    f"k = {m['k']} {number(m['mean'])} [{number(m['low'])}, {number(m['high'])}]"
                    for m in means["worst_effort"]
                )
                print(f"{side.upper()} mean worst effort ratio (95% bootstrap interval over the maps): {shown}")

    return emit(args, result, report)


def cmd_bench_leaderboard(args: argparse.Namespace) -> int:
    from vinadv.bench.leaderboard import (
        entry_files,
        read_entries_checked,
        render_html,
        render_markdown,
        rows,
        write_k_curves,
    )

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out: {out} exists and is not a folder")
    for source in args.sources:  # named as the command line names it: the argument SOURCE
        if not Path(source).exists():
            raise InputError(f"SOURCE {source}: no such folder or file (the result entries)")
    entries_read = entry_files(args.sources)
    if args.index:  # not one of the entries it indexes
        check_output_path(args.index, inputs={"SOURCE": entries_read})
    entries, problems = read_entries_checked(args.sources)
    table = rows(entries, base=out)
    if args.index:  # the files as given: the index names them the way the user does
        with atomic_output(args.index, "w", encoding="utf-8") as fh:
            fh.write(index_json(make_index(entries)))
    out.mkdir(parents=True, exist_ok=True)
    for name, text in (
        ("leaderboard.md", render_markdown(table, legend=True)),
        ("leaderboard.html", render_html(table, figures=args.figures)),
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
