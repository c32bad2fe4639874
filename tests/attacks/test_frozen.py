"""Frozen cells (`MapSet.frozen`, DESIGN.md "Several obstacles" and "Obstacle removal"): no strategy, adding or
removing, one cell or K greedily, ever edits one. The oracle is the brute-force set of allowed cells written from
the rules; the maps are small, their masks random (fixed seeds, hypothesis derandomized)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.grid.oracle import reachable
from vinadv.attacks.strategies import make_attack
from vinadv.attacks.validity import removable_cells, valid_additions, valid_cells, valid_removals
from vinadv.grid import generate_maps
from vinadv.vocabulary import ADD, REMOVE

SIZE = 8
NAMES = ("random", "near-path", "key-points", "saliency", "exhaustive")


def allowed(obstacles, start, goal, frozen, edit) -> set[tuple[int, int]]:
    """The cells one edit may touch, cell by cell in plain Python: never a frozen cell; to add, a free cell that is not
    the start or the goal and leaves the goal reachable; to remove, an obstacle that is not on the outer ring of a map
    whose ring is all obstacles, on a map whose goal is reachable."""
    n = len(obstacles)
    ring = {(r, c) for r in range(n) for c in range(n) if r in (0, n - 1) or c in (0, n - 1)}
    walled = all(obstacles[r][c] for r, c in ring)
    out = set()
    for r in range(n):
        for c in range(n):
            if frozen[r][c]:
                continue
            if edit == ADD:
                if obstacles[r][c] or (r, c) in (tuple(start), tuple(goal)):
                    continue
                blocked = np.array(obstacles, dtype=bool)
                blocked[r, c] = True
                if reachable(blocked, start, goal):
                    out.add((r, c))
            elif obstacles[r][c] and not (walled and (r, c) in ring) and reachable(obstacles, start, goal):
                out.add((r, c))
    return out


def _maps_and_mask(seed: int, share: float):
    maps = generate_maps(3, SIZE, seed=seed, n_starts=1)
    frozen = np.random.default_rng(seed).random(maps.obstacles.shape) < share
    return maps, frozen


@pytest.mark.parametrize("edit", [ADD, REMOVE])
@pytest.mark.parametrize("seed", [1, 2])
def test_the_candidate_cells_are_the_brute_force_sets(seed, edit):
    maps, frozen = _maps_and_mask(seed, 0.3)
    cells = valid_cells if edit == ADD else removable_cells
    got = cells(maps.obstacles, maps.starts[:, 0], maps.goals, frozen=frozen)
    for b in range(len(maps)):
        want = allowed(maps.obstacles[b], maps.starts[b, 0], maps.goals[b], frozen[b], edit)
        assert {tuple(c) for c in np.argwhere(got[b]).tolist()} == want


@pytest.mark.parametrize("edit", [ADD, REMOVE])
def test_a_set_with_a_frozen_cell_is_never_valid(edit):
    maps, _ = _maps_and_mask(3, 0.0)
    cells = (valid_cells if edit == ADD else removable_cells)(maps.obstacles, maps.starts[:, 0], maps.goals)
    b = int(np.flatnonzero(cells.any(axis=(1, 2)))[0])
    cell = np.argwhere(cells[b])[0]
    frozen = np.zeros(maps.obstacles.shape, dtype=bool)
    check = valid_additions if edit == ADD else valid_removals
    args = (maps.obstacles[b : b + 1], maps.starts[b : b + 1, 0], maps.goals[b : b + 1], cell[None, None])
    assert check(*args, frozen=frozen[b : b + 1])[0]
    frozen[b, cell[0], cell[1]] = True
    assert not check(*args, frozen=frozen[b : b + 1])[0]


@pytest.mark.parametrize("edit", [ADD, REMOVE])
@pytest.mark.parametrize("name", NAMES)
def test_no_strategy_edits_a_frozen_cell(name, edit, model):
    """Every pair's cells are allowed cells of the map it was chosen on (brute force), one or two cells greedily;
    exhaustive with one cell evaluates exactly the allowed cells."""

    @settings(
        max_examples=4, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture]
    )
    @given(seed=st.integers(0, 10**4), share=st.sampled_from([0.2, 0.6]), k=st.integers(1, 2))
    def check(seed, share, k):
        maps, frozen = _maps_and_mask(seed, share)
        starts = maps.starts[:, 0]
        attack = make_attack(name, per_map=0 if name == "exhaustive" else 3, seed=seed, obstacles=k, edit=edit)
        result = attack.attack(maps.obstacles, starts, maps.goals, model, frozen=frozen)
        for step, pairs in enumerate(result.steps):
            for i, b in enumerate(pairs.map_index):
                current = maps.obstacles[b].copy()
                for r, c in pairs.added[i, :-1]:  # the cells of the steps before, edited
                    current[r, c] = edit == ADD
                cell = tuple(int(v) for v in pairs.added[i, -1])
                assert pairs.added.shape[1] == step + 1
                assert cell in allowed(current, starts[b], maps.goals[b], frozen[b], edit), (b, cell)
        if name == "exhaustive" and k == 1:
            for b in range(len(maps)):
                got = {tuple(c) for c in result.pairs.added[result.pairs.map_index == b, 0].tolist()}
                assert got == allowed(maps.obstacles[b], starts[b], maps.goals[b], frozen[b], edit)

    check()


@pytest.mark.parametrize("edit", [ADD, REMOVE])
@pytest.mark.parametrize("name", ["random", "key-points"])
def test_no_mask_or_an_empty_one_changes_nothing(name, edit, model):
    maps, _ = _maps_and_mask(5, 0.0)
    runs = [
        make_attack(name, per_map=2, seed=7, obstacles=2, edit=edit).attack(
            maps.obstacles, maps.starts[:, 0], maps.goals, model, frozen=frozen
        )
        for frozen in (None, np.zeros(maps.obstacles.shape, dtype=bool))
    ]
    a, b = (r.pairs for r in runs)
    np.testing.assert_array_equal(a.map_index, b.map_index)
    np.testing.assert_array_equal(a.added, b.added)
    np.testing.assert_array_equal(a.obstacles_a, b.obstacles_a)
