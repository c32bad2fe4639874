"""TransPath beside A*, weighted A* and the optimal planner on generated 64x64 maps, by the real `vinadv` commands:
clean figures and robustness at one to three added obstacles, for the docs' results page.

It generates the maps once (`vinadv maps generate --n N --size 64 --seed S`: octile moves with corner cutting,
TransPath's rule), then for each planner runs `vinadv eval --data ... --planner P --json` (the search figures: Opt /
Exp / Hmean against exact A*, and for a TransPath planner the authors' expansions and cost ratios) and `vinadv
robustness --maps ... --n R --planner P --max-obstacles K --json` (every default strategy, 1..K obstacles added
greedily, the worst case per map). Everything goes to one JSON file with the exact commands (the scratch folder
written as `<work>`), in the shape of `perf/mpd_table.py`'s, which `docs/hooks.py` renders on
`docs/results/transpath.md`: no number is copied. With `--update`, the planners run now replace their entries in the
existing file and the others are kept, so the costly TransPath runs can go apart from the rest.

    nice python perf/transpath_table.py [--n 20] [--seed 1000] [--robustness-n 10] [--planners A,B] [--update]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from common import add_record_arguments, cpu_model, load_average, run_vinadv, scratch_folder  # perf/common.py

PLANNERS = ["transpath-cf", "transpath-focal", "astar", "wastar:w=2", "optimal"]
DEFAULT_OUT = Path(__file__).resolve().parents[1] / "docs" / "results" / "transpath.json"


def merge(old: list[dict], new: list[dict]) -> list[dict]:
    """`old` with the entries of `new` in place of those of the same planner (new ones appended)."""
    fresh = {e["planner"]: e for e in new}
    kept = [fresh.pop(e["planner"], e) for e in old]
    return kept + list(fresh.values())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_record_arguments(parser, DEFAULT_OUT, "the maps")
    parser.add_argument("--n", type=int, default=20, help="generated maps of the clean figures (default 20)")
    parser.add_argument("--seed", type=int, default=1000, help="the maps' seed (default 1000: the held-out maps)")
    parser.add_argument("--robustness-n", type=int, default=10, help="maps of the robustness runs (default 10)")
    parser.add_argument("--max-obstacles", type=int, default=3, help="the robustness runs' largest k")
    parser.add_argument("--planners", default=",".join(PLANNERS), help="planners, joined by commas")
    parser.add_argument("--update", action="store_true", help="merge into the existing --out (module doc)")
    args = parser.parse_args()
    work = scratch_folder(args.work, "transpath_table_")
    folders = {str(work): "<work>"}
    maps = work / "generated64.npz"
    family = f"generated 64x64 (seed {args.seed})"
    load_before = load_average()
    generate, _ = run_vinadv(
        ["maps", "generate", "--n", str(args.n), "--size", "64", "--seed", str(args.seed), "--out", str(maps)]
        + ["--quiet"],
        folders,
    )
    entry = {"family": family, "import": generate, "planners": []}
    robustness = []
    for planner in [p for p in args.planners.split(",") if p]:
        started = time.perf_counter()
        command, out = run_vinadv(["eval", "--data", str(maps), "--planner", planner, "--json", "--quiet"], folders)
        search = json.loads(out)["search"]
        entry["planners"].append({"planner": planner, "command": command, "search": search})
        command, out = run_vinadv(
            ["robustness", "--maps", str(maps), "--n", str(args.robustness_n), "--planner", planner]
            + ["--max-obstacles", str(args.max_obstacles), "--json", "--quiet"],
            folders,
        )
        robustness.append({"family": family, "planner": planner, "command": command, "figures": json.loads(out)})
        print(f"{planner}: {time.perf_counter() - started:.0f} s", file=sys.stderr)
    run = {
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "planners": [e["planner"] for e in entry["planners"]],
        "machine": {"cpu": cpu_model(), "load_average_before": load_before, "load_average_after": load_average()},
    }
    record = {
        "placeholders": {"<work>": "a scratch folder"},
        "robustness_settings": {"maps": args.robustness_n, "max_obstacles": args.max_obstacles},
        "runs": [run],
        "families": [entry],
        "robustness": robustness,
    }
    if args.update and args.out.exists():
        old = json.loads(args.out.read_text())
        if old["families"][0]["import"] != generate or old["robustness_settings"] != record["robustness_settings"]:
            sys.exit(f"--update: {args.out} holds other maps or settings ({old['families'][0]['import']})")
        entry["planners"] = merge(old["families"][0]["planners"], entry["planners"])
        record["robustness"] = merge(old["robustness"], robustness)
        record["runs"] = [*old["runs"], run]
    args.out.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
