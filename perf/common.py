"""What the benchmark scripts share: the side-by-side timer, their common options and the rows they search; and for
the scripts that record results for the docs, running `vinadv` on this checkout's code with the commands recorded
(`run_vinadv`), the machine (`cpu_model`, `load_average`) and the files' checksums (`sha256`).

The scripts run as `python perf/NAME.py`, so this folder is on their path and `from common import ...` finds
this module.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import shlex
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from vinadv.grid.generator import generate_maps


def timed_side_by_side(fns, rounds: int):
    """Best time of each of `fns` over `rounds` rounds, the functions taking turns within a round, so that load
    from other work (this machine is shared) hits them alike; and each one's last result."""
    best = [np.inf] * len(fns)
    results = [None] * len(fns)
    for _ in range(rounds):
        for k, fn in enumerate(fns):
            start = time.perf_counter()
            results[k] = fn()
            best[k] = min(best[k], time.perf_counter() - start)
    return best, results


def add_output_arguments(parser: argparse.ArgumentParser, rounds: int) -> None:
    """`--rounds` (best of, default `rounds`) and `--json` (`print_figures`)."""
    parser.add_argument("--rounds", type=int, default=rounds, help=f"rounds of timing, best kept (default {rounds})")
    parser.add_argument("--json", action="store_true", help="print the figures as one JSON object")


def add_maps_arguments(
    parser: argparse.ArgumentParser, n: int, seed: int, size: int = 28, planner: str | None = None
) -> None:
    """`--n` generated maps of `--size` from the generator's `--seed`; with `planner`, also `--planner` (default
    `planner`)."""
    parser.add_argument("--n", type=int, default=n, help=f"generated maps (default {n})")
    parser.add_argument("--size", type=int, default=size, help=f"side of the maps (default {size})")
    parser.add_argument("--seed", type=int, default=seed, help=f"the generator's seed (default {seed})")
    if planner is not None:
        parser.add_argument("--planner", default=planner, help=f"the registry's planner to time (default {planner})")


def print_figures(figures: dict | list, as_json: bool, lines: Iterable[str]) -> None:
    """With `--json` (`as_json`) the figures as one JSON line, for a script that reads them; else `lines`, the same
    figures worded for a reader."""
    print(json.dumps(figures) if as_json else "\n".join(lines))


def add_record_arguments(parser: argparse.ArgumentParser, out: Path, scratch: str) -> None:
    """`--out`, the JSON record to write (default `out`), and `--work`, the scratch folder for `scratch` (default: a
    new temporary folder; `scratch_folder`)."""
    parser.add_argument("--out", type=Path, default=out, help="the JSON file to write")
    parser.add_argument("--work", type=Path, default=None, help=f"scratch folder for {scratch} (default: a temp)")


def add_rows_arguments(parser: argparse.ArgumentParser, n: int, size: int) -> None:
    """`--data MPD.npz` or `--n` generated maps of `--size`: the rows of `search_rows`."""
    parser.add_argument("--data", help="an MP dataset file (<family>_032_moore_c8.npz): its test maps")
    parser.add_argument("--n", type=int, default=n, help=f"generated maps (default {n})")
    parser.add_argument("--size", type=int, default=size, help=f"side of the generated maps (default {size})")


def mpd_rows(path: str, seed: int = 0):
    """The test split of an MP dataset file: obstacles, one start per map that reaches the goal, goals."""
    with np.load(path) as data:
        free = data["arr_8"] == 1
        goals = np.argwhere(data["arr_9"][:, 0] == 1)[:, 1:]
        reachable = data["arr_11"][:, 0] > data["arr_11"].min()
    rng = np.random.default_rng(seed)
    starts = np.array([rng.choice(np.argwhere(r)) for r in reachable])
    return ~free, starts, goals


def search_rows(args: argparse.Namespace, moves: str = "moore"):
    """`(obstacles, starts, goals, source)` for the options of `add_rows_arguments`: the MP file's test maps (always
    `moore`) or `args.n` generated maps on `moves` with their first start; `source` says which."""
    if args.data:
        obstacles, starts, goals = mpd_rows(args.data)
        return obstacles, starts, goals, f"{args.data}: {len(obstacles)} test maps"
    maps = generate_maps(args.n, args.size, seed=0, n_starts=1, moves=moves)
    return maps.obstacles, maps.starts[:, 0], maps.goals, f"{args.n} generated {args.size}x{args.size} {moves} maps"


ROOT = Path(__file__).resolve().parents[1]


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def load_average() -> float:
    return round(os.getloadavg()[0], 2)


def cpu_model() -> str:
    """The CPU's model name from /proc/cpuinfo, else what `platform` says."""
    try:
        with open("/proc/cpuinfo") as fh:
            return next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()


def scratch_folder(work: Path | None, prefix: str) -> Path:
    """`--work` made, or without it a new temporary folder named from `prefix`: absolute, as the commands recorded
    name it, and `run_vinadv`'s `folders` write it as a placeholder."""
    folder = Path(work or tempfile.mkdtemp(prefix=prefix)).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def shown(text: str, folders: dict[str, str]) -> str:
    """`text` with each folder written as its placeholder."""
    for folder, placeholder in folders.items():
        text = text.replace(folder, placeholder)
    return text


def run_vinadv(args: list[str], folders: dict[str, str]) -> tuple[str, str]:
    """Run `vinadv ARGS` on this checkout's code (`python -m vinadv.cli`, its `src` first on the path); the command
    and its standard output as recorded (the folders written as their placeholders). Exits on failure."""
    src = str(ROOT / "src")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [src, os.environ.get("PYTHONPATH")]))}
    result = subprocess.run(
        [sys.executable, "-m", "vinadv.cli", *args], capture_output=True, text=True, check=False, env=env, cwd=ROOT
    )
    if result.returncode != 0:
        sys.exit(f"vinadv {shlex.join(args)} failed ({result.returncode}): {result.stderr.strip()[-2000:]}")
    return "vinadv " + shown(shlex.join(args), folders), shown(result.stdout, folders)
