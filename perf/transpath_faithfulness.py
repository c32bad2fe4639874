"""TransPath's faithfulness record: on generated 64x64 maps (corner cutting, the authors' rule), the paths and
expanded cells of both models (`cf`, `f`) in both modes (the compiled replica, the differentiable search) against
the literal restatement of the authors' forward and search (`tests/planners/transpath/literal.py`), float32 ties
counted.

    nice .venv/bin/python perf/transpath_faithfulness.py --n 200 --seed 48 --cache /tmp/tp200.jsonl \
        --out docs/results/transpath_faithfulness.json

For each map and model, one row:
- the literal forward (`plain_forward`, the maps in batches of `--batch`) and the literal search on its values: the
  reference path, expanded cells, and the selections where the largest value was shared (float32 ties);
- `replica` and `differentiable`: the two modes' searches on the literal values (the search alone compared);
- `plan` and `plan_differentiable`: the planner end to end (`plan_paths`, `plan_paths_differentiable`: its own
  forward, batched its own way, which PyTorch may round otherwise by about 1e-5), and the largest difference between
  its values and the literal forward's.
Rows go to `--cache` (JSON lines) as they are made, so a run cut short resumes where it stopped; `--out` gets the
record (counts per model and mode, every differing map with its ties, the literal expansions) once every map is done.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the literal restatement lives with the tests (tests/planners/transpath/literal.py)

from tests.planners.transpath.literal import literal_search, plain_forward, state  # noqa: E402

from common import cpu_model, load_average  # noqa: E402 (perf/common.py)
from vinadv.grid import generate_maps  # noqa: E402
from vinadv.planners.registry import load_planner  # noqa: E402
from vinadv.planners.transpath.differentiable import search_arrays  # noqa: E402
from vinadv.planners.transpath.search import transpath_search  # noqa: E402

MODELS = {"cf": "transpath-cf", "f": "transpath-focal"}
COMPARED = ("replica", "differentiable", "plan", "plan_differentiable")


def same(paths, expanded, b: int, path: list, literal_expanded: np.ndarray) -> dict:
    return {
        "path": [tuple(c) for c in np.asarray(paths[b]).tolist()] == path,
        "expanded": bool(np.array_equal(expanded[b], literal_expanded)),
    }


def rows_for(mode: str, planner, obstacles, starts, goals, first: int) -> list[dict]:
    """The rows of the maps `first..first+B-1` for the model `mode` (module doc)."""
    with torch.no_grad():
        values = plain_forward(state(mode), obstacles, starts if mode == "f" else None, goals)[:, 0]
    replica = transpath_search(values.numpy(), obstacles, starts, goals, mode, focal_exp=torch.exp(values).numpy())
    diff_paths, _, diff_expanded = search_arrays(values, obstacles, starts, goals, mode)
    plan = planner.plan_paths(obstacles, starts, goals)
    plan_diff = planner.plan_paths_differentiable(obstacles, starts, goals)
    own, _ = planner.outputs(obstacles, starts, goals)
    rows = []
    for b in range(len(obstacles)):
        path, expanded, reached, ties = literal_search(values[b], ~obstacles[b], starts[b], goals[b], mode)
        row = {
            "map": first + b,
            "model": mode,
            "reached": bool(reached),
            "expansions": int(expanded.sum()),
            "ties": int(ties),
            "forward_max_abs_diff": float(np.abs(own[b] - values[b].numpy()).max()),
            "replica": same(replica.paths, replica.expanded, b, path, expanded),
            "differentiable": same(diff_paths, diff_expanded, b, path, expanded),
            "plan": same(plan.paths, plan.expanded, b, path, expanded),
            "plan_differentiable": same(plan_diff.paths, plan_diff.expanded, b, path, expanded),
        }
        rows.append(row)
    return rows


def summary(rows: list[dict]) -> dict:
    out = {}
    for mode in MODELS:
        mine = [r for r in rows if r["model"] == mode]
        figures = {
            "maps": len(mine),
            "reached": sum(r["reached"] for r in mine),
            "maps_with_ties": sum(r["ties"] > 0 for r in mine),
            "forward_max_abs_diff": max((r["forward_max_abs_diff"] for r in mine), default=0.0),
            "expansions": [r["expansions"] for r in mine],
        }
        for what in COMPARED:
            equal = [r for r in mine if r[what]["path"] and r[what]["expanded"]]
            differing = [r for r in mine if r not in equal]
            figures[what] = {
                "equal_paths_and_expansions": len(equal),
                "differing": [
                    {
                        "map": r["map"],
                        "ties": r["ties"],
                        "path_equal": r[what]["path"],
                        "expanded_equal": r[what]["expanded"],
                    }
                    for r in differing
                ],
                "differing_without_ties": sum(r["ties"] == 0 for r in differing),
            }
        out[mode] = figures
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=200, help="generated 64x64 maps (default 200)")
    parser.add_argument("--seed", type=int, default=48, help="the generator's seed (default 48)")
    parser.add_argument("--batch", type=int, default=10, help="maps per literal forward (default 10)")
    parser.add_argument("--cache", required=True, help="JSON lines of the rows made so far (a run resumes from it)")
    parser.add_argument("--out", help="the record (JSON), written once every map is done")
    args = parser.parse_args(argv)
    torch.set_num_threads(1)

    maps = generate_maps(args.n, 64, seed=args.seed, n_starts=1)
    obstacles, starts, goals = maps.obstacles, maps.starts[:, 0], maps.goals
    cache = Path(args.cache)
    rows = [json.loads(line) for line in cache.read_text().splitlines()] if cache.exists() else []
    done = {(r["model"], r["map"]) for r in rows}
    planners = {mode: load_planner(name, 64) for mode, name in MODELS.items()}
    started, load_before = time.perf_counter(), load_average()
    with cache.open("a") as fh:
        for lo in tqdm(range(0, args.n, args.batch), desc="maps", unit="batch"):
            sl = slice(lo, min(args.n, lo + args.batch))
            for mode, planner in planners.items():
                if all((mode, i) in done for i in range(sl.start, sl.stop)):
                    continue
                for row in rows_for(mode, planner, obstacles[sl], starts[sl], goals[sl], lo):
                    if (mode, row["map"]) not in done:
                        fh.write(json.dumps(row) + "\n")
                        rows.append(row)
                fh.flush()
    rows = sorted((r for r in rows if r["map"] < args.n), key=lambda r: (r["model"], r["map"]))
    record = {
        "command": "python perf/transpath_faithfulness.py " + " ".join(argv if argv is not None else sys.argv[1:]),
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "maps": f"vinadv generate_maps({args.n}, 64, seed={args.seed}, n_starts=1), corner cutting",
        "reference": "tests/planners/transpath/literal.py: plain_forward (batches of "
        f"{args.batch} maps) and literal_search",
        "machine": {"cpu": cpu_model(), "load_average_before": load_before, "load_average_after": load_average()},
        "seconds_this_run": round(time.perf_counter() - started, 1),
        "models": summary(rows),
    }
    text = json.dumps(record, indent=1)
    if args.out and len(rows) == 2 * args.n:
        Path(args.out).write_text(text + "\n")
    for mode, figures in record["models"].items():
        line = ", ".join(f"{w} {figures[w]['equal_paths_and_expansions']}/{figures['maps']}" for w in COMPARED)
        print(f"{MODELS[mode]}: {line}; maps with float32 ties {figures['maps_with_ties']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
