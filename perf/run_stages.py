"""`vinadv run` against the engine's own time: planning, each stage and the whole command, side by side.

    .venv/bin/python perf/run_stages.py [--n 5000] [--size 28] [--json]

Runs `vinadv run --n N --attack near-path --classifier rule` into a fresh SQLite file as its own process (what a
user waits for: interpreter start, imports, the job, exit), with `Planner.plan` timed inside it (every plan of the
run: each map's original and adversarial path); then, in this process, the engine alone on the same plans (the
maps the run planned, in one `plan_batch` call, compiled and warm, best of 3). Goals: the run's planning at most
1.5x the engine's time (issue 19), the whole command at most 3.5x (issue 44).

The measured command runs as it does from an installed package: a warm-up run of the same command on fewer maps
goes first (it writes Python's bytecode of every module the command imports and Numba's cached kernels, as an
install and a first run do), and both child runs may write and read bytecode (PYTHONDONTWRITEBYTECODE is unset for
them: where it is set, as in some sandboxes, every start would compile each vinadv module from source, ~0.3 s a
user never waits for). The output says so.
"""

# Imports stay in the functions: the child (this script, run again) times what `vinadv run` imports, so nothing may be
# imported before its clock starts.
# ruff: noqa: PLC0415

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time


def child(record: str, argv: list[str]) -> int:
    """Run `vinadv ARGV` in this process with `Planner.plan` timed and its inputs kept; write them to `record`."""
    t_enter = time.time()
    import numpy as np

    import vinadv.pipeline  # noqa: F401  (what `vinadv run` imports: timed apart from the job)
    from vinadv import cli
    from vinadv.planners.interface import Planner

    t_imported = time.time()
    calls, seconds = [], [0.0]
    plan = Planner.plan  # every plan of the run goes through it (the VIN planner: to its engine)

    def timed_plan(self, obstacles, starts, goals, corner_cutting=True, moves=None, **options):
        t0 = time.perf_counter()
        out = plan(self, obstacles, starts, goals, corner_cutting, moves, **options)
        seconds[0] += time.perf_counter() - t0
        calls.append((obstacles, starts, goals, corner_cutting))
        return out

    Planner.plan = timed_plan
    sys.argv = ["vinadv", *argv]
    code = cli.main()  # as the `vinadv` program calls it
    t_done = time.time()
    if len({c[3] for c in calls}) > 1:
        raise SystemExit("plans with and without corner cutting: cannot replay them in one call")
    np.savez(
        record,
        obstacles=np.concatenate([c[0] for c in calls]),
        starts=np.concatenate([c[1] for c in calls]),
        goals=np.concatenate([c[2] for c in calls]),
        corner_cutting=bool(calls[0][3]),
        planning=seconds[0],
        enter=t_enter,
        imported=t_imported,
        done=t_done,
    )
    return code


def run_argv(n: int, size: int, db: str) -> list[str]:
    """The measured command, `vinadv run` near-path with the rule labeller into `db`, as `vinadv` arguments."""
    options = {"--n": n, "--size": size, "--attack": "near-path", "--classifier": "rule", "--db": db}
    return ["run", *(str(word) for option in options.items() for word in option), "--json", "--quiet"]


#: maps of the warm-up run before the measured one
WARM_UP_MAPS = 50


def measure(n: int, size: int, workdir: str) -> dict:
    """Run the command as a child process and the engine on its plans; all figures in seconds."""
    import numpy as np
    import torch

    from vinadv.planners.vin.engine import plan_batch
    from vinadv.planners.vin.weights import load_vin

    record = os.path.join(workdir, "plans.npz")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}  # as installed: bytecode kept

    def child_run(maps: int, db: str) -> subprocess.CompletedProcess:
        argv = run_argv(maps, size, os.path.join(workdir, db))
        done = subprocess.run(
            [sys.executable, __file__, "--child", record, "--", *argv], capture_output=True, text=True, env=env
        )
        if done.returncode != 0:
            raise SystemExit(done.stderr[-3000:])
        return done

    child_run(WARM_UP_MAPS, "warm-up.sqlite")  # bytecode and Numba's caches written, as by an install's first run
    t0 = time.time()
    done = child_run(n, "run.sqlite")
    t_exit = time.time()
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    rec = np.load(record)
    model = load_vin(None, size=size)
    obstacles, starts, goals, cc = rec["obstacles"], rec["starts"], rec["goals"], bool(rec["corner_cutting"])
    plan_batch(obstacles[:50], starts[:50], goals[:50], model, cc)  # compile / load the kernels
    engine = []
    for _ in range(3):
        t = time.perf_counter()
        plan_batch(obstacles, starts, goals, model, cc)
        engine.append(time.perf_counter() - t)
    stages = summary["seconds"]
    return {
        "maps": n,
        "size": size,
        "plans": len(obstacles),
        "torch_threads": torch.get_num_threads(),
        "warm_up_maps": WARM_UP_MAPS,  # run first; both runs keep bytecode, as an installed package does
        "bytecode": True,
        "engine": min(engine),
        "planning_in_run": float(rec["planning"]),
        "stages": stages,
        "job": summary["wall_seconds"],
        "start_and_imports": float(rec["imported"]) - t0,
        "exit": t_exit - float(rec["done"]),
        "command": t_exit - t0,
    }


def main() -> None:
    if "--child" in sys.argv:
        i = sys.argv.index("--child")
        sys.exit(child(sys.argv[i + 1], sys.argv[sys.argv.index("--") + 1 :]))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=5000, help="maps (default 5000: 10,000 plans)")
    ap.add_argument("--size", type=int, default=28)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as workdir:
        r = measure(args.n, args.size, workdir)
    r["planning_vs_engine"] = r["planning_in_run"] / r["engine"]
    r["command_vs_engine"] = r["command"] / r["engine"]
    if args.json:
        print(json.dumps(r))
        return
    e = r["engine"]
    print(
        f"vinadv run --n {r['maps']} (near-path, rule, SQLite), {r['size']}x{r['size']}: {r['plans']:,} plans, "
        f"torch threads {r['torch_threads']}; after a warm-up run, bytecode and Numba caches written"
    )
    rows = [("engine alone, same plans", e), ("planning inside the run", r["planning_in_run"])]
    rows += [(f"stage {k}", v) for k, v in r["stages"].items()]
    rows += [
        ("job (run_pipeline)", r["job"]),
        ("start + imports", r["start_and_imports"]),
        ("exit (after the job)", r["exit"]),
        ("whole command", r["command"]),
    ]
    for name, sec in rows:
        print(f"  {name:<26}{sec:>8.2f} s{sec / e:>8.2f}x engine")
    print(
        f"  planning / engine = {r['planning_vs_engine']:.2f} (goal <= 1.5); "
        f"command / engine = {r['command_vs_engine']:.2f} (goal <= 3.5)"
    )


if __name__ == "__main__":
    main()
