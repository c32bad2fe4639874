"""Dataset generation speed: maps + expert data (7 starts per map) per second, and where the time goes.

    .venv/bin/python perf/grid.py [--n 5000] [--size 28]

Target (issue 2): >= 1,000 maps/s at 28x28 on the 2-core machine.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from vinadv.grid import expert_paths, generate_maps, shortest_distances
from vinadv.grid.selection import smallest_first


def best_of(fn, repeat: int = 3) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=5000)
    parser.add_argument("--size", type=int, default=28)
    args = parser.parse_args()
    generate_maps(64, args.size, seed=1)  # compile / load the Numba kernels outside the timing
    maps = generate_maps(args.n, args.size, seed=0)

    t_total = best_of(lambda: generate_maps(args.n, args.size, seed=0))
    t_dijkstra = best_of(lambda: shortest_distances(maps.obstacles, maps.goals))
    t_expert = best_of(lambda: expert_paths(maps.obstacles, maps.goals, maps.starts))
    rate = args.n / t_total
    print(f"maps {args.n} of {args.size}x{args.size}, 7 starts each (best of 3)")
    print(
        f"  whole generation (maps + Dijkstra + expert paths): {rate:10,.0f} maps/s   target >= 1,000: "
        f"{'met' if rate >= 1000 else 'MISSED'} ({rate / 1000:.1f}x)"
    )
    print(f"  Dijkstra alone (all cells, all maps):               {args.n / t_dijkstra:10,.0f} maps/s")
    print(f"  expert paths (Dijkstra + 7 trajectories):           {args.n / t_expert:10,.0f} maps/s")
    print(f"  share of generation spent in expert paths:          {t_expert / t_total:10.0%}")
    print(f"  mean expert path: {maps.expert.lengths.mean() - 1:.1f} moves")
    # the starts' draw: the k smallest random keys of each map's cells, as a full sort would give them
    keys = np.random.default_rng(0).random((args.n, args.size * args.size))
    for k in (1, 7):
        smallest_first(keys[:8], k)  # compile / load outside the timing
        t_sel = best_of(lambda k=k: smallest_first(keys, k))
        t_sort = best_of(lambda k=k: np.argsort(keys, axis=1, kind="stable")[:, :k])
        print(
            f"  {k} start(s) a map: smallest_first {t_sel * 1e3:6.1f} ms, stable argsort {t_sort * 1e3:6.1f} ms "
            f"({t_sel / t_sort:.3f}x)"
        )


if __name__ == "__main__":
    main()
