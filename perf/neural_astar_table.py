"""Neural A*'s figures for the docs (docs/guide/neural-astar.md, "Measured"), by the real commands.

On the mazes file of the MP dataset (omron-sinicx/planning-datasets, commit a982a04, `mazes_032_moore_c8.npz`), for
each seed it imports the test split with one start per map drawn by the Neural A* rule (`vinadv maps import --format
mpd ... --split test --seed S`), compares the exact and the differentiable search on it (`vinadv neural-astar
compare-modes --data ... --json`) and evaluates the planner (`vinadv eval --data ... --planner neural-astar --json`:
Opt / Exp / Hmean beside A*'s expansions). Then it times the searches side by side on the file's test maps with
`perf/neural_astar.py --data ... --json` (plans/s of `astar`, the exact mode, the encoder alone, the
differentiable search, with the gradient).

Everything goes to one JSON file with the exact commands (the data folder written as `<data-dir>`, the scratch folder
as `<work>`), the date and the machine (CPU model, cores, PyTorch version, niceness and the load average before and
after: the speeds are side by side in one run, so their ratios are the figures to read on a loaded machine), which
`docs/hooks.py` renders on the page: no number is copied.

    nice python perf/neural_astar_table.py --data-dir DIR [--out docs/results/neural_astar.json] [--work DIR]
        [--seeds 0,1,2,3,4] [--rounds 10]
"""

from __future__ import annotations

import argparse
import datetime
import importlib.metadata
import json
import os
import shlex
import subprocess
import sys
from pathlib import Path

from common import (  # perf/common.py
    ROOT,
    add_record_arguments,
    cpu_model,
    load_average,
    run_vinadv,
    scratch_folder,
    shown,
)
from mpd_table import SOURCE  # perf/mpd_table.py: the same dataset

DEFAULT_OUT = ROOT / "docs" / "results" / "neural_astar.json"
DATA_FILE = "mazes_032_moore_c8.npz"
SPEED_SCRIPT = "perf/neural_astar.py"


def speed(data: Path, rounds: int, folders: dict[str, str]) -> dict:
    """`perf/neural_astar.py --data DATA --rounds ROUNDS --json`, run as its own process (its figures, as it
    prints them), with the command as recorded."""
    args = [SPEED_SCRIPT, "--data", str(data), "--rounds", str(rounds), "--json"]
    result = subprocess.run([sys.executable, *args], capture_output=True, text=True, check=False, cwd=ROOT)
    if result.returncode != 0:
        sys.exit(f"{shlex.join(args)} failed ({result.returncode}): {result.stderr.strip()[-2000:]}")
    figures = json.loads(shown(result.stdout, folders))
    return {"command": "python " + shown(shlex.join(args), folders), "rounds": rounds, "figures": figures}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-dir", type=Path, required=True, help=f"folder holding the MP dataset's {DATA_FILE}")
    add_record_arguments(parser, DEFAULT_OUT, "the imports")
    parser.add_argument("--seeds", default="0,1,2,3,4", help="the imports' seeds, joined by commas")
    parser.add_argument("--rounds", type=int, default=10, help="the speed's rounds, best kept (default 10)")
    args = parser.parse_args()
    data_dir = args.data_dir.resolve()
    data = data_dir / DATA_FILE
    work = scratch_folder(args.work, "neural_astar_table_")
    folders = {str(data_dir): "<data-dir>", str(work): "<work>"}
    out = args.out.resolve()
    shown_out = os.path.relpath(out, ROOT) if out.is_relative_to(ROOT) else "OUT"
    command_args = [
        "--data-dir",
        str(data_dir),
        "--out",
        shown_out,
        "--seeds",
        args.seeds,
        "--rounds",
        str(args.rounds),
    ]
    record: dict = {
        "command": "python perf/neural_astar_table.py " + shown(shlex.join(command_args), folders),
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "source": SOURCE,
        "placeholders": {"<data-dir>": "the --data-dir folder", "<work>": "a scratch folder"},
        "machine": {
            "cpu": cpu_model(),
            "cores": len(os.sched_getaffinity(0)),
            "torch": importlib.metadata.version("torch"),
            "niceness": os.nice(0),
            "load_average_before": load_average(),
        },
        "modes": [],
    }
    for seed in [int(s) for s in args.seeds.split(",") if s]:
        maps = work / f"mazes_test_{seed}.npz"
        import_args = ["maps", "import", "--format", "mpd", str(data), "--split", "test", "--seed", str(seed)]
        imported, _ = run_vinadv([*import_args, "--out", str(maps), "--quiet"], folders)
        as_json = ["--json", "--quiet"]
        compared, compare_out = run_vinadv(["neural-astar", "compare-modes", "--data", str(maps), *as_json], folders)
        evaluated, eval_out = run_vinadv(["eval", "--data", str(maps), "--planner", "neural-astar", *as_json], folders)
        comparison = json.loads(compare_out)
        entry = {
            "seed": seed,
            "import": imported,
            "compare_modes": {"command": compared, "figures": comparison},
            "eval": {"command": evaluated, "search": json.loads(eval_out)["search"]},
        }
        record["modes"].append(entry)
        print(f"seed {seed}: {comparison['identical_paths']} of {comparison['searches']} identical", file=sys.stderr)
    record["speed"] = speed(data, args.rounds, folders)
    print(f"speed: {record['speed']['figures']['plans_per_s']}", file=sys.stderr)
    record["machine"]["load_average_after"] = load_average()
    out.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
