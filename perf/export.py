"""Export of a stored run: Parquet beside CSV, time and size, measured side by side in one run.

    .venv/bin/python perf/export.py [--n 100000] [--size 28] [--max-path 60] [--repeat 3] [--json]

Stores --n random pairs (`vinadv.testing.store.random_records`: --size maps, paths of up to --max-path cells,
NULLs in the nullable columns) as one run in a fresh SQLite file (untimed), then times `vinadv export` of that run
(the command in this process, `--quiet`) as CSV and as Parquet, and reading each file back into a pandas DataFrame
(`pandas.read_csv`; the Parquet file both with `pandas.read_parquet`, which makes the list columns NumPy object
arrays, and with `vinadv.analysis.read_parquet`, which keeps them as Arrow arrays). Prints the best of --repeat
trials, wall clock and this process's CPU time (which other load on the machine hardly changes; the header gives the
load average), the file sizes and the ratios Parquet / CSV.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

from vinadv.analysis import read_parquet
from vinadv.cli import main as vinadv_main
from vinadv.store import Store
from vinadv.testing.store import random_records

#: pairs generated and written at a time while the run is stored (bounded memory for any --n)
WRITE_CHUNK = 20_000


def best(fn, repeat: int) -> tuple[float, float]:
    """(least wall-clock seconds, least process CPU seconds) of `repeat` calls of `fn()`."""
    wall = cpu = float("inf")
    for _ in range(repeat):
        start, start_cpu = time.perf_counter(), time.process_time()
        fn()
        wall = min(wall, time.perf_counter() - start)
        cpu = min(cpu, time.process_time() - start_cpu)
    return wall, cpu


def store_run(url: str, n: int, size: int, max_path: int) -> int:
    """Store `n` random pairs as one run of the database at `url`; its id."""
    with Store.open(url) as store:
        run_id = store.create_run("bench", config={"n": n, "size": size, "max_path": max_path})
        for lo in range(0, n, WRITE_CHUNK):
            count = min(WRITE_CHUNK, n - lo)
            store.write_pairs(run_id, random_records(count, size=size, seed=lo, max_path=max_path, first_index=lo))
        store.finish_run(run_id)
    return run_id


def measure(n: int, size: int, max_path: int, repeat: int, folder: Path) -> dict:
    """Export and read-back figures of CSV and Parquet (see the module doc)."""
    url = f"sqlite:///{folder / 'bench.db'}"
    t0 = time.perf_counter()
    run_id = store_run(url, n, size, max_path)
    stored_s = time.perf_counter() - t0
    result = {"n": n, "size": size, "max_path": max_path, "repeat": repeat, "store_seconds": round(stored_s, 2)}
    for fmt in ("csv", "parquet"):
        out = folder / f"pairs.{fmt}"
        argv = ["export", "--db", url, "--run", str(run_id), "--format", fmt, "--out", str(out), "--quiet"]

        def export(argv=argv) -> None:
            if vinadv_main(argv) != 0:
                raise SystemExit(f"vinadv {' '.join(argv)} failed")

        wall, cpu = best(export, repeat)
        reader = pd.read_csv if fmt == "csv" else pd.read_parquet
        read_wall, read_cpu = best(lambda out=out, reader=reader: reader(out), repeat)
        result[fmt] = {
            "export_s": wall,
            "export_cpu_s": cpu,
            "pairs_per_s": n / wall,
            "bytes": out.stat().st_size,
            "read_s": read_wall,
            "read_cpu_s": read_cpu,
        }
    arrow_wall, arrow_cpu = best(lambda: read_parquet(folder / "pairs.parquet"), repeat)
    result["parquet"].update(read_arrow_lists_s=arrow_wall, read_arrow_lists_cpu_s=arrow_cpu)
    csv, parquet = result["csv"], result["parquet"]
    result["ratios"] = {
        "export_time": parquet["export_s"] / csv["export_s"],
        "export_cpu": parquet["export_cpu_s"] / csv["export_cpu_s"],
        "size": parquet["bytes"] / csv["bytes"],
        "read_time": parquet["read_s"] / csv["read_s"],
        "read_time_arrow_lists": parquet["read_arrow_lists_s"] / csv["read_s"],
    }
    return result


def report(result: dict) -> None:
    n = result["n"]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"export of {n:,} pairs ({result['size']}x{result['size']} maps, paths <= {result['max_path']} cells), "
        f"best of {result['repeat']}; load average {load:.2f} on {os.cpu_count()} CPUs"
    )
    print(f"  (storing the run: {result['store_seconds']:.1f} s, untimed)")
    print(f"  {'':8} {'export s':>9} {'cpu s':>7} {'pairs/s':>9} {'MB':>8} {'B/pair':>7} {'pandas read s':>14}")
    print(f"  {'':8} {'':>9} {'':>7} {'':>9} {'':>8} {'':>7} {'(pd.read_*)':>14}")
    for fmt in ("csv", "parquet"):
        r = result[fmt]
        print(
            f"  {fmt:8} {r['export_s']:9.2f} {r['export_cpu_s']:7.2f} {r['pairs_per_s']:9,.0f} "
            f"{r['bytes'] / 1e6:8.1f} {r['bytes'] / n:7.0f} {r['read_s']:14.2f}"
        )
    ratios = result["ratios"]
    print(
        f"  parquet / csv: export time {ratios['export_time']:.2f}x (cpu {ratios['export_cpu']:.2f}x), "
        f"size {ratios['size']:.3f}x, pandas read time {ratios['read_time']:.2f}x"
    )
    print(
        f"  vinadv.analysis.read_parquet (list columns as Arrow): {result['parquet']['read_arrow_lists_s']:.2f} s, "
        f"{ratios['read_time_arrow_lists']:.2f}x pandas.read_csv"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=100_000, help="pairs in the run")
    parser.add_argument("--size", type=int, default=28, help="map size N")
    parser.add_argument("--max-path", type=int, default=60, help="longest random path, in cells")
    parser.add_argument("--repeat", type=int, default=3, help="trials of each measurement (the best is kept)")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="vinadv-bench-export-") as folder:
        result = measure(args.n, args.size, args.max_path, args.repeat, Path(folder))
    if args.json:
        print(json.dumps(result))
    else:
        report(result)
    return 0


if __name__ == "__main__":
    sys.exit(main())
