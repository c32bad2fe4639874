"""Planners on a GPU (`--device`) against the CPU, side by side in one run: speed, and how often the two differ.

    python perf/device.py [--device cuda] [--planners gppn,vin] [--batches 1,64,1024] [--tie-maps 1000]
        [--robustness-maps 4] [--full-robustness 0] [--full-chunk 100] [--moves octile] [--json FILE]

For each planner of `--planners`, its default (a torch planner on the CPU, the VIN's exact engine) against the same
planner loaded with `--device` (for the VIN: its PyTorch forward there):
- `plans`: plans per second (one start a map, `plan_maps`) at each batch size of `--batches`, after a warm-up,
  calls repeated for at least `--seconds`;
- `ties`: on `--tie-maps` held-out 28x28 maps (7 starts each), the paths that differ, the cells whose action differs
  (`vinadv.testing.planners.tie_flips`, against the CPU's logits: for the VIN its PyTorch forward on the CPU) and
  those of them that are not near ties (expected 0); policy planners only (a search planner has no logits);
- `robustness`: `vinadv.robustness.robustness` on `--robustness-maps` maps, every strategy and the exhaustive search,
  one obstacle: seconds on each, and whether the figures are equal;
- `full_robustness` (with `--full-robustness N`): the exhaustive robustness of N maps on the device alone (issue 36:
  the GPPN's on 1,000 maps, target under 5 minutes on one H100-class GPU), `--full-chunk` maps a call, the JSON
  written after each call: a run stopped at its time limit still gives the maps done and their seconds (each chunk's
  figures are kept; the maps are the first N of the seed, whatever the chunking).
`--moves`: the movement model of the maps and planners (Neural A* plans `moore` moves: `--planners neural-astar
--moves moore`).
With `--device cpu` it compares the defaults with the forwards on the CPU (the VIN: forward against engine).
`perf/device_check.sh` runs it on a lent GPU machine.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

import numpy as np
import torch

from vinadv.grid import generate_maps
from vinadv.planners.registry import load_planner
from vinadv.planners.search import SearchPlanner
from vinadv.robustness import DEFAULT_STRATEGIES, robustness
from vinadv.testing.planners import tie_flips

SIZE = 28
#: the robustness benchmark's held-out maps (`vinadv robustness`' default seed)
SEED = 1000


def machine(device: str) -> dict:
    info = {
        "cpu": platform.processor() or platform.machine(),
        "cores": len(os.sched_getaffinity(0)),
        "torch": torch.__version__,
        "torch_threads": torch.get_num_threads(),
    }
    try:
        with open("/proc/cpuinfo") as fh:
            info["cpu"] = next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    if torch.device(device).type == "cuda":
        info["gpu"] = torch.cuda.get_device_name(torch.device(device))
    return info


def plans_per_second(planner, maps, batch: int, seconds: float) -> float:
    """Plans per second of `plan_maps` on `batch` maps (one start each) a call, calls repeated for `seconds`."""
    obstacles, goals, starts = maps.obstacles[:batch], maps.goals[:batch], maps.starts[:batch, :1]
    warm = slice(0, min(batch, 64))  # compiles, loads, allocates (a whole batch of 1,024 takes long on a CPU)
    planner.plan(obstacles[warm], starts[warm], goals[warm])
    done, t0 = 0, time.perf_counter()
    while True:
        planner.plan(obstacles, starts, goals)
        done += batch
        elapsed = time.perf_counter() - t0
        if elapsed >= seconds:
            return done / elapsed


def ties(reference, default, device, maps) -> dict:
    """How the device's paths differ from the default's, and which action flips explain it (see the module doc)."""
    flips = tie_flips(reference.logits(maps.obstacles, maps.goals), device.logits(maps.obstacles, maps.goals))
    a = default.plan(maps.obstacles, maps.starts, maps.goals)
    b = device.plan(maps.obstacles, maps.starts, maps.goals)
    differ = ~a.paths.same_as(b.paths)
    owner = np.repeat(np.arange(len(maps)), maps.n_starts)
    return {
        "maps": len(maps),
        "paths": len(differ),
        "paths_differing": int(differ.sum()),
        "paths_differing_on_maps_without_a_flip": int((differ & ~flips["maps"][owner]).sum()),
        "flipped_cells": flips["cells"],
        "flipped_cells_not_near_ties": flips["not_ties"],
        "maps_with_a_flip": int(flips["maps"].sum()),
    }


def robustness_figures(planner, maps, strategies) -> tuple[dict, float]:
    t0 = time.perf_counter()
    result = robustness(planner, maps, strategies, 1, progress=False).to_dict()
    seconds = time.perf_counter() - t0
    figures = {name: s["by_obstacles"] for name, s in result["strategies"].items()}
    return {"clean": result["clean"], "overall": result["overall"], "strategies": figures}, seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cuda" if torch.cuda.is_available() else "cpu")
    parser.add_argument("--planners", default="gppn,vin")
    parser.add_argument("--batches", default="1,64,1024")
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--tie-maps", type=int, default=1000)
    parser.add_argument("--robustness-maps", type=int, default=4)
    parser.add_argument("--full-robustness", type=int, default=0, metavar="N")
    parser.add_argument("--full-chunk", type=int, default=100, metavar="M", help="maps a robustness call")
    parser.add_argument("--moves", default="octile", help="movement model of the maps (neural-astar: moore)")
    parser.add_argument("--json", metavar="FILE", help="also write the figures here")
    args = parser.parse_args()
    batches = [int(b) for b in args.batches.split(",")]
    out = {"device": args.device, "machine": machine(args.device), "moves": args.moves, "planners": {}}

    def save() -> None:  # after every part: a run stopped at its time limit keeps what it measured
        if args.json:
            with open(args.json, "w") as fh:
                json.dump(out, fh, indent=1)

    moves = args.moves
    maps = generate_maps(max(batches), SIZE, seed=SEED, moves=moves)
    for spec in args.planners.split(","):
        default = load_planner(spec, SIZE, moves=moves)
        device = load_planner(spec, SIZE, device=args.device, moves=moves)
        # the CPU's logits (the VIN's engine has none of its own)
        reference = load_planner(spec, SIZE, device="cpu", moves=moves)
        got = out["planners"][spec] = {"device_record": device.spec().get("device")}
        for batch in batches:
            rates = {
                name: round(plans_per_second(p, maps, batch, args.seconds), 1)
                for name, p in (("default", default), (args.device, device))
            }
            rates["ratio"] = round(rates[args.device] / rates["default"], 2)
            got.setdefault("plans_per_s", {})[str(batch)] = rates
            print(spec, "batch", batch, rates, flush=True)
            save()
        if args.tie_maps and not isinstance(reference, SearchPlanner):
            got["ties"] = ties(reference, default, device, generate_maps(args.tie_maps, SIZE, seed=SEED, moves=moves))
            print(spec, "ties", got["ties"], flush=True)
            save()
        if args.robustness_maps:
            few = generate_maps(args.robustness_maps, SIZE, seed=SEED, moves=moves)
            strategies = [*DEFAULT_STRATEGIES, "exhaustive"]
            a, ta = robustness_figures(default, few, strategies)
            b, tb = robustness_figures(device, few, strategies)
            got["robustness"] = {
                "maps": args.robustness_maps,
                "seconds": {"default": round(ta, 1), args.device: round(tb, 1)},
                "ratio": round(ta / tb, 2),
                "figures_equal": a == b,
            }
            print(spec, "robustness", got["robustness"], flush=True)
            save()
        if args.full_robustness:
            full = generate_maps(args.full_robustness, SIZE, seed=SEED, moves=moves)
            done = got["full_robustness"] = {"maps": args.full_robustness, "maps_done": 0, "seconds": 0.0, "chunks": []}
            for lo in range(0, len(full), args.full_chunk):
                t0 = time.perf_counter()
                result = robustness(device, full.take(slice(lo, lo + args.full_chunk)), ["exhaustive"], 1).to_dict()
                seconds = time.perf_counter() - t0
                chunk = result["strategies"]["exhaustive"]["by_obstacles"][0]
                done["chunks"].append({"first_map": lo, "seconds": round(seconds, 1), "exhaustive": chunk})
                done["maps_done"] += chunk["maps"]
                done["seconds"] = round(done["seconds"] + seconds, 1)
                print(spec, "full robustness", {k: done[k] for k in ("maps_done", "seconds")}, flush=True)
                save()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
