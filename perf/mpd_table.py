"""The MP benchmark's table and robustness figures for the docs, by the real `vinadv` commands.

For each of the six MP dataset families (omron-sinicx/planning-datasets, commit a982a04, `*_032_moore_c8.npz`) it
imports the test split with one start per map drawn by the Neural A* rule (`vinadv maps import --format mpd
... --split test --seed 0`), then runs `vinadv eval --data ... --planner P --json` for each planner and keeps the
search metrics (Opt / Exp / Hmean, success). On every family's import it also runs the robustness suite, `vinadv
robustness --maps ... --n N --max-obstacles K --json` (every default strategy, 1..K obstacles added greedily, worst
case per map; harm on the maps' movement model, unit costs), for each robustness planner on the first N maps.
Planners trained elsewhere come as `--weighted NAME=PLANNER:FILE` (`vin=vin:/path/vin32.pt`): run as `--planner
PLANNER --weights FILE`, recorded under NAME with the file's SHA-256 (the path shown as `<weights>/FILE-NAME`).

Everything goes to one JSON file with the exact commands (the data folder written as `<data-dir>`, the scratch
folder as `<work>`), which `docs/hooks.py` renders on the docs page: no number is copied. With `--update`, the
entries run now replace those of the same family and planner in the existing file and the others are kept, so a
planner can be added without running the rest again.

    python perf/mpd_table.py --data-dir DIR [--out docs/results/mpd.json] [--work DIR] [--update]
        [--skip-table] [--skip-robustness] [--robustness-n 10] [--max-obstacles 3] [--weighted NAME=PLANNER:FILE]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from common import add_record_arguments, run_vinadv, scratch_folder, sha256  # perf/common.py

FAMILIES = ["mazes", "alternating_gaps", "forest", "multiple_bugtraps", "shifting_gaps", "single_bugtrap"]
PLANNERS = ["astar", "wastar:w=2", "optimal", "neural-astar"]
ROBUSTNESS_PLANNERS = ["neural-astar", "astar", "wastar:w=2", "optimal"]
DEFAULT_OUT = Path(__file__).resolve().parents[1] / "docs" / "results" / "mpd.json"
SOURCE = "omron-sinicx/planning-datasets, commit a982a04 (data/mpd/*_032_moore_c8.npz)"


def weighted(spec: str) -> tuple[str, str, Path]:
    """`NAME=PLANNER:FILE` -> (name, planner, file)."""
    name, _, rest = spec.partition("=")
    planner, _, file = rest.partition(":")
    if not (name and planner and file) or not Path(file).is_file():
        sys.exit(f"--weighted {spec!r}: expected NAME=PLANNER:FILE with an existing FILE")
    return name, planner, Path(file).resolve()


def merge(old: list[dict], new: list[dict], key) -> list[dict]:
    """`old` with the entries of `new` put in place of those with the same `key` (new ones appended)."""
    fresh = {key(e): e for e in new}
    kept = [fresh.pop(key(e), e) for e in old]
    return kept + list(fresh.values())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-dir", type=Path, required=True, help="folder holding the MP dataset's .npz files")
    add_record_arguments(parser, DEFAULT_OUT, "the imports")
    parser.add_argument("--families", default=",".join(FAMILIES), help="families, joined by commas")
    parser.add_argument("--planners", default=",".join(PLANNERS), help="the table's planners, joined by commas")
    parser.add_argument(
        "--robustness-planners", default=",".join(ROBUSTNESS_PLANNERS), help="robustness planners, joined by commas"
    )
    parser.add_argument(
        "--weighted",
        action="append",
        default=[],
        metavar="NAME=PLANNER:FILE",
        help="a planner with a weights file, in the robustness runs (and the table with --weighted-in-table)",
    )
    parser.add_argument("--weighted-in-table", action="store_true", help="also evaluate --weighted in the table")
    parser.add_argument("--robustness-n", type=int, default=10, help="maps of each family's robustness runs")
    parser.add_argument("--max-obstacles", type=int, default=3, help="the robustness runs' largest k")
    parser.add_argument("--skip-table", action="store_true", help="no eval runs")
    parser.add_argument("--skip-robustness", action="store_true", help="no robustness runs")
    parser.add_argument("--update", action="store_true", help="merge into the existing --out (module doc)")
    args = parser.parse_args()
    data_dir = args.data_dir.resolve()
    work = scratch_folder(args.work, "mpd_table_")
    extra = [weighted(s) for s in args.weighted]
    folders = {str(data_dir): "<data-dir>", str(work): "<work>"}
    for _, _, file in extra:
        folders[str(file.parent)] = "<weights>"
    record: dict = {
        "source": SOURCE,
        "placeholders": {
            "<data-dir>": "the --data-dir folder",
            "<work>": "a scratch folder",
            "<weights>": "the folder of a weights file (its SHA-256 recorded in the entry)",
        },
        "robustness_settings": {"maps_per_family": args.robustness_n, "max_obstacles": args.max_obstacles},
        "families": [],
        "robustness": [],
    }
    for family in args.families.split(","):
        maps = work / f"{family}_test.npz"
        source = data_dir / f"{family}_032_moore_c8.npz"
        import_args = ["maps", "import", "--format", "mpd", str(source), "--split", "test", "--seed", "0"]
        command, _ = run_vinadv([*import_args, "--out", str(maps), "--quiet"], folders)
        entry = {"family": family, "import": command, "planners": []}
        table = [] if args.skip_table else [(p, p, None) for p in args.planners.split(",") if p]
        table += [e for e in extra if args.weighted_in_table and not args.skip_table]
        for name, planner, file in table:
            started = time.perf_counter()
            weights = [] if file is None else ["--weights", str(file)]
            command, out = run_vinadv(
                ["eval", "--data", str(maps), "--planner", planner, *weights, "--json", "--quiet"], folders
            )
            search = json.loads(out)["search"]
            item = {"planner": name, "command": command, "search": search}
            if file is not None:
                item["weights_sha256"] = sha256(file)
            entry["planners"].append(item)
            print(f"{family} {name}: {search} ({time.perf_counter() - started:.0f} s)", file=sys.stderr)
        if entry["planners"]:
            record["families"].append(entry)
        names = [p for p in args.robustness_planners.split(",") if p]
        robust = [] if args.skip_robustness else [(p, p, None) for p in names]
        robust += [] if args.skip_robustness else extra
        for name, planner, file in robust:
            started = time.perf_counter()
            weights = [] if file is None else ["--weights", str(file)]
            command, out = run_vinadv(
                ["robustness", "--maps", str(maps), "--n", str(args.robustness_n), "--planner", planner, *weights]
                + ["--max-obstacles", str(args.max_obstacles), "--json", "--quiet"],
                folders,
            )
            item = {"family": family, "planner": name, "command": command, "figures": json.loads(out)}
            if file is not None:
                item["weights_sha256"] = sha256(file)
            record["robustness"].append(item)
            print(f"robustness {family} {name} ({time.perf_counter() - started:.0f} s)", file=sys.stderr)
    if args.update and args.out.exists():
        old = json.loads(args.out.read_text())
        families = {f["family"]: f for f in old.get("families", [])}
        for entry in record["families"]:
            if entry["family"] in families:
                kept = families[entry["family"]]
                kept["import"] = entry["import"]
                kept["planners"] = merge(kept["planners"], entry["planners"], lambda e: e["planner"])
            else:
                families[entry["family"]] = entry
        record["families"] = list(families.values())
        record["robustness"] = merge(
            old.get("robustness", []), record["robustness"], lambda e: (e.get("family", "mazes"), e["planner"])
        )
        if args.skip_robustness:
            record["robustness_settings"] = old.get("robustness_settings", record["robustness_settings"])
    args.out.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
