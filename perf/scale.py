"""`vinadv run` on a Dask LocalCluster: pairs/s with 1 and 2 worker processes on the same work, and the ratio.

    nice .venv/bin/python perf/scale.py [--n 2000] [--size 28] [--shard-size 100] [--attack near-path]
                                              [--workers 1,2] [--weights FILE] [--json]

Measured in one run, on the same RunConfig (same seed, so the same pairs), each into a fresh SQLite file:
- local: `run_pipeline` in this process (no Dask; torch and the planner use their default threads);
- k workers: `run_pipeline` with a `DaskExecutor` on a LocalCluster of k single-threaded worker processes, started
  and warmed up (weights loaded, compiled kernels cached) before the clock starts, so the figure is the
  steady-state rate, not start-up. The client writes every pair to the database (included in the time).
Also printed: the client's database write rate (the ceiling of one client) and, from the 1-worker rate, a
projection (linear scaling assumed, checked by the measured 2/1 ratio) of the workers and hours for 10 million
pairs. Default weights: the shipped ones for --size if present, else `planning_vin(size)` (same cost per map).
The load average before and after is printed: on a shared machine the ratio is noisy.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from distributed import Client

from vinadv.cluster import DaskExecutor, start_local_cluster
from vinadv.cluster.worker import plugin_class
from vinadv.executor import LOCAL
from vinadv.pipeline import RunConfig, run_pipeline
from vinadv.planners.vin.weights import default_weights_path, save_vin
from vinadv.testing.planners import planning_vin

TARGET_PAIRS = 10_000_000


def _weights(args, tmp: Path) -> str:
    if args.weights:
        return args.weights
    if default_weights_path(args.size).exists():
        return str(default_weights_path(args.size))
    path = tmp / f"vin{args.size}.pt"
    save_vin(planning_vin(args.size, seed=0, noise=0.1), path)
    return str(path)


def _timed_run(config, db: str, executor=LOCAL) -> dict:
    t0 = time.perf_counter()
    summary = run_pipeline(config, db=db, progress=False, executor=executor)
    wall = time.perf_counter() - t0
    return {
        "pairs": summary.n_pairs,
        "wall_s": wall,
        "pairs_per_s": summary.n_pairs / wall,
        "store_s": summary.seconds["store"],
        "compute_s": sum(summary.seconds[s] for s in ("generate", "attack", "identify")),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=2000, help="maps (one pair each with near-path)")
    parser.add_argument("--size", type=int, default=28)
    parser.add_argument("--shard-size", type=int, default=100)
    parser.add_argument("--attack", default="near-path")
    parser.add_argument("--workers", default="1,2", help="worker counts to measure, comma-separated")
    parser.add_argument("--weights")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    load_before = os.getloadavg()
    out = {
        "n_maps": args.n,
        "size": args.size,
        "shard_size": args.shard_size,
        "attack": args.attack,
        "cores": len(os.sched_getaffinity(0)),
        "load_before": [round(v, 2) for v in load_before],
        "runs": {},
    }
    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = Path(tmp_dir)
        weights = _weights(args, tmp)
        config = RunConfig(
            n=args.n, size=args.size, attack=args.attack, seed=1, shard_size=args.shard_size, weights=weights
        )
        warm = RunConfig(
            n=args.shard_size * 2,
            size=args.size,
            attack=args.attack,
            seed=2,
            shard_size=args.shard_size,
            weights=weights,
        )
        _timed_run(warm, f"sqlite:///{tmp / 'warm.db'}")
        out["runs"]["local"] = _timed_run(config, f"sqlite:///{tmp / 'local.db'}")
        for k in (int(v) for v in args.workers.split(",")):
            with start_local_cluster(k) as cluster, Client(cluster) as client:
                client.register_plugin(plugin_class()())
                _timed_run(warm, f"sqlite:///{tmp / f'warm{k}.db'}", DaskExecutor(client))  # every worker warm
                out["runs"][f"{k}w"] = _timed_run(config, f"sqlite:///{tmp / f'w{k}.db'}", DaskExecutor(client))
    out["load_after"] = [round(v, 2) for v in os.getloadavg()]
    runs = out["runs"]
    if "1w" in runs and "2w" in runs:
        out["ratio_2w_over_1w"] = runs["2w"]["pairs_per_s"] / runs["1w"]["pairs_per_s"]
    if "1w" in runs:
        per_core = runs["1w"]["pairs_per_s"]
        write_rate = runs["1w"]["pairs"] / max(runs["1w"]["store_s"], 1e-9)
        out["projection"] = {
            "per_worker_pairs_per_s": per_core,
            "client_write_pairs_per_s": write_rate,
            "core_hours_for_10M": TARGET_PAIRS / per_core / 3600,
            "workers_for_1_hour": TARGET_PAIRS / per_core / 3600,
            "hours_on": {w: TARGET_PAIRS / (per_core * w) / 3600 for w in (16, 64, 256)},
            "hours_at_client_write_ceiling": TARGET_PAIRS / write_rate / 3600,
        }
    if args.json:
        print(json.dumps(out))
        return
    print(
        f"{args.n} maps of {args.size}x{args.size}, {args.attack}, shards of {args.shard_size}; "
        f"{out['cores']} cores, load average before {load_before[0]:.2f}, after {out['load_after'][0]:.2f}"
    )
    print(f"{'':<10}{'pairs':>8}{'wall s':>9}{'pairs/s':>10}{'store s':>9}")
    for name, r in runs.items():
        print(f"{name:<10}{r['pairs']:>8}{r['wall_s']:>9.2f}{r['pairs_per_s']:>10.1f}{r['store_s']:>9.2f}")
    if "ratio_2w_over_1w" in out:
        print(f"2 workers / 1 worker: {out['ratio_2w_over_1w']:.2f}x (ideal 2.00x)")
    if "projection" in out:
        p = out["projection"]
        print(
            f"10M pairs at {p['per_worker_pairs_per_s']:.0f} pairs/s per worker: {p['core_hours_for_10M']:.1f} "
            f"worker-hours; "
            + ", ".join(f"{w} workers {h:.2f} h" for w, h in p["hours_on"].items())
            + f"; one client writes SQLite at {p['client_write_pairs_per_s']:.0f} pairs/s "
            f"(>= {p['hours_at_client_write_ceiling']:.2f} h for 10M)"
        )


if __name__ == "__main__":
    main()
