"""TransPath beside A*, weighted A*, the optimal planner, the 64x64 VIN and Neural A* on four families of 64x64 maps, by
the real `vinadv` commands: clean figures and robustness at one to three added obstacles, for the docs' results page.

The families (`--families`, joined by commas; each is made once by its `vinadv maps` commands):

- `generated`: `vinadv maps generate --n N --size 64 --seed S`, octile moves with corner cutting (TransPath's rule);
  TransPath cf and focal, `astar`, `wastar:w=2`, `optimal` and `vin64` (`--planner vin --weights vin64`, trained on
  these maps' rule).
- `movingai`: `vinadv maps import --format movingai CITY.map --crop 64 --crops C --seed S` for each of the four
  256x256 city maps, joined by `vinadv maps concat`: octile moves without corner cutting (the format's rule, kept by
  every planner); the same planners but `vin64`, whose rule they are not.
- `examples`: the authors' six example tasks (`vinadv maps import --format transpath FILES`), their rule (corner
  cutting), so `vin64` too.
- `moore`: the `generated` maps' `moore` twin (`--moves moore`, same seed: the same obstacles, every move cost 1,
  Neural A*'s rule): `neural-astar` beside `astar` (there the Neural A* authors' vanilla A*).

For each family and planner it runs `vinadv eval --data MAPS --planner P --json` (the search figures: Opt / Exp /
Hmean against exact A*, and for a TransPath planner the authors' expansions and cost ratios) and `vinadv robustness
--maps MAPS --n R --planner P --max-obstacles K --json` (every default strategy, 1..K obstacles added greedily, the
worst case per map; for a planner that reports expansions, the effort-harmful rate too). Everything goes to one JSON
file with the exact commands (the scratch folder written as `<work>`), a list of families each with its planners,
which `docs/hooks.py` renders on `docs/results/transpath.md`: no number is copied. With `--update`, the families and
planners run now replace their entries in the existing file (a family whose maps or settings changed is replaced
whole) and the others are kept, so that the families, and the costly TransPath runs, can go apart; `--join A.json
B.json ...` runs nothing and writes the records of runs made side by side (each to its own `--out`) as one, merged in
the order given as `--update` would merge them.

    nice python perf/transpath_table.py [--families generated,movingai,examples,moore] [--n 20] [--seed 1000]
        [--crops 2] [--robustness-n 5] [--planners A,B] [--update] [--join A.json B.json ...]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from common import add_record_arguments, cpu_model, load_average, run_vinadv, scratch_folder  # perf/common.py

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUT = ROOT / "docs" / "results" / "transpath.json"
MOVINGAI = ROOT.parent / "shared" / "data" / "movingai"
TRANSPATH_DATA = ROOT.parent / "shared" / "data" / "transpath"
CITIES = ["Berlin_1_256", "Boston_0_256", "Milan_0_256", "Paris_1_256"]
SEARCH = ["transpath-cf", "transpath-focal", "astar", "wastar:w=2", "optimal"]
#: each family's planners, by the name shown, and the `--planner ...` arguments that name stands for
FAMILY_PLANNERS = {
    "generated": [*SEARCH, "vin64"],
    "movingai": SEARCH,
    "examples": [*SEARCH, "vin64"],
    "moore": ["neural-astar", "astar"],
}
PLANNER_ARGS = {"vin64": ["--planner", "vin", "--weights", "vin64"]}


def family_maps(name: str, args: argparse.Namespace, work: Path, folders: dict) -> tuple[str, list[str], Path]:
    """Make family `name`'s maps file in `work`: its title, the commands run and the file."""
    out = work / f"{name}64.npz"
    generate = ["maps", "generate", "--n", str(args.n), "--size", "64", "--seed", str(args.seed)]
    if name in ("generated", "moore"):
        moves = ["--moves", "moore"] if name == "moore" else []
        command, _ = run_vinadv([*generate, *moves, "--out", str(out), "--quiet"], folders)
        twin = ", moore twin" if name == "moore" else ""
        return f"generated 64x64{twin} (seed {args.seed})", [command], out
    if name == "movingai":
        commands, parts = [], []
        for city in CITIES:
            part = work / f"{city}.npz"
            command, _ = run_vinadv(
                ["maps", "import", "--format", "movingai", str(MOVINGAI / f"{city}.map"), "--crop", "64"]
                + ["--crops", str(args.crops), "--seed", str(args.crop_seed), "--out", str(part), "--quiet"],
                folders,
            )
            commands.append(command)
            parts.append(str(part))
        command, _ = run_vinadv(["maps", "concat", *parts, "--out", str(out), "--quiet"], folders)
        return f"Moving AI city crops (seed {args.crop_seed})", [*commands, command], out
    if name == "examples":
        files = sorted(str(p) for p in TRANSPATH_DATA.glob("heatmap_*.xml"))
        command, _ = run_vinadv(
            ["maps", "import", "--format", "transpath", *files, "--out", str(out), "--quiet"], folders
        )
        return "TransPath's examples", [command], out
    raise SystemExit(f"--families: unknown family {name!r} (known: {', '.join(FAMILY_PLANNERS)})")


def merge(old: list[dict], new: list[dict], key) -> list[dict]:
    """`old` with the entries of `new` in place of those of the same `key(entry)` (new ones appended)."""
    fresh = {key(e): e for e in new}
    kept = [fresh.pop(key(e), e) for e in old]
    return kept + list(fresh.values())


def merge_record(old: dict, record: dict) -> dict:
    """`record`'s families, planners and robustness runs merged into `old` (module doc: `--update`)."""
    if old.get("robustness_settings", {}).get("max_obstacles") != record["robustness_settings"]["max_obstacles"]:
        sys.exit("--update: the existing record has another --max-obstacles")
    families = {f["family"]: f for f in old["families"]}
    robustness = old["robustness"]
    for entry in record["families"]:
        before = families.get(entry["family"])
        if before is not None and (before["import"], before.get("robustness_maps")) == (
            entry["import"],
            entry["robustness_maps"],
        ):
            merged = merge(before["planners"], entry["planners"], lambda e: e["planner"])
            if len(merged) > len(entry["planners"]):  # planners of another run: this run's time is not theirs
                entry["seconds"] = None
            entry["planners"] = merged
        else:  # other maps or settings: the family's old runs go with them
            robustness = [r for r in robustness if r["family"] != entry["family"]]
        families[entry["family"]] = entry
    record["families"] = list(families.values())
    record["robustness"] = merge(robustness, record["robustness"], lambda r: (r["family"], r["planner"]))
    record["runs"] = [*old["runs"], *record["runs"]]
    return record


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_record_arguments(parser, DEFAULT_OUT, "the maps")
    parser.add_argument("--families", default=",".join(FAMILY_PLANNERS), help="families, joined by commas")
    parser.add_argument("--n", type=int, default=20, help="generated maps of the clean figures (default 20)")
    parser.add_argument("--seed", type=int, default=1000, help="the generated maps' seed (default 1000: held out)")
    parser.add_argument("--crops", type=int, default=2, help="crops of each city map (default 2)")
    parser.add_argument("--crop-seed", type=int, default=0, help="the crops' seed (default 0)")
    parser.add_argument("--robustness-n", type=int, default=5, help="maps of the robustness runs (default 5)")
    parser.add_argument("--max-obstacles", type=int, default=3, help="the robustness runs' largest k")
    parser.add_argument("--planners", default="", help="only these of each family's planners, joined by commas")
    parser.add_argument("--update", action="store_true", help="merge into the existing --out (module doc)")
    parser.add_argument("--join", nargs="+", type=Path, default=[], help="write these records as one (module doc)")
    args = parser.parse_args()
    if args.join:
        records = [json.loads(path.read_text()) for path in args.join]
        joined = records[0]
        for record in records[1:]:
            joined = merge_record(joined, record)
        args.out.write_text(json.dumps(joined, indent=1) + "\n")
        print(f"wrote {args.out}", file=sys.stderr)
        return
    work = scratch_folder(args.work, "transpath_table_")
    folders = {str(work): "<work>", str(ROOT.parent / "shared" / "data"): "<data>"}
    only = {p for p in args.planners.split(",") if p}
    load_before = load_average()
    families, robustness, planners_run = [], [], []
    for name in [f for f in args.families.split(",") if f]:
        family, imports, maps = family_maps(name, args, work, folders)
        entry = {"family": family, "import": imports, "robustness_maps": args.robustness_n, "planners": []}
        family_started = time.perf_counter()
        for planner in FAMILY_PLANNERS[name]:
            if only and planner not in only:
                continue
            started = time.perf_counter()
            spec = PLANNER_ARGS.get(planner, ["--planner", planner])
            command, out = run_vinadv(["eval", "--data", str(maps), *spec, "--json", "--quiet"], folders)
            entry["planners"].append({"planner": planner, "command": command, "search": json.loads(out)["search"]})
            command, out = run_vinadv(
                ["robustness", "--maps", str(maps), "--n", str(args.robustness_n), *spec]
                + ["--max-obstacles", str(args.max_obstacles), "--json", "--quiet"],
                folders,
            )
            figures = json.loads(out)
            robustness.append({"family": family, "planner": planner, "command": command, "figures": figures})
            planners_run.append(f"{name}: {planner}")
            print(f"{family}, {planner}: {time.perf_counter() - started:.0f} s", file=sys.stderr)
        entry["seconds"] = round(time.perf_counter() - family_started, 1)
        families.append(entry)
        print(f"{family}: {entry['seconds']:.0f} s", file=sys.stderr)
    run = {
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "planners": planners_run,
        "machine": {"cpu": cpu_model(), "load_average_before": load_before, "load_average_after": load_average()},
    }
    record = {
        "placeholders": {"<work>": "a scratch folder", "<data>": "the public data: Moving AI maps, TransPath's tasks"},
        "robustness_settings": {"max_obstacles": args.max_obstacles},
        "runs": [run],
        "families": families,
        "robustness": robustness,
    }
    if args.update and args.out.exists():
        record = merge_record(json.loads(args.out.read_text()), record)
    args.out.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
