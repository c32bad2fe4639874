"""The differentiable search against the literal loop of the published equations (paths, expansions, Tmax), its
straight-through gradient against the softmax's analytic derivative, and its edge cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from tests.planners.neural_astar.literal import literal_search
from vinadv.planners.classical.astar import best_first_search
from vinadv.planners.neural_astar.differentiable import authors_heuristic, differentiable_astar


def random_problems(b: int, n: int, seed: int, density: float = 0.3):
    """B random maps with random float32 costs in (0, 1), a start and a goal on free cells, not necessarily
    connected."""
    rng = np.random.default_rng(seed)
    free = rng.random((b, n, n)) > density
    starts, goals = rng.integers(0, n, (b, 2)), rng.integers(0, n, (b, 2))
    free[np.arange(b), starts[:, 0], starts[:, 1]] = True
    free[np.arange(b), goals[:, 0], goals[:, 1]] = True
    cost = rng.random((b, n, n)).astype(np.float32)
    return free, starts, goals, cost


def search(free, starts, goals, cost, tmax=1.0):
    return differentiable_astar(
        torch.from_numpy(cost),
        torch.from_numpy(free.astype(np.float32)),
        torch.from_numpy(starts),
        torch.from_numpy(goals),
        tmax=tmax,
    )


def test_heuristic_is_chebyshev_plus_a_thousandth_of_euclid():
    h = authors_heuristic(torch.tensor([[2, 5]]), 7)[0].double().numpy()
    r, c = np.mgrid[:7, :7]
    expected = np.maximum(abs(r - 2), abs(c - 5)) + 0.001 * np.hypot(r - 2, c - 5)
    np.testing.assert_allclose(h, expected, rtol=1e-6)


@pytest.mark.parametrize("unit", [False, True], ids=["guidance-costs", "vanilla"])
def test_paths_and_expansions_equal_the_literal_loop(unit):
    free, starts, goals, cost = random_problems(24, 11, seed=3, density=0.5)
    if unit:
        cost = np.ones_like(cost)
    out = search(free, starts, goals, cost)
    paths = out.paths(starts, goals)
    for b in range(len(free)):
        path, expanded, reached = literal_search(torch.from_numpy(cost[b]), free[b], starts[b], goals[b])
        assert bool(out.reached[b]) == reached, b
        assert np.array_equal(out.histories[b].numpy() > 0.5, expanded), b
        assert [tuple(p) for p in paths[b].tolist()] == path, b
        path_map = np.zeros_like(expanded)
        if reached:
            path_map[tuple(np.array(path).T)] = True
        else:
            path_map[tuple(goals[b])] = True  # the authors' backtrack from a goal never opened
        assert np.array_equal(out.path_maps[b].numpy() > 0.5, path_map), b
    assert out.reached.any() and not out.reached.all()  # both kinds occur on these maps


def test_tmax_limits_the_selections_as_the_literal_loop():
    free, _, _, cost = random_problems(12, 12, seed=8, density=0.15)
    starts, goals = np.tile([[0, 0]], (12, 1)), np.tile([[11, 11]], (12, 1))
    goals[:4] = [[1, 2], [2, 2], [3, 1], [0, 4]]  # near: reached within the budget
    free[:, 0, 0] = free[:, 11, 11] = True
    free[np.arange(4), goals[:4, 0], goals[:4, 1]] = True
    out = search(free, starts, goals, cost, tmax=0.1)
    budget = int(0.1 * 12 * 12)
    for b in range(len(free)):
        _, expanded, reached = literal_search(torch.from_numpy(cost[b]), free[b], starts[b], goals[b], budget)
        assert bool(out.reached[b]) == reached and np.array_equal(out.histories[b].numpy() > 0.5, expanded), b
    assert out.reached.any() and not out.reached.all()


def test_a_batch_gives_what_each_map_gives_alone():
    free, starts, goals, cost = random_problems(6, 10, seed=4)
    batch = search(free, starts, goals, cost)
    for b in range(6):
        alone = search(free[b : b + 1], starts[b : b + 1], goals[b : b + 1], cost[b : b + 1])
        assert torch.equal(alone.histories[0], batch.histories[b]) and torch.equal(
            alone.path_maps[0], batch.path_maps[b]
        )


def test_an_unreachable_goal_ends_unsolved_without_nan():
    free = np.ones((1, 6, 6), dtype=bool)
    free[0, :, 3] = False  # a wall between start and goal
    out = search(free, np.array([[0, 0]]), np.array([[5, 5]]), np.full((1, 6, 6), 0.5, np.float32))
    assert not out.reached[0] and torch.isfinite(out.histories).all()
    assert int(out.histories[0].sum()) == 18  # every cell on the start's side was expanded
    assert out.path_maps[0].sum() == 1 and out.path_maps[0, 5, 5] == 1


def test_the_straight_through_gradient_is_the_softmax_derivative_summed_over_steps():
    """d sum(w * histories) / d cost_j = sum over selections of -(1 - g_ratio) / sqrt(N) * y_j (w_j - <w, y>), y
    the softmax share of that selection (its open cells), from a literal replay of the search."""
    free, starts, goals, cost = random_problems(1, 7, seed=11, density=0.2)
    c = torch.from_numpy(cost).requires_grad_(True)
    out = differentiable_astar(
        c, torch.from_numpy(free.astype(np.float32)), torch.from_numpy(starts), torch.from_numpy(goals)
    )
    w = torch.from_numpy(np.random.default_rng(0).standard_normal((1, 7, 7)).astype(np.float32))
    (out.histories * w).sum().backward()
    # replay with the same selections, in float64, collecting each step's share y over the open cells
    n = 7
    h = authors_heuristic(torch.from_numpy(goals), n)[0].double().reshape(-1) + c.detach()[0].double().reshape(-1)
    g = np.zeros(n * n)
    open_, closed = {int(starts[0, 0]) * n + int(starts[0, 1])}, set()
    goal = int(goals[0, 0]) * n + int(goals[0, 1])
    wf = w[0].double().reshape(-1).numpy()
    expected = np.zeros(n * n)
    cf = cost[0].reshape(-1).astype(np.float64)
    while open_:
        cells = np.array(sorted(open_))
        f = 0.5 * g[cells] + 0.5 * h.numpy()[cells]
        y = np.exp(-(f - f.min()) / math.sqrt(n))
        y /= y.sum()
        expected[cells] += -0.5 / math.sqrt(n) * y * (wf[cells] - (wf[cells] * y).sum())
        v = cells[np.argmax(y)]
        closed.add(v)
        open_.discard(v)
        if v == goal:
            break
        r, col = divmod(v, n)
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr, cc = r + dr, col + dc
                if (dr or dc) and 0 <= rr < n and 0 <= cc < n and free[0, rr, cc]:
                    u = rr * n + cc
                    if u not in closed and (u not in open_ or g[u] > g[v] + cf[v]):
                        g[u] = g[v] + cf[v]
                        open_.add(u)
    assert bool(out.reached[0])
    assert np.array_equal(np.isin(np.arange(n * n), list(closed)), out.histories.detach()[0].reshape(-1).numpy() > 0.5)
    np.testing.assert_allclose(c.grad[0].reshape(-1).numpy(), expected, rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("scale", [2000.0, 60.0], ids=["all-zero", "subnormal"])
def test_where_exp_is_subnormal_or_zero_the_smallest_f_goes_first_as_in_the_exact_mode(scale):
    """scale 2000: f / sqrt(N) far above 104 from the first step, every exp(-f / sqrt N) is 0 in float32; scale 60:
    the search passes from normal through subnormal values (f / sqrt N about 87 to 104) to 0 as g grows."""
    free, starts, goals, noise = random_problems(8, 9, seed=5, density=0.2)
    starts[:4], goals[:4] = [0, 0], [8, 8]  # long searches
    free[:4, 0, 0] = free[:4, 8, 8] = True
    cost = (scale + noise).astype(np.float32)
    out = search(free, starts, goals, cost)
    exact = best_first_search(cost, ~free, starts, goals, 0.5, "moore", True, exact=False)
    assert np.array_equal(out.histories.numpy() > 0.5, exact.expanded)
    assert np.array_equal(out.reached.numpy(), exact.reached)
    assert all(np.array_equal(a, b) for a, b in zip(out.paths(starts, goals), exact.paths))
    # the regime was entered: f / sqrt(N) of some goal above 87 (exp below the smallest normal float32)
    f_goal = [0.5 * cost[b][tuple(p[:-1].T)].sum() + 0.5 * cost[b][tuple(goals[b])] for b, p in enumerate(exact.paths)]
    assert max(f_goal) / 3 > 87


def test_solved_gradients_change_gradients_of_solved_maps_only_not_values():
    # map 0 is solved in two selections, map 1 searches on: with the authors' batched gradient map 0 keeps adding
    # the softmax term after its goal (off the goal cell); values and map 1's gradient stay the same
    free = np.ones((2, 6, 6), dtype=bool)
    starts, goals = np.array([[0, 0], [0, 0]]), np.array([[1, 1], [5, 5]])
    cost = np.random.default_rng(1).random((2, 6, 6)).astype(np.float32)
    grads, values = [], []
    for solved in (False, True):
        c = torch.from_numpy(cost).requires_grad_(True)
        out = differentiable_astar(
            c,
            torch.from_numpy(free.astype(np.float32)),
            torch.from_numpy(starts),
            torch.from_numpy(goals),
            solved_gradients=solved,
        )
        weights = torch.from_numpy(np.random.default_rng(2).random((2, 6, 6)).astype(np.float32))
        (out.histories * weights).sum().backward()
        grads.append(c.grad.clone())
        values.append(out.histories.detach().clone())
    assert torch.equal(values[0], values[1])
    assert torch.equal(grads[0][1], grads[1][1])
    assert not torch.allclose(grads[0][0], grads[1][0])
