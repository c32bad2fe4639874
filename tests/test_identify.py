"""`vinadv.identify`: the harm objective of the ranking attacks (`--objective harm`)."""

import math

import numpy as np
import pytest

from tests.classify.oracle import rule_oracle
from tests.classify.test_harm import optimal_path, path_cost
from vinadv.attacks.strategies import make_attack
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid.generator import generate_maps
from vinadv.identify import objective_strength
from vinadv.planners.vin.reference import plan_reference
from vinadv.store import Store
from vinadv.testing.planners import planning_vin

SIZE = 10


@pytest.mark.slow  # over a second: the quick tier keeps the module's other tests
def test_exhaustive_with_the_harm_objective_keeps_the_most_harmful_cell_of_a_brute_force_search():
    model = planning_vin(SIZE, seed=1, noise=0.1)
    maps = generate_maps(6, SIZE, seed=3, n_starts=1)
    result = make_attack("exhaustive").attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, model, strength=objective_strength("harm")
    )
    for i in range(len(maps.obstacles)):
        obstacles, start, goal = maps.obstacles[i], tuple(maps.starts[i, 0]), tuple(maps.goals[i])
        original = plan_reference(obstacles[None], np.array([start]), np.array([goal]), model).paths.cells.tolist()
        strengths = {}
        for r in range(SIZE):  # every cell, the slow way: independent of the attack and harm code
            for c in range(SIZE):
                if obstacles[r, c] or (r, c) in (start, goal):
                    continue
                adv = obstacles.copy()
                adv[r, c] = True
                expert = optimal_path(adv.tolist(), start, goal, True)
                if expert is None:
                    continue  # not a valid cell: the goal must stay reachable
                path = plan_reference(adv[None], np.array([start]), np.array([goal]), model).paths.cells.tolist()
                label = rule_oracle(original, path, goal, round(4 * SIZE / 28))[0]
                if label == "UrP":
                    strengths[(r, c)] = math.inf
                elif label == "invalid":
                    strengths[(r, c)] = -math.inf
                else:
                    strengths[(r, c)] = path_cost(path) - path_cost(expert)
        kept = np.flatnonzero(result.pairs.map_index == i)
        assert len(kept) == 1
        best = max(strengths.values())
        got = strengths[tuple(result.pairs.added[kept[0], 0])]
        assert got == best or abs(got - best) < 1e-9


def test_unknown_objective_is_refused():
    with pytest.raises(InputError, match="objective"):
        objective_strength("fastest")


@pytest.mark.parametrize("moves", ["moore", "news"])
def test_identify_stores_the_pairs_movement_model_and_its_harm(moves, tmp_path):
    """A pairs file of `moore` or `news` maps is stored as a run of that model (`runs.moves`); its optimal costs are
    a plain Dijkstra's of the model (tests.classify.test_harm), so a diagonal move costs 1 on moore maps."""
    maps, pairs, db = tmp_path / "m.npz", tmp_path / "p.npz", f"sqlite:///{tmp_path / 'v.db'}"
    generate_maps(5, 9, seed=4, n_starts=1, moves=moves).save(maps)
    attack = ["attack", "--maps", str(maps), "--planner", "optimal", "--strategy", "random", "--per-map", "2"]
    assert main([*attack, "--out", str(pairs), "--quiet"]) == 0
    assert main(["identify", "--pairs", str(pairs), "--db", db, "--quiet"]) == 0
    with Store.open(db) as store:
        run_id = store.list_runs()[-1]["id"]
        assert store.run_moves(run_id) == moves
        records = store.read_pairs(run_id)
    assert len(records) and set(records.harm) <= {"harmless", "invalid"}
    for i in range(len(records)):
        expert = optimal_path(
            records.obstacles_a[i].tolist(), tuple(records.starts[i]), tuple(records.goals[i]), True, moves
        )
        assert records.opt_cost_a[i] == pytest.approx(path_cost(expert, moves), abs=1e-9)
