"""The 64x64 VIN's figures for the docs (docs/guide/planners.md, "The 64x64 VIN"), measured, with their commands.

Two measurements, written to one JSON file that `docs/hooks.py` renders on the page (no number is copied):

- transfer: the shipped 28x28 weights on generated 64x64 maps, by the real commands. A weights file records the
  size it was trained on and `vin eval` refuses it on maps of another size, so each is first exported as a
  port-style file, which records no size (`vinadv vin export-weights W.pt --format state-dict --out W.pth`), then
  measured with `vinadv vin eval --weights W.pth --n N --seed S --size 64 --k K --json` for each k given.
- reach: why `vin64.pt` was trained with k = 100 (a value crosses one cell per value-iteration step, so k bounds the
  optimal path the VIN can follow). On maps of the generator with the training set's settings (`vinadv maps
  generate --size 64 --seed 64 --starts 1`, here its first `--reach-maps` maps, by `vinadv.grid.generate_maps`), the
  optimal move count (an optimal path's cells less one, `vinadv.grid.shortest_distances`) of every start and of every
  free cell that reaches the goal: the longest from a start, the share of cells within each k, and each map's
  farthest cell (median, 99th percentile).

`vinadv` runs as `python -m vinadv.cli` with this checkout's `src` first on the path, so the code measured is the
code beside this script. The JSON has the exact commands (the scratch folder written as `<work>`), the date and the
machine.

    nice python perf/vin64_reach.py [--out docs/results/vin64_reach.json] [--work DIR] [--n 200]
        [--seed 5000] [--reach-maps 500] [--reach-seed 64]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import shlex
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
sys.path.insert(0, str(SRC))  # the library measured is this checkout's, as the commands' is

from common import (  # noqa: E402 (perf/common.py)
    add_record_arguments,
    cpu_model,
    load_average,
    run_vinadv,
    scratch_folder,
    sha256,
)
from vinadv.grid.generator import generate_maps  # noqa: E402
from vinadv.grid.shortest_paths import shortest_distances  # noqa: E402

DEFAULT_OUT = ROOT / "docs" / "results" / "vin64_reach.json"
WEIGHTS_DIR = SRC / "vinadv" / "weights"
SIZE = 64
#: the shipped 28x28 weights and the value-iteration steps each is measured with on 64x64 maps
TRANSFER = (("vin28.pt", (100,)), ("vin28_robust.pt", (84, 128)))
#: the k whose reach is measured: the one `vin64.pt` was trained with, and 1.3 N (N = 64), the rule of the 28x28 VINs
REACH_K = (84, 100)


def transfer(work: Path, n: int, seed: int, folders: dict[str, str]) -> list[dict]:
    """Each shipped 28x28 weights file, exported without its size and measured on generated 64x64 maps."""
    entries = []
    for name, ks in TRANSFER:
        source = WEIGHTS_DIR / name
        exported = work / (source.stem + ".pth")
        export, _ = run_vinadv(
            ["vin", "export-weights", os.path.relpath(source, ROOT), "--format", "state-dict", "--out", str(exported)],
            folders,
        )
        runs = []
        for k in ks:
            started = time.perf_counter()
            eval_args = ["vin", "eval", "--weights", str(exported), "--n", str(n), "--seed", str(seed)]
            eval_args += ["--size", str(SIZE), "--k", str(k), "--threads", "1", "--json", "--quiet"]
            command, out = run_vinadv(eval_args, folders)
            figures = json.loads(out)
            runs.append({"k": k, "command": command, "figures": figures})
            took = time.perf_counter() - started
            print(
                f"{name} k={k}: {figures['success_rate']:.4f} of {figures['rollouts']} ({took:.0f} s)",
                file=sys.stderr,
            )
        entries.append({"weights": name, "weights_sha256": sha256(source), "export": export, "runs": runs})
    return entries


def reach(n_maps: int, seed: int, n_starts: int) -> dict:
    """The optimal move counts on the generator's maps: from the starts, and from every free cell that reaches the
    goal (the goal itself left out, as the training loss leaves it out)."""
    maps = generate_maps(n_maps, size=SIZE, seed=seed, n_starts=n_starts)
    _, moves = shortest_distances(maps.obstacles, maps.goals, maps.corner_cutting, maps.moves)
    rows = np.arange(len(maps))[:, None]
    from_starts = moves[rows, maps.starts[..., 0], maps.starts[..., 1]]
    cells = moves[moves > 0]
    farthest = moves.reshape(len(maps), -1).max(axis=1)
    return {
        "maps": len(maps),
        "size": SIZE,
        "seed": seed,
        "starts_per_map": n_starts,
        "moves": maps.moves,
        "corner_cutting": maps.corner_cutting,
        "longest_from_a_start": int(from_starts.max()),
        "cells": int(len(cells)),
        "cells_within": {str(k): float((cells <= k).mean()) for k in REACH_K},
        "farthest_cell_median": float(np.median(farthest)),
        "farthest_cell_p99": float(np.percentile(farthest, 99)),
        "farthest_cell_max": int(farthest.max()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_record_arguments(parser, DEFAULT_OUT, "the exports")
    parser.add_argument("--n", type=int, default=200, help="generated 64x64 maps of the transfer runs (default 200)")
    parser.add_argument("--seed", type=int, default=5000, help="their seed (default 5000)")
    parser.add_argument("--reach-maps", type=int, default=500, help="maps of the reach figures (default 500)")
    parser.add_argument("--reach-seed", type=int, default=64, help="their seed (default 64, the training set's)")
    args = parser.parse_args()
    work = scratch_folder(args.work, "vin64_reach_")
    folders = {str(work): "<work>"}
    out = args.out.resolve()
    shown_out = os.path.relpath(out, ROOT) if out.is_relative_to(ROOT) else "OUT"
    command_args = ["--out", shown_out, "--n", str(args.n), "--seed", str(args.seed)]
    command_args += ["--reach-maps", str(args.reach_maps), "--reach-seed", str(args.reach_seed)]
    record: dict = {
        "command": "python perf/vin64_reach.py " + shlex.join(command_args),
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "placeholders": {"<work>": "a scratch folder"},
        "machine": {
            "cpu": cpu_model(),
            "cores": len(os.sched_getaffinity(0)),
            "niceness": os.nice(0),
            "load_average_before": load_average(),
        },
    }
    # the training set's generator: one start per map, as `vinadv maps generate --starts 1` drew it
    record["reach"] = reach(args.reach_maps, args.reach_seed, n_starts=1)
    print(f"reach: {record['reach']}", file=sys.stderr)
    record["transfer"] = transfer(work, args.n, args.seed, folders)
    record["machine"]["load_average_after"] = load_average()
    out.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
