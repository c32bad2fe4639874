"""The same `vinadv run` quiet and with one busy process beside it: how much a busy core slows the whole job.

    .venv/bin/python perf/under_load.py [--n 5000] [--size 28] [--json]

Runs `vinadv run --n N --attack near-path --classifier rule` into a fresh SQLite file twice, as its own process:
first alone, then with one busy process (a pure-Python spin loop, started here and killed when the run ends, and
never running longer than `--load-limit` seconds). Prints both wall times, their stages and the ratio (goal,
issue 19: at most 2x). The "quiet" figure is only as quiet as the machine: other users' work counts in both.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

from run_stages import run_argv  # the same command (this folder is on the path of a script run here)

BUSY = "import time\nend = time.time() + {limit}\nwhile time.time() < end:\n    pass\n"


def run_once(n: int, size: int, db: str) -> dict:
    argv = [sys.executable, "-m", "vinadv.cli", *run_argv(n, size, db)]
    t0 = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(done.stderr[-3000:])
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    return {"command": wall, "job": summary["wall_seconds"], "stages": summary["seconds"]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=5000)
    ap.add_argument("--size", type=int, default=28)
    ap.add_argument("--load-limit", type=float, default=600.0, help="seconds the busy process may run at most")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as workdir:
        run_once(50, args.size, os.path.join(workdir, "warm.sqlite"))  # compiled kernels on disk, files cached
        quiet = run_once(args.n, args.size, os.path.join(workdir, "quiet.sqlite"))
        busy = subprocess.Popen([sys.executable, "-c", BUSY.format(limit=args.load_limit)])
        try:
            loaded = run_once(args.n, args.size, os.path.join(workdir, "loaded.sqlite"))
        finally:
            busy.kill()
            busy.wait()
    out = {
        "maps": args.n,
        "size": args.size,
        "cores": len(os.sched_getaffinity(0)),
        "quiet": quiet,
        "one_busy_process": loaded,
        "ratio": loaded["command"] / quiet["command"],
    }
    if args.json:
        print(json.dumps(out))
        return
    print(f"vinadv run --n {args.n} (near-path, rule, SQLite) on {out['cores']} cores")
    for name, r in (("quiet", quiet), ("one busy process", loaded)):
        stages = ", ".join(f"{k} {v:.2f}" for k, v in r["stages"].items())
        print(f"  {name:<17} command {r['command']:7.2f} s  job {r['job']:7.2f} s  ({stages})")
    print(f"  busy / quiet = {out['ratio']:.2f} (goal <= 2)")


if __name__ == "__main__":
    main()
