import numpy as np
import pytest

from tests.grid.oracle import reachable
from tests.progress_bars import recorded_bars
from vinadv.attacks import strategies
from vinadv.attacks.pairs import PairSet
from vinadv.attacks.strategies import STRATEGIES, make_attack, within_distance
from vinadv.attacks.validity import valid_cells
from vinadv.classify import label_pairs
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.identify import rule_strength
from vinadv.planners.vin.reference import plan_reference
from vinadv.testing.planners import planning_vin
from vinadv.vocabulary import LABEL_STRENGTH

SIZE = 10


@pytest.fixture(scope="module")
def maps():
    return generate_maps(40, SIZE, seed=3, n_starts=1)


def assert_valid(pairs: PairSet, maps):
    src = pairs.map_index
    np.testing.assert_array_equal(pairs.obstacles_o, maps.obstacles[src])
    np.testing.assert_array_equal(pairs.starts, maps.starts[src, 0])
    np.testing.assert_array_equal(pairs.goals, maps.goals[src])
    for i in range(len(pairs)):
        cells = sorted(map(tuple, pairs.added[i].tolist()))
        assert len(set(cells)) == len(cells) == pairs.n_added  # K distinct cells
        diff = np.argwhere(pairs.obstacles_a[i] != pairs.obstacles_o[i])
        assert list(map(tuple, diff.tolist())) == cells and pairs.obstacles_a[i][tuple(np.array(cells).T)].all()
        assert tuple(pairs.starts[i]) not in cells and tuple(pairs.goals[i]) not in cells
        assert reachable(pairs.obstacles_a[i], pairs.starts[i], pairs.goals[i])


@pytest.mark.parametrize("name", list(STRATEGIES))
def test_every_pair_is_valid_and_seeds_reproduce(name, model, maps, tmp_path):
    attack = make_attack(name, per_map=2, seed=7, budget=5)
    first = attack.attack(maps.obstacles, maps.starts[:, 0], maps.goals, model, strength=rule_strength)
    assert len(first.pairs) > 0
    assert_valid(first.pairs, maps)
    assert np.all(np.bincount(first.pairs.map_index) <= 2)
    second = make_attack(name, per_map=2, seed=7, budget=5).attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, model, strength=rule_strength
    )
    np.testing.assert_array_equal(first.pairs.added, second.pairs.added)
    assert first.pairs.path_a == second.pairs.path_a
    # the pairs file round-trips
    first.pairs.save(tmp_path / "p.npz")
    back = PairSet.load(tmp_path / "p.npz")
    np.testing.assert_array_equal(back.added, first.pairs.added)
    assert back.strategy == name and back.params == {**attack.params(), "planner": first.pairs.params["planner"]}
    assert back.params["planner"]["name"] == "vin"  # which planner the attacks were found on


def test_paths_in_pairs_are_the_reference_planners(model, maps):
    pairs = make_attack("random", seed=1).attack(maps.obstacles, maps.starts[:, 0], maps.goals, model).pairs
    ref_o = plan_reference(pairs.obstacles_o, pairs.starts, pairs.goals, model)
    ref_a = plan_reference(pairs.obstacles_a, pairs.starts, pairs.goals, model)
    assert ref_o.paths == pairs.path_o and ref_a.paths == pairs.path_a
    np.testing.assert_array_equal(ref_a.termination_names, pairs.term_a)


def test_valid_cells_match_brute_force(maps):
    valid = valid_cells(maps.obstacles, maps.starts[:, 0], maps.goals)
    for i in range(10):
        obstacles, start, goal = maps.obstacles[i], maps.starts[i, 0], maps.goals[i]
        for r in range(SIZE):
            for c in range(SIZE):
                expected = not obstacles[r, c] and (r, c) not in (tuple(start), tuple(goal))
                if expected:
                    blocked = obstacles.copy()
                    blocked[r, c] = True
                    expected = reachable(blocked, start, goal)
                assert valid[i, r, c] == expected, (i, r, c)


# octile's variants are slow: the quick tier checks octile validity against the brute force on the usual maps
@pytest.mark.parametrize(
    "corner_cutting, moves",
    [
        pytest.param(True, "octile", id="corner-cutting", marks=pytest.mark.slow),
        pytest.param(False, "octile", id="no-corner-cutting", marks=pytest.mark.slow),
        pytest.param(True, "moore", id="moore"),
        pytest.param(True, "news", id="news"),
    ],
)
def test_valid_cells_match_brute_force_on_dense_maps(corner_cutting, moves):
    # dense small maps: many cells are the only way through (the generated maps have few)
    rng = np.random.default_rng(11)
    n = 7
    obstacles = rng.random((150, n, n)) < 0.45
    starts, goals = rng.integers(0, n, (150, 2)), rng.integers(0, n, (150, 2))
    idx = np.arange(150)
    obstacles[idx, starts[:, 0], starts[:, 1]] = False
    obstacles[idx, goals[:, 0], goals[:, 1]] = False
    valid = valid_cells(obstacles, starts, goals, corner_cutting, moves)
    separators = 0
    for i in range(150):
        start, goal = tuple(starts[i]), tuple(goals[i])
        solvable = reachable(obstacles[i], start, goal, corner_cutting, moves)
        for r in range(n):
            for c in range(n):
                expected = solvable and not obstacles[i, r, c] and (r, c) not in (start, goal)
                if expected:
                    blocked = obstacles[i].copy()
                    blocked[r, c] = True
                    expected = reachable(blocked, start, goal, corner_cutting, moves)
                    separators += not expected
                assert valid[i, r, c] == expected, (i, r, c)
    assert separators > 50  # the maps do exercise the separators


def corridor_map():
    """A 1-wide corridor from start to goal: every free cell but the two ends disconnects them."""
    obstacles = np.ones((1, 8, 8), dtype=bool)
    obstacles[0, 3, 1:7] = False
    return obstacles, np.array([[3, 1]]), np.array([[3, 6]])


@pytest.mark.parametrize("name", list(STRATEGIES))
def test_no_valid_cell_gives_no_pair(name):
    obstacles, starts, goals = corridor_map()
    result = make_attack(name).attack(obstacles, starts, goals, planning_vin(8, noise=0.0))
    assert len(result.pairs) == 0
    assert result.no_valid_cell.tolist() == [0]


#: the maps of the brute-force search (a planner call per cell): three of the module's, whose strongest cells are an
#: FP among DPs, the first of two FPs, and an UrP; in each a weaker label comes first in row-major order
EXHAUSTIVE_MAPS = [0, 3, 10]


@pytest.mark.slow  # a planner call per cell; tests/test_identify.py checks exhaustive against a brute force quickly
def test_exhaustive_finds_the_strongest_cell_of_a_brute_force_search(model, maps):
    chosen = maps.take(EXHAUSTIVE_MAPS)
    result = make_attack("exhaustive").attack(
        chosen.obstacles, chosen.starts[:, 0], chosen.goals, model, strength=rule_strength
    )
    strongest, beaten = [], []
    for i in range(len(EXHAUSTIVE_MAPS)):
        obstacles, start, goal = chosen.obstacles[i], chosen.starts[i, 0], chosen.goals[i]
        original = plan_reference(obstacles[None], start[None], goal[None], model)
        best = first = None
        for r in range(SIZE):  # every cell, the slow way: independent of the attack code
            for c in range(SIZE):
                if obstacles[r, c] or (r, c) in (tuple(start), tuple(goal)):
                    continue
                adv = obstacles.copy()
                adv[r, c] = True
                if not reachable(adv, start, goal):
                    continue
                planned = plan_reference(adv[None], start[None], goal[None], model)
                label = label_pairs(original.paths, planned.paths, goal[None], SIZE).labels[0]
                first = label if first is None else first
                if best is None or LABEL_STRENGTH[label] > LABEL_STRENGTH[best[0]]:
                    best = (label, (r, c))
        strongest.append(best[0])
        beaten.append(LABEL_STRENGTH[best[0]] > LABEL_STRENGTH[first])
        got = np.flatnonzero(result.pairs.map_index == i)
        assert len(got) == 1
        assert tuple(result.pairs.added[got[0], 0]) == best[1]
    assert all(beaten) and "UrP" in strongest and "FP" in strongest  # the maps still tell the labels apart


def test_exhaustive_keeps_every_valid_cell_with_per_map_zero(model, maps):
    result = make_attack("exhaustive", per_map=0).attack(maps.obstacles[:3], maps.starts[:3, 0], maps.goals[:3], model)
    valid = valid_cells(maps.obstacles[:3], maps.starts[:3, 0], maps.goals[:3])
    assert len(result.pairs) == valid.sum()


def test_key_points_and_saliency_try_budget_candidates(model, maps):
    for name in ("key-points", "saliency"):
        result = make_attack(name, budget=3).attack(maps.obstacles, maps.starts[:, 0], maps.goals, model)
        assert result.planner_calls <= len(maps) * 4


def test_bad_parameters():
    with pytest.raises(InputError, match="unknown attack strategy 'nope'"):
        make_attack("nope")
    with pytest.raises(InputError, match="^per_map must be"):
        make_attack("random", per_map=-1)
    with pytest.raises(InputError, match="^budget must be"):
        make_attack("saliency", budget=0)


@pytest.mark.parametrize("radius", [0, 1, 2, 5])
def test_within_distance_is_the_chebyshev_neighbourhood(radius):
    rng = np.random.default_rng(radius)
    mask = rng.random((4, 9, 9)) < 0.08
    before = mask.copy()
    got = within_distance(mask, radius)
    assert (mask == before).all()
    for b, r, c in np.ndindex(mask.shape):  # brute force: any marked cell at most `radius` king moves away
        want = any(mask[b, i, j] for i in range(9) for j in range(9) if max(abs(i - r), abs(j - c)) <= radius)
        assert got[b, r, c] == want, (b, r, c)


def test_the_progress_bar_counts_maps_chunk_by_chunk_and_the_chunks_change_no_pair(model, maps, monkeypatch):
    args = (maps.obstacles[:5], maps.starts[:5, 0], maps.goals[:5], model)
    whole = make_attack("exhaustive").attack(*args).pairs
    bars = recorded_bars(monkeypatch)
    monkeypatch.setattr(strategies, "EVAL_CHUNK", 1)  # a chunk per map
    per_map = make_attack("exhaustive").attack(*args, progress=True).pairs
    (bar,) = bars
    assert (bar.total, bar.unit, bar.updates) == (5, "map", [1] * 5)
    for name in ("map_index", "added", "obstacles_a", "term_a"):
        np.testing.assert_array_equal(getattr(per_map, name), getattr(whole, name))
    np.testing.assert_array_equal(per_map.path_a.cells, whole.path_a.cells)
