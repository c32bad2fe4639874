"""Harm of path pairs against independent oracles: a plain-Python Dijkstra (heapq), path costs summed move by
move, the expert path walked with the DESIGN.md tie-break, and the rule by brute force; on every movement model
(octile: diagonal sqrt 2; moore: every move 1; news: the 4 straight moves only)."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from tests.classify.oracle import rule_oracle
from vinadv.classify.harm import HARMS, pair_harm
from vinadv.errors import InputError
from vinadv.grid.generator import generate_maps
from vinadv.grid.paths import PackedPaths
from vinadv.grid.shortest_paths import expert_paths

MOVES = [(-1, 0), (1, 0), (0, 1), (0, -1), (-1, 1), (-1, -1), (1, 1), (1, -1)]
MODELS = ("octile", "moore", "news")


def model_moves(moves):
    """The (dr, dc) of the model's moves, in action order."""
    return MOVES[:4] if moves == "news" else MOVES


def step_cost(dr, dc, moves):
    return math.sqrt(2) if dr and dc and moves == "octile" else 1.0


def legal(obstacles, r, c, dr, dc, corner_cutting):
    n = len(obstacles)
    nr, nc = r + dr, c + dc
    if not (0 <= nr < n and 0 <= nc < n) or obstacles[nr][nc]:
        return False
    return corner_cutting or not (dr and dc) or not (obstacles[nr][c] or obstacles[r][nc])


def dijkstra(obstacles, goal, corner_cutting, moves="octile"):
    """Cost-to-goal of every cell, {cell: cost} (reachable cells only)."""
    dist = {tuple(goal): 0.0}
    heap = [(0.0, tuple(goal))]
    done = set()
    while heap:
        d, (r, c) = heapq.heappop(heap)
        if (r, c) in done:
            continue
        done.add((r, c))
        for dr, dc in model_moves(moves):
            if legal(obstacles, r, c, dr, dc, corner_cutting):
                nd = d + step_cost(dr, dc, moves)
                if nd < dist.get((r + dr, c + dc), math.inf) - 1e-12:
                    dist[(r + dr, c + dc)] = nd
                    heapq.heappush(heap, (nd, (r + dr, c + dc)))
    return dist


def optimal_path(obstacles, start, goal, corner_cutting, moves="octile"):
    """The expert path (lowest-index optimal action at each cell), or None when the goal is unreachable."""
    dist = dijkstra(obstacles, goal, corner_cutting, moves)
    cell = tuple(start)
    if cell not in dist:
        return None
    path = [cell]
    while cell != tuple(goal):
        r, c = cell
        for dr, dc in model_moves(moves):
            nb = (r + dr, c + dc)
            step = step_cost(dr, dc, moves)
            tight = nb in dist and abs(step + dist[nb] - dist[cell]) <= 1e-9
            if legal(obstacles, r, c, dr, dc, corner_cutting) and tight:
                cell = nb
                break
        path.append(cell)
    return path


def path_cost(path, moves="octile"):
    return sum(step_cost(b[0] - a[0], b[1] - a[1], moves) for a, b in zip(path, path[1:]))


@st.composite
def harm_cases(draw, corner_cutting=None):
    """Pairs on small random maps of one movement model: an original map, the same plus 1-2 obstacles, and two
    'planner' paths that are legal on their maps, optimal or not, reaching the goal or not. `(rows, cc, moves)`, at
    least one row (a draw whose every start was cut off from its goal is rejected)."""
    n = draw(st.integers(4, 9))
    moves = draw(st.sampled_from(MODELS))
    cc = draw(st.booleans()) if corner_cutting is None else corner_cutting
    cc = cc or moves == "news"  # news has no corner to cut
    rows = []
    for _ in range(draw(st.integers(1, 5))):
        obstacles = np.array(draw(st.lists(st.booleans(), min_size=n * n, max_size=n * n)), dtype=bool).reshape(n, n)
        obstacles &= np.array(draw(st.lists(st.booleans(), min_size=n * n, max_size=n * n))).reshape(n, n)  # ~25%
        cell = st.tuples(st.integers(0, n - 1), st.integers(0, n - 1))
        start, goal = draw(cell), draw(cell)
        obstacles[start] = obstacles[goal] = False
        expert_o = optimal_path(obstacles.tolist(), start, goal, cc, moves)
        if expert_o is None or start == goal:
            continue
        adv = obstacles.copy()
        for _ in range(draw(st.integers(1, 2))):
            added = draw(cell)
            if added not in (start, goal):
                adv[added] = True
        paths = []
        for side_map in (obstacles, adv):
            kind = draw(st.sampled_from(["optimal", "detour", "cut", "original"]))
            if (
                kind == "original"
                and paths
                and all(
                    legal(side_map.tolist(), *p, q[0] - p[0], q[1] - p[1], cc) for p, q in zip(paths[0], paths[0][1:])
                )
            ):
                paths.append(list(paths[0]))
                continue
            extra = side_map.copy()
            if kind == "detour":  # optimal on a map with more obstacles: legal here, often longer
                extra |= np.array(draw(st.lists(st.booleans(), min_size=n * n, max_size=n * n))).reshape(n, n)
                extra[start] = extra[goal] = False
            path = optimal_path(extra.tolist(), start, goal, cc, moves) or [start]
            if kind == "cut" or path == [start]:
                path = path[: draw(st.integers(1, max(1, len(path) - 1)))]
            paths.append(path)
        rows.append((obstacles, adv, start, goal, paths[0], paths[1]))
    assume(rows)
    return rows, cc, moves


def run(rows, cc, **kwargs):
    obstacles_o = np.array([r[0] for r in rows])
    obstacles_a = np.array([r[1] for r in rows])
    starts = np.array([r[2] for r in rows])
    goals = np.array([r[3] for r in rows])

    path_o, path_a = PackedPaths.pack([r[4] for r in rows]), PackedPaths.pack([r[5] for r in rows])
    t = round(4 * obstacles_o.shape[-1] / 28)
    labels = np.array([rule_oracle(r[4], r[5], r[3], t)[0] for r in rows])
    return pair_harm(obstacles_o, obstacles_a, starts, goals, path_o, path_a, labels, cc, **kwargs), labels, t


def close(a, b):
    return (math.isnan(a) and math.isnan(b)) or math.isclose(a, b, abs_tol=1e-9)


@pytest.mark.slow  # over a second: the quick tier keeps the module's other tests
# 100 cases of up to five pairs each, on three movement models: some 300 pairs, every field of each against its oracle
@settings(max_examples=100, deadline=None)
@given(harm_cases())
def test_every_field_matches_the_oracles(case):
    rows, cc, moves = case
    harm, labels, t = run(rows, cc, moves=moves)
    for i, (obs_o, obs_a, start, goal, path_o, path_a) in enumerate(rows):
        expert_o = optimal_path(obs_o.tolist(), start, goal, cc, moves)
        expert_a = optimal_path(obs_a.tolist(), start, goal, cc, moves)
        opt_o = path_cost(expert_o, moves)
        opt_a = math.nan if expert_a is None else path_cost(expert_a, moves)
        cost_o = path_cost(path_o, moves) if path_o[-1] == goal else math.nan
        cost_a = path_cost(path_a, moves) if path_a[-1] == goal else math.nan
        assert close(harm.opt_cost_o[i], opt_o)
        assert close(harm.opt_cost_a[i], opt_a)
        assert close(harm.cost_o[i], cost_o)
        assert close(harm.cost_a[i], cost_a)
        assert close(harm.regret_o[i], cost_o - opt_o)
        assert close(harm.regret_a[i], cost_a - opt_a)
        assert harm.expert_label[i] == rule_oracle(expert_o, expert_a or [start], goal, t)[0]
        if labels[i] == "invalid":
            want = "invalid"
        elif labels[i] == "UrP" or cost_a - opt_a > cost_o - opt_o + 1e-6:
            want = "harmful"
        else:
            want = "harmless"
        assert harm.harm[i] == want


@pytest.mark.slow  # the quick tier checks every field against the oracles (test_every_field_matches_the_oracles)
# fewer cases than the oracle test: these bounds hold of any field the oracle test finds right
@settings(max_examples=50, deadline=None)
@given(harm_cases())
def test_harm_properties(case):
    rows, cc, moves = case
    harm, labels, _ = run(rows, cc, moves=moves)
    assert np.all(np.isnan(harm.regret_o) | (harm.regret_o >= -1e-9))
    assert np.all(np.isnan(harm.regret_a) | (harm.regret_a >= -1e-9))
    assert np.all(np.isin(harm.harm, HARMS))
    assert np.all(harm.harm[labels == "UcP"] == "harmless")
    assert np.all(harm.harm[labels == "UrP"] == "harmful")
    assert np.all(harm.harm[labels == "invalid"] == "invalid")
    assert np.all(harm.harm[labels != "invalid"] != "invalid")
    # the adversarial map only adds obstacles: the optimum can only grow
    assert np.all(np.isnan(harm.opt_cost_a) | (harm.opt_cost_a >= harm.opt_cost_o - 1e-9))


def _dihedral(cells, n, k):
    """Cells under the k-th symmetry of the n x n square (4 rotations, each optionally transposed)."""
    out = []
    for r, c in cells:
        for _ in range(k % 4):
            r, c = c, n - 1 - r  # a quarter turn
        if k >= 4:
            r, c = c, r
        out.append((r, c))
    return out


def _dihedral_map(obstacles, k):
    n = len(obstacles)
    out = np.zeros_like(obstacles)
    cells = [(r, c) for r in range(n) for c in range(n)]
    for (r, c), (tr, tc) in zip(cells, _dihedral(cells, n, k)):
        out[tr, tc] = obstacles[r, c]
    return out


@pytest.mark.slow  # 30 generated cases, each run twice (as drawn and flipped or rotated)
@settings(max_examples=30, deadline=None)
@given(harm_cases(), st.integers(1, 7))
def test_harm_invariant_under_flips_and_rotations(case, k):
    rows, cc, moves = case
    n = len(rows[0][0])
    moved = [
        (
            _dihedral_map(o, k),
            _dihedral_map(a, k),
            _dihedral([s], n, k)[0],
            _dihedral([g], n, k)[0],
            _dihedral(po, n, k),
            _dihedral(pa, n, k),
        )
        for o, a, s, g, po, pa in rows
    ]
    before, _, _ = run(rows, cc, moves=moves)
    after, _, _ = run(moved, cc, moves=moves)
    assert np.array_equal(before.harm, after.harm)
    for name in ("opt_cost_o", "opt_cost_a", "cost_o", "cost_a", "regret_o", "regret_a"):
        assert np.allclose(getattr(before, name), getattr(after, name), atol=1e-9, equal_nan=True), name


def _corridor():
    """A 7x7 map with two optimal routes around a block, the planner on the upper one before and the lower after."""
    obstacles = np.zeros((7, 7), dtype=bool)
    obstacles[3, 1:6] = True
    start, goal = (3, 0), (3, 6)
    return obstacles, start, goal


def test_fork_onto_another_optimal_route_is_harmless_and_a_longer_one_harmful():
    obstacles, start, goal = _corridor()
    upper = [(3, 0), (2, 1), (2, 2), (2, 3), (2, 4), (2, 5), (3, 6)]
    lower = [(3, 0), (4, 1), (4, 2), (4, 3), (4, 4), (4, 5), (3, 6)]
    wide = [(3, 0), (4, 1), (5, 2), (5, 3), (5, 4), (4, 5), (3, 6)]  # one row further out: longer
    adv = obstacles.copy()
    adv[2, 3] = True
    rows = [(obstacles, adv, start, goal, upper, lower), (obstacles, adv, start, goal, upper, wide)]
    harm, labels, _ = run(rows, True)
    assert list(labels) == ["FP", "FP"]
    assert list(harm.harm) == ["harmless", "harmful"]
    assert harm.regret_a[0] == pytest.approx(0.0, abs=1e-9)
    assert harm.regret_a[1] == pytest.approx(2 * math.sqrt(2) - 2)
    assert list(harm.expert_label) == ["FP", "FP"]


def test_the_verdict_follows_the_movement_model():
    """The wide detour costs 2 sqrt 2 - 2 more than the upper route with octile costs, but on moore maps (every move
    costs 1) both take 6 moves: the fork is harmless there. On news maps the planner's straight-only detours are
    judged by their move counts."""
    obstacles, start, goal = _corridor()
    upper = [(3, 0), (2, 1), (2, 2), (2, 3), (2, 4), (2, 5), (3, 6)]
    wide = [(3, 0), (4, 1), (5, 2), (5, 3), (5, 4), (4, 5), (3, 6)]
    adv = obstacles.copy()
    adv[2, 3] = True
    octile = run([(obstacles, adv, start, goal, upper, wide)], True)[0]
    moore = run([(obstacles, adv, start, goal, upper, wide)], True, moves="moore")[0]
    assert octile.harm[0] == "harmful" and moore.harm[0] == "harmless"
    assert moore.opt_cost_o[0] == moore.cost_a[0] == 6 and moore.regret_a[0] == 0
    news_upper = [(3, 0), (2, 0), (2, 1), (2, 2), (2, 3), (2, 4), (2, 5), (2, 6), (3, 6)]
    news_wide = [(3, 0), (4, 0), (5, 0), (5, 1), (5, 2), (5, 3), (5, 4), (5, 5), (5, 6), (4, 6), (3, 6)]
    news = run([(obstacles, adv, start, goal, news_upper, news_wide)], True, moves="news")[0]
    assert news.opt_cost_o[0] == news.opt_cost_a[0] == 8 and news.cost_a[0] == 10
    assert news.regret_a[0] == 2 and news.harm[0] == "harmful"


def test_tolerances():
    obstacles, start, goal = _corridor()
    upper = [(3, 0), (2, 1), (2, 2), (2, 3), (2, 4), (2, 5), (3, 6)]
    wide = [(3, 0), (4, 1), (5, 2), (5, 3), (5, 4), (4, 5), (3, 6)]
    adv = obstacles.copy()
    adv[2, 3] = True
    rows = [(obstacles, adv, start, goal, upper, wide)]
    regret = 2 * math.sqrt(2) - 2  # 0.83
    assert run(rows, True, tol=regret - 0.01)[0].harm[0] == "harmful"
    assert run(rows, True, tol=regret + 0.01)[0].harm[0] == "harmless"
    opt = 4 + 2 * math.sqrt(2)
    assert run(rows, True, rtol=(regret + 0.01) / opt)[0].harm[0] == "harmless"
    assert run(rows, True, rtol=(regret - 0.01) / opt)[0].harm[0] == "harmful"
    with pytest.raises(InputError, match="tol"):
        run(rows, True, tol=-1)
    with pytest.raises(InputError, match="rtol"):
        run(rows, True, rtol=math.nan)


def test_shared_original_and_given_expert_data_give_the_same_result():
    maps = generate_maps(40, 16, seed=5, n_starts=1)
    # four attacks per map, on cells of the expert path and off it, maps repeated consecutively
    map_index = np.repeat(np.arange(len(maps.obstacles)), 4)
    obstacles_o = maps.obstacles[map_index]
    rng = np.random.default_rng(0)
    obstacles_a = obstacles_o.copy()
    free = np.argwhere(~obstacles_o)
    lengths = maps.expert.lengths[map_index]
    on_path = maps.expert.cells[maps.expert.offsets[map_index] + (rng.random(len(map_index)) * lengths).astype(int)]
    for i in range(len(map_index)):
        cell = on_path[i] if i % 2 else free[rng.integers(len(free))][1:]
        if tuple(cell) not in (tuple(maps.starts[map_index[i], 0]), tuple(maps.goals[map_index[i]])):
            obstacles_a[i, cell[0], cell[1]] = True
    starts, goals = maps.starts[map_index, 0], maps.goals[map_index]
    _, expert_o = expert_paths(obstacles_o, goals, starts[:, None])
    _, expert_a = expert_paths(obstacles_a, goals, starts[:, None])
    labels = np.array([rule_oracle(expert_o[i], expert_a[i], goals[i], 2)[0] for i in range(len(map_index))])
    args = (obstacles_o, obstacles_a, starts, goals, expert_o, expert_a, labels)
    plain = pair_harm(*args)
    given = pair_harm(*args, expert_o=(maps.expert_costs[map_index, 0], maps.expert.take(map_index)))
    shuffled = rng.permutation(len(map_index))  # no consecutive repeats: every original searched on its own
    alone = pair_harm(
        obstacles_o[shuffled],
        obstacles_a[shuffled],
        starts[shuffled],
        goals[shuffled],
        expert_o.take(shuffled),
        expert_a.take(shuffled),
        labels[shuffled],
    )
    for name in ("opt_cost_o", "opt_cost_a", "regret_a", "expert_label", "harm"):
        a, b, c = getattr(plain, name), getattr(given, name), getattr(alone, name)
        if a.dtype.kind == "f":  # sums of 1 and sqrt(2) in another order: equal up to rounding
            assert np.allclose(a, b, atol=1e-9, equal_nan=True)
            assert np.allclose(a[shuffled], c, atol=1e-9, equal_nan=True)
        else:
            assert np.array_equal(a, b) and np.array_equal(a[shuffled], c), name
    assert set(plain.expert_label) >= {"UcP", "DP"}


def test_bad_input_is_refused():
    obstacles, start, goal = _corridor()
    path = [(3, 0), (2, 1), (2, 2), (2, 3), (2, 4), (2, 5), (3, 6)]
    rows = [(obstacles, obstacles, start, goal, path, path)]
    one = PackedPaths.pack([path])
    with pytest.raises(InputError, match="labels"):
        pair_harm(obstacles[None], obstacles[None], [start], [goal], one, one, ["UcP", "UcP"])
    with pytest.raises(InputError, match="starts"):
        pair_harm(obstacles[None], obstacles[None], [(9, 9)], [goal], one, one, ["UcP"])
    with pytest.raises(InputError, match="path_a"):
        pair_harm(obstacles[None], obstacles[None], [start], [goal], one, PackedPaths.pack([path, path]), ["UcP"])
    assert run(rows, True)[0].harm[0] == "harmless"
