"""Search effort through the attacks: a search planner's pairs carry both searches' expanded cells and A*'s counts
(checked against fresh plans of the pairs' maps), the pairs file keeps them (`vinadv.pairs/4`, older files read
without), and `--objective effort` keeps, per map, the candidate whose search expands the most cells."""

from __future__ import annotations

import numpy as np
import pytest

from vinadv.attacks.pairs import PairSet
from vinadv.attacks.strategies import make_attack
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.identify import objective_strength, replan
from vinadv.planners.classical.astar import AStarPlanner, WeightedAStarPlanner


@pytest.fixture(scope="module")
def maps():
    return generate_maps(6, 9, seed=4, n_starts=1)


def attack(planner, maps, objective="harm", per_map=1):
    return make_attack("exhaustive", per_map=per_map, seed=0).attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, planner, True, strength=objective_strength(objective)
    )


def masks(planner, obstacles, pairs):
    return planner.plan(obstacles, pairs.starts, pairs.goals, pairs.corner_cutting, pairs.moves).expanded


def test_pairs_carry_both_searches_and_a_stars_counts(maps, tmp_path):
    planner = WeightedAStarPlanner(9, w=3.0)
    pairs = attack(planner, maps).pairs
    for side in ("o", "a"):
        obstacles = getattr(pairs, f"obstacles_{side}")
        expected = masks(planner, obstacles, pairs)
        got = np.zeros_like(expected)
        cells = getattr(pairs, f"expanded_{side}")
        got[cells.owners(), cells.cells[:, 0], cells.cells[:, 1]] = True
        assert (got == expected).all() and (cells.lengths == expected.sum(axis=(1, 2))).all()
        astar = masks(AStarPlanner(9), obstacles, pairs).sum(axis=(1, 2))
        assert (getattr(pairs, f"astar_expansions_{side}") == astar).all()
    path = tmp_path / "p.npz"
    pairs.save(path)
    back = PairSet.load(path)
    assert back.expanded_a == pairs.expanded_a and (back.astar_expansions_o == pairs.astar_expansions_o).all()
    # a file without the fields (vinadv.pairs/3 and older, or a planner without expansions) reads without them
    with np.load(path) as z:
        fields = {k: z[k] for k in z.files}
    old = {k: v for k, v in fields.items() if "expan" not in k}
    np.savez(tmp_path / "old.npz", **{**old, "format": np.array("vinadv.pairs/3")})
    assert PairSet.load(tmp_path / "old.npz").expanded_o is None
    fields.pop("astar_expansions_a")
    np.savez(tmp_path / "cut.npz", **fields)
    with pytest.raises(InputError, match="astar_expansions_a"):
        PairSet.load(tmp_path / "cut.npz")


def test_replanned_pairs_get_the_new_planners_expansions(maps):
    pairs = attack(AStarPlanner(9), maps).pairs
    again = replan(pairs, WeightedAStarPlanner(9, w=4.0))
    assert (again.astar_expansions_a == pairs.astar_expansions_a).all()  # A*'s: the maps' own
    assert (again.expansions_a == masks(WeightedAStarPlanner(9, w=4.0), pairs.obstacles_a, pairs).sum((1, 2))).all()
    assert (pairs.expansions_a == pairs.astar_expansions_a).all()  # A* is its own reference


def test_objective_effort_keeps_the_candidate_that_expands_the_most(maps):
    planner = AStarPlanner(9)
    every = attack(planner, maps, per_map=0).pairs  # every valid cell of every map
    kept = attack(planner, maps, "effort").pairs
    for i, m in enumerate(kept.map_index):
        candidates = every.expansions_a[every.map_index == m]
        assert kept.expansions_a[i] == candidates.max()
    with pytest.raises(InputError, match="reports no expansions"):
        from vinadv.planners.classical.optimal import OptimalPlanner  # noqa: PLC0415

        attack(OptimalPlanner(9), maps, "effort")
