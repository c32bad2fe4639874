"""The MP benchmark's table and robustness figures for the docs, by the real `vinadv` commands.

For each of the six MP dataset families (omron-sinicx/planning-datasets, commit a982a04, `*_032_moore_c8.npz`) it
imports the test split with one start per map drawn by the Neural A* rule (`vinadv maps import --format mpd
... --split test --seed 0`), then runs `vinadv eval --data ... --planner P --json` for each planner and keeps the
search metrics (Opt / Exp / Hmean, success). On the mazes import it also runs `vinadv robustness --maps ...
--max-obstacles 1 --json` for weighted A* and Neural A* on the first `--robustness-n` maps (harm on the maps'
movement model, unit costs). Everything goes to one JSON file with the exact commands (the data folder written as
`<data-dir>`, the scratch folder as `<work>`), which `docs/hooks.py` renders on the docs page: no number is copied.

    python benchmarks/mpd_table.py --data-dir DIR [--out docs/results/mpd.json] [--work DIR]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

FAMILIES = ["mazes", "alternating_gaps", "forest", "multiple_bugtraps", "shifting_gaps", "single_bugtrap"]
PLANNERS = ["astar", "wastar:w=2", "optimal", "neural-astar"]
ROBUSTNESS_PLANNERS = ["wastar:w=2", "neural-astar"]
DEFAULT_OUT = Path(__file__).resolve().parents[1] / "docs" / "results" / "mpd.json"


def run(args: list[str], data_dir: Path, work: Path) -> tuple[str, str]:
    """Run `vinadv ARGS`; the command and its standard output as recorded (placeholders for the folders)."""
    result = subprocess.run(["vinadv", *args], capture_output=True, text=True, check=False)
    if result.returncode != 0:
        sys.exit(f"vinadv {' '.join(args)} failed ({result.returncode}): {result.stderr.strip()[-2000:]}")

    def shown(text: str) -> str:
        return text.replace(str(data_dir), "<data-dir>").replace(str(work), "<work>")

    return "vinadv " + shown(" ".join(args)), shown(result.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-dir", type=Path, required=True, help="folder holding the MP dataset's .npz files")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="the JSON file to write")
    parser.add_argument("--work", type=Path, default=None, help="scratch folder for the imports (default: a temp)")
    parser.add_argument("--families", default=",".join(FAMILIES), help="families, joined by commas")
    parser.add_argument("--robustness-n", type=int, default=20, help="maps of the robustness runs")
    args = parser.parse_args()
    data_dir = args.data_dir.resolve()
    work = Path(args.work or tempfile.mkdtemp(prefix="mpd_table_")).resolve()
    work.mkdir(parents=True, exist_ok=True)
    record: dict = {
        "source": "omron-sinicx/planning-datasets, commit a982a04 (data/mpd/*_032_moore_c8.npz)",
        "placeholders": {"<data-dir>": "the --data-dir folder", "<work>": "a scratch folder"},
        "families": [],
        "robustness": [],
    }
    for family in args.families.split(","):
        maps = work / f"{family}_test.npz"
        source = data_dir / f"{family}_032_moore_c8.npz"
        command, _ = run(
            ["maps", "import", "--format", "mpd", str(source), "--split", "test", "--seed", "0", "--out", str(maps)],
            data_dir,
            work,
        )
        entry = {"family": family, "import": command, "planners": []}
        for planner in PLANNERS:
            started = time.perf_counter()
            command, out = run(["eval", "--data", str(maps), "--planner", planner, "--json", "--quiet"], data_dir, work)
            search = json.loads(out)["search"]
            entry["planners"].append({"planner": planner, "command": command, "search": search})
            print(f"{family} {planner}: {search} ({time.perf_counter() - started:.0f} s)", file=sys.stderr)
        record["families"].append(entry)
        if family == "mazes":
            for planner in ROBUSTNESS_PLANNERS:
                command, out = run(
                    ["robustness", "--maps", str(maps), "--n", str(args.robustness_n), "--planner", planner]
                    + ["--max-obstacles", "1", "--json", "--quiet"],
                    data_dir,
                    work,
                )
                record["robustness"].append({"planner": planner, "command": command, "figures": json.loads(out)})
                print(f"robustness {planner} done", file=sys.stderr)
    args.out.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
