"""Obstacle removal (edit `remove`, DESIGN.md "Obstacle removal"): the removal validity rule against brute force
(hypothesis), every strategy's removal candidates against their documented sets, removal never harming `optimal`
(a freed cell never lengthens the optimum: plain-Python Dijkstra), and the pairs file keeping the edit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import event, example, given, settings, target
from hypothesis import strategies as st

from tests.fault_files import read_npz
from tests.grid.oracle import MOVES, brute_distances, reachable
from vinadv.attacks.pairs import PairSet
from vinadv.attacks.strategies import STRATEGIES, make_attack, within_distance
from vinadv.attacks.validity import removable_cells, valid_removals
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.grid.checks import border_walls
from vinadv.identify import identify
from vinadv.npzfile import save_npz
from vinadv.planners.classical.optimal import OptimalPlanner
from vinadv.planners.vin.planner import as_planner
from vinadv.testing.planners import planning_vin

SIZE = 8


def oracle_removable(obstacles, start, goal, cells, moves="octile") -> bool:
    """The rule, cell by cell in plain Python: K distinct cells on the grid, each an obstacle of the original map and
    not on the outer ring of a map whose ring is all obstacles, and the goal reachable from the start."""
    cells = [tuple(c) for c in cells]
    n = len(obstacles)
    if len(set(cells)) != len(cells) or any(not (0 <= r < n and 0 <= c < n) for r, c in cells):
        return False
    ring = [(r, c) for r in range(n) for c in range(n) if r in (0, n - 1) or c in (0, n - 1)]
    walled = all(obstacles[r][c] for r, c in ring)
    if any(not obstacles[r][c] or (walled and (r, c) in ring) for r, c in cells):
        return False
    return reachable(np.array(obstacles, dtype=bool), start, goal, moves=moves)


@pytest.mark.slow
@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 10**6),
    k=st.integers(1, 4),
    data=st.data(),
    moves=st.sampled_from(MOVES),
    borderless=st.booleans(),
)
def test_valid_removals_is_the_rule(seed, k, data, moves, borderless):
    maps = generate_maps(1, SIZE, seed=seed, n_starts=1, moves=moves)
    obstacles, start, goal = maps.obstacles[0].copy(), maps.starts[0, 0], maps.goals[0]
    if borderless:  # a map without a border wall: its outer ring is removable too
        obstacles[0, 3] = False
    blocked = [tuple(c) for c in np.argwhere(obstacles).tolist()]
    # mostly obstacle cells (the interesting case, border walls included), sometimes any cell, repeats allowed
    cell = st.one_of(st.sampled_from(blocked), st.tuples(st.integers(-1, SIZE), st.integers(0, SIZE - 1)))
    cells = data.draw(st.lists(cell, min_size=k, max_size=k))
    got = valid_removals(obstacles[None], start[None], goal[None], np.array([cells]), moves=moves)
    assert bool(got[0]) == oracle_removable(obstacles, start, goal, cells, moves)


@pytest.mark.parametrize(("seed", "moves"), [(1, "octile"), (2, "news"), (3, "moore")])
def test_removable_cells_match_brute_force(seed, moves):
    maps = generate_maps(3, SIZE, seed=seed, n_starts=1, moves=moves)
    obstacles = maps.obstacles.copy()
    obstacles[1, 0, 3] = False  # a map without a border wall: its outer ring is removable too
    got = removable_cells(obstacles, maps.starts[:, 0], maps.goals, moves=moves)
    for b in range(3):
        start, goal = maps.starts[b, 0], maps.goals[b]
        for r in range(SIZE):
            for c in range(SIZE):
                assert got[b, r, c] == oracle_removable(obstacles[b], start, goal, [(r, c)], moves), (b, r, c)


def test_border_walls_only_where_the_ring_is_whole():
    walled = np.zeros((6, 6), bool)
    walled[[0, -1], :] = walled[:, [0, -1]] = True
    open_ring = walled.copy()
    open_ring[0, 2] = False
    walls = border_walls(np.stack([walled, open_ring]))
    assert walls[0].sum() == 20 and not walls[0, 1:-1, 1:-1].any()
    assert not walls[1].any()


def test_an_unsolvable_map_has_nothing_to_remove():
    obstacles = np.zeros((1, 6, 6), bool)
    obstacles[0, :, 3] = True  # a wall between start and goal
    cells = removable_cells(obstacles, np.array([[2, 1]]), np.array([[2, 5]]))
    assert not cells.any()


@pytest.fixture(scope="module")
def maps():
    return generate_maps(16, SIZE, seed=9, n_starts=1)


@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_removal_candidates_are_the_documented_sets(name, maps):
    model = planning_vin(SIZE, seed=2, noise=0.2)
    starts, goals = maps.starts[:, 0], maps.goals
    per_map = 0 if name == "exhaustive" else 3
    result = make_attack(name, per_map=per_map, seed=4, budget=5, radius=1, edit="remove").attack(
        maps.obstacles, starts, goals, model
    )
    pairs = result.pairs
    assert len(pairs) and set(pairs.edit) == {"remove"} and pairs.params["edit"] == "remove"
    cells = pairs.added[:, 0]
    m = pairs.map_index
    allowed = removable_cells(maps.obstacles, starts, goals)
    assert allowed[m, cells[:, 0], cells[:, 1]].all()
    expected = pairs.obstacles_o.copy()
    expected[np.arange(len(pairs)), cells[:, 0], cells[:, 1]] = False
    assert np.array_equal(pairs.obstacles_a, expected)
    if name == "exhaustive":  # every removable cell, once
        assert len(pairs) == allowed.sum()
    if name == "near-path":  # within the radius of the original path
        path = np.zeros_like(maps.obstacles)
        for i, p in enumerate(as_planner(model, SIZE).plan(maps.obstacles, starts, goals).paths.unpack()):
            path[i, p[:, 0], p[:, 1]] = True
        assert within_distance(path, 1)[m, cells[:, 0], cells[:, 1]].all()
    if name in ("random", "near-path"):
        assert (np.bincount(m, minlength=len(maps)) <= 3).all()


def _optimal_cost(obstacles, start, goal) -> float:
    return float(brute_distances(obstacles, tuple(goal))[tuple(start)][0])


def _check_never_harmed(maps, name: str, k: int, seed: int, checked: int) -> int:
    """Every pair `name` makes on `maps` by freeing k cells for `optimal` is harmless, and its optimum (the first
    `checked` pairs by the plain-Python oracle) is never longer than the original map's. Returns the number of pairs,
    which may be 0: a strategy may find no cell to free on small maps (near-path, with none near the path)."""
    result = make_attack(name, per_map=2, seed=seed, budget=4, obstacles=k, edit="remove").attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, OptimalPlanner(SIZE)
    )
    pairs = result.pairs
    ident = identify(pairs)
    assert "invalid" not in set(ident.labels)  # `optimal` reaches every goal on the clean map
    assert set(ident.harm.harm) <= {"harmless"} and "UrP" not in set(ident.labels)
    assert (ident.harm.opt_cost_a <= ident.harm.opt_cost_o + 1e-9).all()
    for i in range(min(checked, len(pairs))):  # a freed cell never lengthens the optimum (the oracle)
        before = _optimal_cost(pairs.obstacles_o[i], pairs.starts[i], pairs.goals[i])
        after = _optimal_cost(pairs.obstacles_a[i], pairs.starts[i], pairs.goals[i])
        assert after <= before + 1e-9
        assert abs(ident.harm.opt_cost_a[i] - after) < 1e-9 and abs(ident.harm.opt_cost_o[i] - before) < 1e-9
    return len(pairs)


def test_removal_never_harms_optimal_on_fixed_maps(maps):
    assert _check_never_harmed(maps, "exhaustive", 1, 0, checked=3) > 0


@pytest.mark.parametrize("k", [1, 2])
@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_every_strategy_frees_cells_on_fixed_maps(name, k):
    """The property below may meet maps where a strategy makes no pair; on these every strategy makes some, so the
    property is not checked on nothing."""
    assert _check_never_harmed(generate_maps(4, SIZE, seed=7, n_starts=1), name, k, 7, checked=1) > 0


@pytest.mark.slow
@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 10**6), k=st.integers(1, 2), name=st.sampled_from(sorted(STRATEGIES)))
@example(seed=450, k=2, name="near-path")  # no pair on these four maps: it failed when the test assumed one
def test_removal_never_harms_optimal(seed, k, name):
    made = _check_never_harmed(generate_maps(4, SIZE, seed=seed, n_starts=1), name, k, seed, checked=4)
    event("pairs made" if made else "no pair made")
    target(made, label="pairs made")


def test_pairs_files_keep_the_edit_and_older_files_read_as_add(maps, tmp_path):
    model = planning_vin(SIZE, seed=2, noise=0.2)
    removed = make_attack("random", per_map=1, seed=1, edit="remove", obstacles=2).attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, model
    )
    removed.pairs.save(tmp_path / "r.npz")
    back = PairSet.load(tmp_path / "r.npz")
    assert list(back.edit) == ["remove"] * len(back) and np.array_equal(back.added, removed.pairs.added)
    added = make_attack("random", per_map=1, seed=1).attack(maps.obstacles, maps.starts[:, 0], maps.goals, model)
    added.pairs.save(tmp_path / "a.npz")
    old = {k: v for k, v in read_npz(tmp_path / "a.npz").items() if k not in ("format", "edit")}
    save_npz(tmp_path / "old.npz", "vinadv.pairs/2", old)
    assert list(PairSet.load(tmp_path / "old.npz").edit) == ["add"] * len(added.pairs)
    # a removal pair read as an addition (its edit lost) breaks the file's rules
    fields = {k: v for k, v in read_npz(tmp_path / "r.npz").items() if k not in ("format", "edit")}
    save_npz(tmp_path / "lost.npz", "vinadv.pairs/2", fields)
    with pytest.raises(InputError, match="already an obstacle"):
        PairSet.load(tmp_path / "lost.npz")
    # a freed border wall is refused
    fields = read_npz(tmp_path / "r.npz")
    fields.pop("format")
    fields["added"] = fields["added"].copy()
    fields["added"][0, 0] = (0, 0)
    fields["obstacles_a"] = fields["obstacles_a"].copy()
    fields["obstacles_a"][0] = fields["obstacles_o"][0]
    fields["obstacles_a"][0][tuple(fields["added"][0].T)] = False
    save_npz(tmp_path / "wall.npz", "vinadv.pairs/3", fields)
    with pytest.raises(InputError, match="border wall"):
        PairSet.load(tmp_path / "wall.npz")
    fields["edit"] = np.array(["swap"] * len(fields["edit"]))
    save_npz(tmp_path / "bad.npz", "vinadv.pairs/3", fields)
    with pytest.raises(InputError, match="field 'edit' has value 'swap'"):
        PairSet.load(tmp_path / "bad.npz")
