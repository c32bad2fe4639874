"""Draw the pictures of docs/guide/real-maps.md from the real Moving AI files, with `vinadv.plot`:

    PYTHONPATH=src python docs/gen_movingai_figures.py --data ../shared/data/movingai --out docs/guide/img

- `movingai-crops.png`: the first crop of each city map and the first problem on each 64x64 MAPF map of the suite
  `movingai64-quick-v1`, with the start, the goal and the shortest path (octile, no corner cutting);
- `movingai-attacked.png`: the two most harmful pairs the key-points attack (one added cell, the most harmful of its
  candidates kept, as the suites keep it) makes against weighted A* (`wastar:w=2`) on the suite's city crops;
- `movingai-one-obstacle.png`: on a city crop, the one cell of the shortest path whose blocking lengthens the
  shortest path most, with both shortest paths: what one obstacle does to a street.

Deterministic (seeded suite maps and attack); one CPU thread, a few seconds.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np


def _name(maps, i: int) -> str:
    r, c = (int(v) for v in maps.origin[i])
    return f"{Path(str(maps.source[i])).stem} ({r}, {c})"


def crops(maps, out: Path) -> None:
    import matplotlib.pyplot as plt  # noqa: PLC0415 (matplotlib only when drawing)

    import vinadv.plot  # noqa: PLC0415

    picks = [int(np.flatnonzero(maps.source == name)[0]) for name in dict.fromkeys(maps.source.tolist())]
    fig, axes = plt.subplots(2, 4, figsize=(11, 6), layout="constrained")
    for ax, i in zip(axes.ravel(), picks):
        path = maps.expert[int(i) * maps.n_starts]
        vinadv.plot.draw_map(
            ax, maps.obstacles[i], maps.goals[i], maps.starts[i, 0], [("expert", path)], title=_name(maps, i)
        )
    axes.ravel()[-1].axis("off")
    vinadv.plot.map_legend(fig, axes.ravel()[: len(picks)])
    vinadv.plot.save_figure(fig, out / "movingai-crops.png")


def attacked(maps, out: Path) -> None:
    import matplotlib.pyplot as plt  # noqa: PLC0415

    import vinadv.plot  # noqa: PLC0415
    from vinadv.attacks.strategies import make_attack  # noqa: PLC0415
    from vinadv.identify import identify, objective_strength  # noqa: PLC0415
    from vinadv.planners.registry import load_planner  # noqa: PLC0415

    city = np.flatnonzero(np.char.find(maps.source.astype(str), "256") >= 0)
    planner = load_planner("wastar:w=2", maps.size, corner_cutting=False, moves=maps.moves)
    result = make_attack("key-points", per_map=1, seed=0, budget=8, obstacles=1).attack(
        maps.obstacles[city], maps.starts[city, 0], maps.goals[city], planner, False, objective_strength("harm")
    )
    pairs = result.pairs
    expert = (maps.expert_costs[city[pairs.map_index], 0], maps.expert.take(city[pairs.map_index] * maps.n_starts))
    ident = identify(pairs, expert_o=expert)
    # the two most harmful: the largest growth of the regret (a detour that costs the most over the new optimum)
    growth = np.where(np.asarray(ident.harm.harm) == "harmful", ident.harm.regret_a - ident.harm.regret_o, -np.inf)
    harmful = np.argsort(-growth, kind="stable")[:2]
    fig, axes = plt.subplots(2, 2, figsize=(7.5, 8), layout="constrained")
    for row, j in zip(axes, harmful):
        i = int(city[pairs.map_index[j]])
        vinadv.plot.draw_pair(row, vinadv.plot.as_pair(pairs, int(j)))
        row[0].set_title(f"{_name(maps, i)}: wastar:w=2", fontsize=9)
        row[1].set_title(f"one cell added: {ident.labels[j]}, regret +{growth[j]:.2f}", fontsize=9)
    vinadv.plot.map_legend(fig, axes.ravel())
    vinadv.plot.save_figure(fig, out / "movingai-attacked.png")


def one_obstacle(maps, out: Path) -> None:
    """Every cell of each city crop's shortest path blocked in turn (one batch of Dijkstras per crop); the crop and
    cell that lengthen the path most, as a pair of the optimal planner's paths."""
    import matplotlib.pyplot as plt  # noqa: PLC0415

    import vinadv.plot  # noqa: PLC0415
    from vinadv.grid.shortest_paths import shortest_distances  # noqa: PLC0415
    from vinadv.planners.registry import load_planner  # noqa: PLC0415

    best = (-1.0, 0, None)
    for i in np.flatnonzero(np.char.find(maps.source.astype(str), "256") >= 0):
        path = maps.expert[int(i) * maps.n_starts][1:-1]  # not the start or the goal
        blocked = np.repeat(maps.obstacles[i][None], len(path), axis=0)
        blocked[np.arange(len(path)), path[:, 0], path[:, 1]] = True
        goals = np.repeat(maps.goals[i][None], len(path), axis=0)
        dist, _ = shortest_distances(blocked, goals, False, maps.moves)
        cost = dist[:, maps.starts[i, 0, 0], maps.starts[i, 0, 1]]
        gain = np.where(np.isfinite(cost), cost - maps.expert_costs[i, 0], -1.0)
        j = int(np.argmax(gain))
        if gain[j] > best[0]:
            best = (float(gain[j]), int(i), path[j])
    gain, i, cell = best
    edited = maps.obstacles[i].copy()
    edited[cell[0], cell[1]] = True
    planner = load_planner("optimal", maps.size, corner_cutting=False, moves=maps.moves)
    both = np.stack([maps.obstacles[i], edited])
    plans = planner.plan(
        both, np.repeat(maps.starts[i, :1], 2, axis=0), np.repeat(maps.goals[i][None], 2, axis=0), False
    )
    pair = vinadv.plot.Pair(
        obstacles_o=both[0],
        obstacles_a=both[1],
        start=maps.starts[i, 0],
        goal=maps.goals[i],
        added=cell[None],
        removed=False,
        path_o=plans.paths[0],
        path_a=plans.paths[1],
    )
    fig, axes = plt.subplots(1, 2, figsize=(7, 4), layout="constrained")
    vinadv.plot.draw_pair(axes, pair, titles=("a street crop: the shortest path", "one cell blocked: the detour"))
    fig.suptitle(f"{_name(maps, i)}: one obstacle lengthens the shortest path by {gain:.1f}", fontsize=10)
    vinadv.plot.map_legend(fig, axes)
    vinadv.plot.save_figure(fig, out / "movingai-one-obstacle.png")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default="../shared/data/movingai", help="the folder of the Moving AI files")
    parser.add_argument("--out", default="docs/guide/img", help="the folder the PNGs go to")
    args = parser.parse_args()
    import matplotlib  # noqa: PLC0415 (the script's heavy imports: after the arguments)

    matplotlib.use("Agg")
    import torch  # noqa: PLC0415

    from vinadv.bench.scoring import suite_maps  # noqa: PLC0415
    from vinadv.bench.suites import get_suite  # noqa: PLC0415

    torch.set_num_threads(1)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    maps = suite_maps(get_suite("movingai64-quick-v1"), args.data)
    crops(maps, out)
    attacked(maps, out)
    one_obstacle(maps, out)
    for f in sorted(out.glob("movingai-*.png")):
        print(f, f.stat().st_size, "bytes")


if __name__ == "__main__":
    main()
