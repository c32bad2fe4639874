"""The attack call the job tests compare against: `attack_maps` itself, on the optimal planner."""

from __future__ import annotations

from vinadv.attacks.strategies import AttackResult
from vinadv.grid.mapset import MapSet
from vinadv.jobs.attack import attack_maps
from vinadv.planners.registry import load_planner


def random_attack_on_optimal(maps: MapSet, seed: int, per_map: int = 2) -> AttackResult:
    """The random strategy's pairs (`per_map` per map, one added obstacle, `seed`) on the first start of each of
    `maps`, planned by the optimal planner."""
    return attack_maps(
        "random",
        dict(per_map=per_map, seed=seed, budget=8, radius=2, obstacles=1, edit="add"),
        maps.obstacles,
        maps.starts[:, 0],
        maps.goals,
        load_planner("optimal", maps.size),
        maps.corner_cutting,
    )
