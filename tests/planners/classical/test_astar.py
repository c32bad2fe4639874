"""The best-first search kernel and the `astar` / `wastar` planners (`vinadv.planners.classical.astar`).

Oracles: a literal, scanning re-statement of the Neural A* authors' step (every step computes f and the float32
exp(-f / sqrt N) of every cell with NumPy and takes the first index of the largest open value: no heap), its float64
twin with the tie term as a second key, and a plain-Python Dijkstra for the optimal costs.
"""

import heapq
import math

import numpy as np
import pytest

from vinadv.attacks.strategies import make_attack
from vinadv.classify.harm import pairset_harm
from vinadv.classify.rule import label_pairs
from vinadv.errors import InputError
from vinadv.grid.moves import move_model
from vinadv.planners.classical.astar import AStarPlanner, WeightedAStarPlanner, best_first_search, replica_is_exact
from vinadv.planners.registry import load_planner
from vinadv.planners.result import GOAL, STEP_LIMIT

F32 = np.float32


def legal(free, r, c, dr, dc, corner_cutting):
    n = free.shape[0]
    nr, nc = r + dr, c + dc
    if not (0 <= nr < n and 0 <= nc < n) or not free[nr, nc]:
        return False
    if not corner_cutting and dr and dc:
        return bool(free[nr, c] and free[r, nc])
    return True


def distance(dr, dc, moves):
    if moves == "moore":
        return dr + dc - min(dr, dc)  # Chebyshev, as the authors write it
    if moves == "news":
        return dr + dc
    return abs(dr - dc) + min(dr, dc) * math.sqrt(2)


def oracle(cost, obstacles, start, goal, g_ratio, moves, corner_cutting, exact, tmax=1.0):
    """The authors' search, literally, one scan of all cells per step: `(path, expanded, termination)`."""
    n = obstacles.shape[0]
    free = ~obstacles
    model = move_model(moves)
    rows, cols = np.indices((n, n))
    dr, dc = np.abs(rows - goal[0]), np.abs(cols - goal[1])
    d = np.vectorize(lambda a, b: distance(a, b, moves))(dr, dc)
    if exact:
        h = d + cost.astype(np.float64)
        tie = 0.001 * np.sqrt(dr * dr + dc * dc)
        g = np.zeros((n, n))
    else:
        euc = np.sqrt((dr * dr + dc * dc).astype(F32))
        h = (d.astype(F32) + F32(0.001) * euc) + cost
        g = np.zeros((n, n), F32)
    is_open = np.zeros((n, n), bool)
    closed = np.zeros((n, n), bool)
    parent = {}
    is_open[tuple(start)] = True
    for _ in range(int(tmax * n * n)):
        if not is_open.any():
            return [tuple(start)], closed, STEP_LIMIT
        if exact:
            f = g_ratio * g + (1 - g_ratio) * h
            keys = sorted((f[r, c], tie[r, c], r * n + c) for r, c in zip(*np.nonzero(is_open)))
            sel = divmod(keys[0][2], n)
        else:
            f = F32(g_ratio) * g + F32(1 - g_ratio) * h
            e = np.exp(((-f) / F32(math.sqrt(n))).astype(np.float64)).astype(F32) * is_open
            if e.max() >= np.finfo(F32).tiny:
                sel = divmod(int(np.argmax(e)), n)  # the first index of the largest
            else:  # every open value subnormal or 0: the largest, then the smallest f, then the first
                keys = sorted((-e[r, c], f[r, c], r * n + c) for r, c in zip(*np.nonzero(is_open)))
                sel = divmod(keys[0][2], n)
        closed[sel] = True
        is_open[sel] = False
        if sel == tuple(goal):
            path = [sel]
            while path[-1] in parent:
                path.append(parent[path[-1]])
            return path[::-1], closed, GOAL
        for a, (mr, mc) in enumerate(model.deltas):
            if not legal(free, sel[0], sel[1], mr, mc, corner_cutting):
                continue
            nb = (sel[0] + mr, sel[1] + mc)
            if exact:
                g2 = g[sel] + float(cost[sel]) * model.costs[a]
                better = g2 < g[nb] - 1e-9
            else:
                g2 = F32(g[sel] + F32(cost[sel] * F32(model.costs[a])))
                better = g[nb] > g2
            if (not is_open[nb] and not closed[nb]) or (is_open[nb] and better):
                g[nb] = g2
                is_open[nb] = True
                parent[nb] = sel
    return [tuple(start)], closed, STEP_LIMIT


def dijkstra(obstacles, start, goal, moves, corner_cutting):
    """Plain-Python Dijkstra: the optimal cost start -> goal (inf if unreachable)."""
    n = obstacles.shape[0]
    free = ~obstacles
    model = move_model(moves)
    best = {tuple(start): 0.0}
    heap = [(0.0, tuple(start))]
    while heap:
        d, cell = heapq.heappop(heap)
        if cell == tuple(goal):
            return d
        if d > best[cell]:
            continue
        for a, (mr, mc) in enumerate(model.deltas):
            if legal(free, cell[0], cell[1], mr, mc, corner_cutting):
                nb = (cell[0] + mr, cell[1] + mc)
                nd = d + model.costs[a]
                if nd < best.get(nb, math.inf) - 1e-12:
                    best[nb] = nd
                    heapq.heappush(heap, (nd, nb))
    del n
    return math.inf


def path_cost(path, moves):
    diagonal = move_model(moves).diagonal_cost
    steps = np.abs(np.diff(np.asarray(path, dtype=np.int64), axis=0)).sum(axis=1)
    return float(np.where(steps == 2, diagonal, steps).sum())


def random_problems(seed, count, sizes=(6, 12), density=(0.15, 0.4)):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        n = int(rng.integers(*sizes))
        obstacles = rng.random((n, n)) < rng.uniform(*density)
        start, goal = rng.integers(0, n, 2), rng.integers(0, n, 2)
        obstacles[tuple(start)] = obstacles[tuple(goal)] = False
        out.append((obstacles, start, goal))
    return out


def search_one(cost, obstacles, start, goal, **kwargs):
    result = best_first_search(cost[None], obstacles[None], start[None], goal[None], **kwargs)
    return [tuple(c) for c in result.paths[0].tolist()], result.expanded[0], int(result.termination[0])


@pytest.mark.parametrize(
    ("moves", "corner_cutting", "exact"),
    [
        ("moore", True, False),
        ("moore", False, False),
        ("news", True, False),
        ("octile", True, True),
        ("octile", False, True),
        ("moore", True, True),
        ("octile", True, False),
    ],
)
def test_the_kernel_expands_and_returns_what_the_literal_rule_does(moves, corner_cutting, exact):
    rng = np.random.default_rng(3)
    for k, (obstacles, start, goal) in enumerate(random_problems(11, 25)):
        n = obstacles.shape[0]
        # unit costs (vanilla A*: many exact ties) half of the time, a guidance map (Neural A*) otherwise
        cost = (~obstacles).astype(F32) if k % 2 else rng.random((n, n)).astype(F32)
        g_ratio = (0.5, 1 / 3, 0.0, 0.8)[k % 4]
        want = oracle(cost, obstacles, start, goal, g_ratio, moves, corner_cutting, exact)
        path, expanded, term = search_one(
            cost, obstacles, start, goal, g_ratio=g_ratio, moves=moves, corner_cutting=corner_cutting, exact=exact
        )
        assert term == want[2], k
        assert path == want[0], k
        assert np.array_equal(expanded, want[1]), k


def test_where_exp_underflows_the_replica_orders_by_f():
    rng = np.random.default_rng(6)
    for k, (obstacles, start, goal) in enumerate(random_problems(12, 12, sizes=(6, 9))):
        n = obstacles.shape[0]
        cost = (200 + 300 * rng.random((n, n))).astype(F32)  # f / sqrt N far above 87: exp subnormal or 0
        want = oracle(cost, obstacles, start, goal, 0.5, "moore", True, False)
        path, expanded, term = search_one(cost, obstacles, start, goal, exact=False)
        assert (path, term) == (want[0], want[2]) and np.array_equal(expanded, want[1]), k
    for k, (obstacles, start, goal) in enumerate(random_problems(13, 12, sizes=(8, 9))):
        # greedy (g_ratio 0), f = h in [283, 294]: f / sqrt 8 in [100, 104], where float32 exp is a few units of
        # the smallest subnormal and cells of different f tie
        cost = (283 + 4 * rng.random((8, 8))).astype(F32)
        want = oracle(cost, obstacles, start, goal, 0.0, "moore", True, False)
        path, expanded, term = search_one(cost, obstacles, start, goal, g_ratio=0.0, exact=False)
        assert (path, term) == (want[0], want[2]) and np.array_equal(expanded, want[1]), k


def test_the_budget_stops_the_search_as_the_literal_rule_does():
    for obstacles, start, goal in random_problems(4, 10, sizes=(8, 10), density=(0.0, 0.1)):
        cost = (~obstacles).astype(F32)
        want = oracle(cost, obstacles, start, goal, 0.5, "moore", True, False, tmax=0.05)
        path, expanded, term = search_one(cost, obstacles, start, goal, tmax=0.05, exact=False)
        assert (path, term) == (want[0], want[2]) and np.array_equal(expanded, want[1])
        if term == STEP_LIMIT:
            assert expanded.sum() == int(0.05 * obstacles.size) and path == [tuple(start)]


@pytest.mark.parametrize("moves", ["octile", "moore", "news"])
@pytest.mark.parametrize("corner_cutting", [True, False])
def test_astar_paths_are_legal_and_cost_what_dijkstra_finds(moves, corner_cutting):
    if moves == "news" and not corner_cutting:
        pytest.skip("news has no diagonals: refused without corner cutting")
    problems = random_problems(7, 30, sizes=(5, 14))
    for obstacles, start, goal in problems:
        result = best_first_search(
            (~obstacles).astype(F32)[None], obstacles[None], start[None], goal[None], 0.5, moves, corner_cutting
        )
        want = dijkstra(obstacles, start, goal, moves, corner_cutting)
        path = result.paths[0].tolist()
        if math.isinf(want):
            assert result.termination[0] == STEP_LIMIT and path == [start.tolist()]
            continue
        assert result.termination[0] == GOAL and path[0] == start.tolist() and path[-1] == goal.tolist()
        model = move_model(moves)
        for (r, c), (r2, c2) in zip(path, path[1:]):
            assert [r2 - r, c2 - c] in model.deltas.tolist()
            assert legal(~obstacles, r, c, r2 - r, c2 - c, corner_cutting)
        assert path_cost(path, moves) == pytest.approx(want, abs=1e-9)


def test_the_planner_follows_the_maps_moves_and_plans_many_rows_at_once():
    problems = random_problems(8, 12, sizes=(10, 11))
    obstacles = np.stack([p[0] for p in problems])
    starts = np.stack([p[1] for p in problems])
    goals = np.stack([p[2] for p in problems])
    for moves in ("octile", "moore", "news"):
        planner = AStarPlanner(10).for_moves(moves)
        assert planner.moves == moves and planner.spec()["name"] == "astar"
        batched = planner.plan(obstacles, starts, goals)
        for i in range(len(problems)):  # each row as if searched alone
            alone = planner.plan_paths(obstacles[i : i + 1], starts[i : i + 1], goals[i : i + 1])
            assert alone.paths[0].tolist() == batched.paths[i].tolist()
            assert np.array_equal(alone.expanded[0], batched.expanded[i])
            assert batched.expanded[i][tuple(starts[i])]
    assert AStarPlanner(10).for_moves("moore").config == {"moves": "moore"}


def test_weighted_astar_is_never_better_and_sometimes_worse_with_fewer_expansions():
    problems = random_problems(9, 60, sizes=(12, 16), density=(0.2, 0.35))
    worse = fewer = 0
    for obstacles, start, goal in problems:
        n = obstacles.shape[0]
        exact = AStarPlanner(n, "moore").plan_paths(obstacles[None], start[None], goal[None])
        weighted = WeightedAStarPlanner(n, "moore", w=3.0).plan_paths(obstacles[None], start[None], goal[None])
        assert weighted.termination[0] == exact.termination[0]
        if exact.termination[0] != GOAL:
            continue
        a, b = path_cost(exact.paths[0], "moore"), path_cost(weighted.paths[0], "moore")
        assert b >= a
        worse += b > a
        fewer += weighted.expansions[0] < exact.expansions[0]
    assert worse > 0 and fewer > 0
    assert WeightedAStarPlanner(8, w=1.0).g_ratio == 0.5
    assert WeightedAStarPlanner(8, "news", w=2.5).for_moves("moore").config == {"moves": "moore", "w": 2.5}


def test_an_unreachable_goal_ends_the_search_when_the_open_list_is_empty():
    obstacles = np.zeros((6, 6), bool)
    obstacles[:, 3] = True  # a wall: the left three columns are cut off
    start, goal = np.array([2, 0]), np.array([2, 5])
    path, expanded, term = search_one((~obstacles).astype(F32), obstacles, start, goal)
    assert term == STEP_LIMIT and path == [(2, 0)]
    assert np.array_equal(expanded, ~obstacles & (np.indices((6, 6))[1] < 3))  # every cell it could reach


def test_start_at_the_goal_and_a_diagonal_between_two_obstacles():
    obstacles = np.array([[0, 1], [1, 0]], bool)
    cost = np.ones((2, 2), F32)
    assert search_one(cost, obstacles, np.array([1, 1]), np.array([1, 1]))[0] == [(1, 1)]
    path, _, term = search_one(cost, obstacles, np.array([0, 0]), np.array([1, 1]), moves="moore")
    assert term == GOAL and path == [(0, 0), (1, 1)]  # the authors' filter lets the diagonal pass
    _, _, term = search_one(cost, obstacles, np.array([0, 0]), np.array([1, 1]), moves="moore", corner_cutting=False)
    assert term == STEP_LIMIT


def test_the_replica_is_used_where_it_is_exact():
    assert replica_is_exact("moore", 32) and replica_is_exact("news", 300)
    assert not replica_is_exact("octile", 32) and not replica_is_exact("moore", 400)


def test_bad_arguments_are_refused_naming_them():
    obstacles = np.zeros((1, 4, 4), bool)
    starts, goals = np.array([[0, 0]]), np.array([[3, 3]])
    cost = np.ones((1, 4, 4), F32)
    with pytest.raises(InputError, match="cost has shape"):
        best_first_search(np.ones((1, 3, 3)), obstacles, starts, goals)
    with pytest.raises(InputError, match="cost has a negative"):
        best_first_search(-cost, obstacles, starts, goals)
    with pytest.raises(InputError, match="cost has a negative, NaN"):
        best_first_search(cost * np.nan, obstacles, starts, goals)
    with pytest.raises(InputError, match="g_ratio 1.5"):
        best_first_search(cost, obstacles, starts, goals, g_ratio=1.5)
    with pytest.raises(InputError, match="tmax 0.0"):
        best_first_search(cost, obstacles, starts, goals, tmax=0)
    with pytest.raises(InputError, match="moves 'news'"):
        best_first_search(cost, obstacles, starts, goals, moves="news", corner_cutting=False)
    with pytest.raises(InputError, match="w 0.5"):
        WeightedAStarPlanner(4, w=0.5)
    with pytest.raises(InputError, match="for 4x4 maps"):
        AStarPlanner(4).plan_paths(np.zeros((1, 5, 5), bool), starts, goals)


@pytest.mark.slow
@pytest.mark.parametrize("moves", ["octile", "moore", "news"])
def test_astar_is_never_harmful_and_weighted_astar_sometimes_is(moves):
    """Every valid one-obstacle attack (exhaustive) on cluttered random maps: A* re-routes optimally on each, so
    no pair is harmful; weighted A* does not."""
    rng = np.random.default_rng(2)
    n, b = 14, 16
    obstacles = rng.random((b, n, n)) < 0.3
    starts, goals = np.tile([1, 1], (b, 1)), np.tile([n - 2, n - 2], (b, 1))
    obstacles[:, 1, 1] = obstacles[:, n - 2, n - 2] = False
    reachable = np.isfinite([dijkstra(o, s, g, moves, True) for o, s, g in zip(obstacles, starts, goals)])
    obstacles, starts, goals = obstacles[reachable], starts[reachable], goals[reachable]
    harmful = {}
    for spec in ("astar", "wastar:w=3"):
        planner = load_planner(spec, n, moves=moves)
        pairs = make_attack("exhaustive", per_map=0).attack(obstacles, starts, goals, planner).pairs
        labels = label_pairs(pairs.path_o, pairs.path_a, pairs.goals, n).labels
        harmful[spec] = int((pairset_harm(pairs, labels).harm == "harmful").sum())
        assert len(pairs) > 100
    assert harmful["astar"] == 0
    assert harmful["wastar:w=3"] > 0
