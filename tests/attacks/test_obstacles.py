"""Several added obstacles (DESIGN.md "Several obstacles"): the K-obstacle validity rule against brute force
(hypothesis), the greedy steps against a brute-force search, and what the pairs file keeps."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.fault_files import read_npz, rewrite_npz
from tests.grid.oracle import MOVES, brute_distances, reachable
from vinadv.attacks.pairs import PairSet
from vinadv.attacks.strategies import STRATEGIES, make_attack
from vinadv.attacks.validity import valid_additions, valid_cells
from vinadv.classify import label_pairs
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.identify import harm_strength, rule_strength
from vinadv.planners.registry import load_planner
from vinadv.planners.vin.reference import plan_reference
from vinadv.testing.planners import planning_vin
from vinadv.vocabulary import LABEL_STRENGTH

SIZE = 8


@pytest.fixture(scope="module")
def maps():
    return generate_maps(24, SIZE, seed=5, n_starts=1)


def oracle_valid(obstacles, start, goal, cells, moves="octile") -> bool:
    """DESIGN.md's rule, cell by cell in plain Python: K distinct free cells, none the start or the goal, the goal
    reachable from the start with all K added."""
    cells = [tuple(c) for c in cells]
    n = len(obstacles)
    if len(set(cells)) != len(cells) or any(not (0 <= r < n and 0 <= c < n) for r, c in cells):
        return False
    if any(obstacles[r][c] or (r, c) in (tuple(start), tuple(goal)) for r, c in cells):
        return False
    blocked = np.array(obstacles, dtype=bool)
    for r, c in cells:
        blocked[r, c] = True
    return reachable(blocked, start, goal, moves=moves)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10**6), k=st.integers(1, 5), data=st.data(), moves=st.sampled_from(MOVES))
def test_valid_additions_is_the_rule(seed, k, data, moves):
    maps = generate_maps(1, SIZE, seed=seed, n_starts=1, moves=moves)
    obstacles, start, goal = maps.obstacles[0], maps.starts[0, 0], maps.goals[0]
    free = [tuple(c) for c in np.argwhere(~obstacles).tolist()]
    # mostly free cells (the interesting case), sometimes any cell of the grid, repeats allowed
    cell = st.one_of(st.sampled_from(free), st.tuples(st.integers(0, SIZE - 1), st.integers(0, SIZE - 1)))
    cells = data.draw(st.lists(cell, min_size=k, max_size=k))
    got = valid_additions(obstacles[None], start[None], goal[None], np.array([cells]), moves=moves)
    assert bool(got[0]) == oracle_valid(obstacles, start, goal, cells, moves)


@pytest.mark.slow
@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 10**6), k=st.integers(1, 4), name=st.sampled_from(sorted(STRATEGIES)), per_map=st.integers(1, 2)
)
def test_every_k_obstacle_pair_keeps_the_rules(seed, k, name, per_map):
    maps = generate_maps(6, SIZE, seed=seed, n_starts=1)
    model = planning_vin(SIZE, seed=seed % 7, noise=0.2)
    result = make_attack(name, per_map=per_map, seed=seed, budget=3, obstacles=k).attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, model, strength=rule_strength
    )
    pairs = result.pairs
    assert pairs.added.shape == (len(pairs), k, 2) and len(result.steps) == k
    assert set(pairs.map_index.tolist()).isdisjoint(result.no_valid_cell.tolist())
    for i in range(len(pairs)):
        m = pairs.map_index[i]
        assert np.array_equal(pairs.obstacles_o[i], maps.obstacles[m])
        assert oracle_valid(maps.obstacles[m], maps.starts[m, 0], maps.goals[m], pairs.added[i])
        expected = maps.obstacles[m].copy()
        expected[tuple(pairs.added[i].T)] = True
        assert np.array_equal(pairs.obstacles_a[i], expected)
    assert valid_additions(pairs.obstacles_o, pairs.starts, pairs.goals, pairs.added).all()
    # the maps left out really had no valid cell at some step: a map with no pair at step k had none left (for the
    # strategies that score every cell; key-points and near-path score only cells near the path: no candidate there)
    for step, kept in enumerate(result.steps if name in ("random", "saliency", "exhaustive") else []):
        for m in sorted(set(range(len(maps))) - set(kept.map_index.tolist())):
            before = result.steps[step - 1] if step else None
            if before is not None and m not in before.map_index:
                continue
            current = maps.obstacles[m].copy()
            if before is not None:
                current[tuple(before.added[np.flatnonzero(before.map_index == m)[0]].T)] = True
            assert not valid_cells(current[None], maps.starts[m], maps.goals[m][None]).any()


def _brute_greedy(model, obstacles, start, goal, k, strength_of):
    """The greedy choice the slow way: at each step every cell of the grid, in row-major order, tried on the map with
    the cells chosen so far; the pair judged against the ORIGINAL map's path; the first strongest kept. With the
    chosen cells (None where a step has no valid cell), the strongest value of each step and whether some step's
    strongest cell came after a weaker valid one (a search that took the first valid cell would differ)."""
    original = plan_reference(obstacles[None], start[None], goal[None], model)
    chosen, current, strongest, beat_first = [], obstacles.copy(), [], False
    for _ in range(k):
        best = first = None
        for r in range(SIZE):
            for c in range(SIZE):
                cells = [*chosen, (r, c)]
                if not oracle_valid(obstacles, start, goal, cells):
                    continue
                adv = current.copy()
                adv[r, c] = True
                planned = plan_reference(adv[None], start[None], goal[None], model)
                value = strength_of(obstacles, adv, start, goal, original, planned)
                first = value if first is None else first
                if best is None or value > best[0]:
                    best = (value, (r, c))
        if best is None:
            return None, strongest, beat_first
        chosen.append(best[1])
        current[best[1]] = True
        strongest.append(best[0])
        beat_first |= best[0] > first
    return chosen, strongest, beat_first


def _label_strength(obstacles, adv, start, goal, original, planned):
    return LABEL_STRENGTH[label_pairs(original.paths, planned.paths, goal[None], SIZE).labels[0]]


def _harm_value(obstacles, adv, start, goal, original, planned):
    """UrP strongest, then the adversarial path's regret (its cost over the optimum on the adversarial map)."""
    label = label_pairs(original.paths, planned.paths, goal[None], SIZE).labels[0]
    if label in ("UrP", "invalid"):
        return math.inf if label == "UrP" else -math.inf
    path = planned.paths[0].tolist()
    cost = sum(math.sqrt(2) if a[0] != b[0] and a[1] != b[1] else 1.0 for a, b in zip(path, path[1:]))
    optimum = brute_distances(adv.tolist(), tuple(goal))[tuple(start)][0]
    return round(cost - optimum, 9)


#: the maps of the brute-force search (a planner call per cell and step): four of the module's, where for both
#: objectives some step's strongest cell comes after weaker valid ones and some map is harmed (UrP); most maps of
#: this planner keep the first valid cell under the harm objective, every cell as strong as the next
GREEDY_MAPS = [7, 17, 18, 20]


@pytest.mark.slow
@pytest.mark.parametrize("objective", ["paper", "harm"])
def test_greedy_steps_pick_the_strongest_cell_of_a_brute_force_search(model, maps, objective):
    k = 3
    strength, oracle = (rule_strength, _label_strength) if objective == "paper" else (harm_strength, _harm_value)
    urp = LABEL_STRENGTH["UrP"] if objective == "paper" else math.inf
    chosen = maps.take(GREEDY_MAPS)
    result = make_attack("exhaustive", obstacles=k).attack(
        chosen.obstacles, chosen.starts[:, 0], chosen.goals, model, strength=strength
    )
    beaten, harmed = [], []
    for i in range(len(GREEDY_MAPS)):
        expected, strongest, beat_first = _brute_greedy(
            model, chosen.obstacles[i], chosen.starts[i, 0], chosen.goals[i], k, oracle
        )
        beaten.append(beat_first)
        harmed.append(urp in strongest)
        got = np.flatnonzero(result.pairs.map_index == i)
        if expected is None:
            assert len(got) == 0 and i in result.no_valid_cell
            continue
        assert len(got) == 1
        assert [tuple(c) for c in result.pairs.added[got[0]].tolist()] == expected, i
    assert any(beaten) and any(harmed)  # the maps tell the strongest cell from the first, and harm some


@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_the_steps_of_k_obstacles_are_the_attacks_of_fewer(name, model, maps):
    full = make_attack(name, seed=3, budget=4, obstacles=3).attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, model, strength=rule_strength
    )
    for k in (1, 2, 3):
        alone = (
            make_attack(name, seed=3, budget=4, obstacles=k)
            .attack(maps.obstacles, maps.starts[:, 0], maps.goals, model, strength=rule_strength)
            .pairs
        )
        step = full.steps[k - 1]
        assert np.array_equal(step.added, alone.added) and np.array_equal(step.map_index, alone.map_index)
        assert step.path_a == alone.path_a and step.path_o == alone.path_o


@pytest.mark.parametrize("name", ["random", "near-path", "key-points"])
def test_shards_attack_as_the_whole_batch(name, model, maps):
    whole = make_attack(name, seed=9, obstacles=2).attack(maps.obstacles, maps.starts[:, 0], maps.goals, model)
    parts = [
        make_attack(name, seed=9, obstacles=2)
        .attack(
            maps.obstacles[lo : lo + 10], maps.starts[lo : lo + 10, 0], maps.goals[lo : lo + 10], model, first_map=lo
        )
        .pairs
        for lo in (0, 10, 20)
    ]
    for lo, part in zip((0, 10, 20), parts):
        sel = (whole.pairs.map_index >= lo) & (whole.pairs.map_index < lo + 10)
        assert np.array_equal(part.added, whole.pairs.added[sel])
        assert np.array_equal(part.map_index + lo, whole.pairs.map_index[sel])


def test_per_map_keeps_several_pairs_at_the_last_step_only(model, maps):
    result = make_attack("exhaustive", per_map=0, obstacles=2).attack(
        maps.obstacles[:4], maps.starts[:4, 0], maps.goals[:4], model
    )
    first = result.steps[0]
    assert np.bincount(first.map_index).max() == 1
    for i in range(4):
        rows = np.flatnonzero(result.pairs.map_index == i)
        # every valid second cell, all after the same first one
        current = maps.obstacles[i].copy()
        current[tuple(first.added[first.map_index == i][0, 0])] = True
        assert len(rows) == valid_cells(current[None], maps.starts[i, :1], maps.goals[i][None]).sum()
        assert (result.pairs.added[rows, 0] == first.added[first.map_index == i][0, 0]).all()


def test_pairs_files_of_k_obstacles_round_trip_and_one_obstacle_files_stay_as_before(model, maps, tmp_path):
    three = make_attack("key-points", obstacles=3).attack(maps.obstacles, maps.starts[:, 0], maps.goals, model).pairs
    three.save(tmp_path / "three.npz")
    back = PairSet.load(tmp_path / "three.npz")
    assert np.array_equal(back.added, three.added) and back.added.shape[1:] == (3, 2)
    assert read_npz(tmp_path / "three.npz")["added"].shape == (len(three), 3, 2)
    assert back.params["obstacles"] == 3
    one = make_attack("key-points").attack(maps.obstacles, maps.starts[:, 0], maps.goals, model).pairs
    one.save(tmp_path / "one.npz")
    assert read_npz(tmp_path / "one.npz")["added"].shape == (len(one), 2)  # as every vinadv wrote and reads it
    assert np.array_equal(PairSet.load(tmp_path / "one.npz").added, one.added)


@pytest.mark.parametrize(
    "fault, field, message",
    [
        ("twice", "added", "the same cell twice"),
        ("start", "added", "is on the start"),
        ("missing", "obstacles_a", "exactly the cells 'added'"),
        ("obstacle", "added", "already an obstacle"),
    ],
)
def test_k_obstacle_pairs_files_are_checked(model, maps, tmp_path, fault, field, message):
    pairs = (
        make_attack("random", obstacles=3, seed=2).attack(maps.obstacles, maps.starts[:, 0], maps.goals, model).pairs
    )
    pairs.save(tmp_path / "p.npz")
    a = read_npz(tmp_path / "p.npz")
    added, obs_a, obs_o = a["added"].copy(), a["obstacles_a"].copy(), a["obstacles_o"].copy()
    k = 2
    if fault == "twice":
        obs_a[k, added[k, 2, 0], added[k, 2, 1]] = False
        added[k, 2] = added[k, 1]
    elif fault == "start":
        obs_a[k, added[k, 0, 0], added[k, 0, 1]] = False
        added[k, 0] = a["starts"][k]
        obs_a[k, added[k, 0, 0], added[k, 0, 1]] = True
    elif fault == "missing":
        obs_a[k, added[k, 1, 0], added[k, 1, 1]] = False
    else:
        obs_o[k, added[k, 1, 0], added[k, 1, 1]] = True
    bad = rewrite_npz(tmp_path / "p.npz", tmp_path / "bad.npz", added=added, obstacles_a=obs_a, obstacles_o=obs_o)
    with pytest.raises(InputError) as err:
        PairSet.load(bad)
    assert f"field '{field}'" in str(err.value) and message in str(err.value) and f"pair {k}" in str(err.value)


def test_bad_obstacle_count_is_refused():
    with pytest.raises(InputError, match="^obstacles must be >= 1") as err:
        make_attack("random", obstacles=0)
    assert err.value.parameters == ("obstacles",)


@pytest.mark.parametrize("edit", ["add", "remove"])
def test_a_greedy_search_past_the_cells_left_stops_when_none_is_left(maps, edit):
    """`--obstacles 1000000000` kept planning every map at every step after no cell was left (issue 45): the search
    stops at the step where no map has a valid cell; that step's pairs (none) are the result, and `steps` ends there."""
    planner = load_planner("optimal", SIZE)
    calls = []
    plan = planner.plan

    def counted(*args, **kwargs):
        calls.append(1)
        assert len(calls) < 5000, "the greedy search kept planning after no cell was left"
        return plan(*args, **kwargs)

    planner.plan = counted
    few = slice(0, 3)
    attack = make_attack("random", seed=1, obstacles=10**9, edit=edit)
    result = attack.attack(maps.obstacles[few], maps.starts[few, 0], maps.goals[few], planner)
    k = len(result.steps)
    assert k < SIZE * SIZE and len(result.pairs) == 0 and len(result.steps[-1]) == 0
    assert sorted(result.no_valid_cell.tolist()) == [0, 1, 2] and all(len(s) for s in result.steps[:-1])
    # the steps made are those of an attack of that many cells: the same cells, step for step
    again = make_attack("random", seed=1, obstacles=k - 1, edit=edit)
    shorter = again.attack(maps.obstacles[few], maps.starts[few, 0], maps.goals[few], load_planner("optimal", SIZE))
    for mine, theirs in zip(result.steps[:-1], shorter.steps, strict=True):
        assert np.array_equal(mine.added, theirs.added) and np.array_equal(mine.map_index, theirs.map_index)
