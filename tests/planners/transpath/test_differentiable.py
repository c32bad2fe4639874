"""TransPath's differentiable mode: the same search as the compiled replica (the literal comparisons of both modes are
in test_planner.py), its straight-through gradient against the softmax's analytic derivative from a float64
replay, the maps' rule, an unreachable goal, and the planner's module."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from tests.planners.neural_astar.literal import free_neighbours
from vinadv.grid import generate_maps
from vinadv.planners.registry import load_planner
from vinadv.planners.transpath.differentiable import DIAGONAL, as_search_arrays, transpath_differentiable_search
from vinadv.planners.transpath.search import transpath_search


def small_problem(n: int, seed: int, mode: str):
    rng = np.random.default_rng(seed)
    free = rng.random((1, n, n)) > 0.2
    starts, goals = np.array([[0, 0]]), np.array([[n - 1, n - 2]])
    free[0, 0, 0] = free[0, n - 1, n - 2] = True
    low, high = (0.05, 1.5) if mode == "cf" else (0.0, 1.0)  # cf: some factors below the 0.1 floor
    return free, starts, goals, rng.uniform(low, high, (1, n, n)).astype(np.float32)


def differentiable(values, free, starts, goals, mode, corner_cutting=True):
    return transpath_differentiable_search(
        values,
        torch.from_numpy(free.astype(np.float32)),
        torch.from_numpy(starts),
        torch.from_numpy(goals),
        mode,
        corner_cutting,
    )


@pytest.mark.parametrize("mode", ["cf", "f"])
def test_both_modes_agree_on_random_values_with_and_without_corner_cutting(mode):
    """Random values on 12 small maps (some goals cut off): the same paths, reached flags and expanded cells as the
    compiled replica, under both rules."""
    rng = np.random.default_rng(4)
    n, b = 12, 12
    free = rng.random((b, n, n)) > 0.35
    starts, goals = rng.integers(0, n, (b, 2)), rng.integers(0, n, (b, 2))
    free[np.arange(b), starts[:, 0], starts[:, 1]] = True
    free[np.arange(b), goals[:, 0], goals[:, 1]] = True
    values = rng.uniform(0.0, 1.0, (b, n, n)).astype(np.float32)
    for rule in (True, False):
        compiled = transpath_search(values, ~free, starts, goals, mode, rule, focal_exp=np.exp(values))
        with torch.no_grad():
            out = differentiable(torch.from_numpy(values), free, starts, goals, mode, rule)
        paths, reached, expanded = as_search_arrays(out, starts, goals)
        assert np.array_equal(reached, compiled.reached) and np.array_equal(expanded, compiled.expanded)
        assert all(np.array_equal(p, q) for p, q in zip(paths, compiled.paths, strict=True))
        assert reached.any() and not reached.all()  # both kinds occur


def test_an_unreachable_goal_ends_unsolved_without_nan():
    free = np.ones((1, 6, 6), dtype=bool)
    free[0, :, 3] = False
    out = differentiable(torch.full((1, 6, 6), 0.5), free, np.array([[0, 0]]), np.array([[5, 5]]), "cf")
    assert not out.reached[0] and torch.isfinite(out.histories).all()
    assert int(out.histories[0].sum()) == 18  # every cell on the start's side was selected
    assert out.path_maps[0].sum() == 1 and out.path_maps[0, 5, 5] == 1


def replayed_gradient(mode, values, free, start, goal, weights):
    """d sum(w * histories) / d values from a float64 replay of the search's selections: at each selection with
    shares y over the candidates C (cf: the open cells, y = softmax(-f / sqrt N); f: the focal list, y = softmax(v)),
    dy_i/dz_j = y_i (delta_ij - y_j) for the logits z, so the step adds y_j (w_j - <w, y>) dz_j/dv_j: cf, z = -f /
    sqrt N with f = 0.5 g + 0.501 octile / max(k, 0.1), dz/dk = 0.501 octile / (sqrt N k^2) where k > 0.1, else 0;
    f, z = v."""
    n = values.shape[-1]
    v = values.astype(np.float64).reshape(-1)
    r, c = np.divmod(np.arange(n * n), n)
    dr, dc = np.abs(r - goal[0]), np.abs(c - goal[1])
    octile = np.minimum(dr, dc) * math.sqrt(2) + np.abs(dr - dc)
    k = np.maximum(v, 0.1)
    g = np.zeros(n * n)
    w = weights.reshape(-1).astype(np.float64)
    open_, closed = {start[0] * n + start[1]}, set()
    expected = np.zeros(n * n)
    while open_:
        cells = np.array(sorted(open_))
        if mode == "cf":
            f = 0.5 * g[cells] + 0.501 * octile[cells] / k[cells]
            z = -f / math.sqrt(n)
            dz = np.where(v[cells] > 0.1, 0.501 * octile[cells] / (math.sqrt(n) * k[cells] ** 2), 0.0)
        else:
            f = 0.5 * g[cells] + 0.5 * octile[cells]
            cells = cells[f <= f.min() * 100]
            z, dz = v[cells], np.ones(len(cells))
        y = np.exp(z - z.max())
        y /= y.sum()
        expected[cells] += y * (w[cells] - (w[cells] * y).sum()) * dz
        sel = int(cells[np.argmax(y)])
        closed.add(sel)
        open_.discard(sel)
        if sel == goal[0] * n + goal[1]:
            break
        for u, du, dv in free_neighbours(free, sel, n):
            g2 = g[sel] + (DIAGONAL if du and dv else 1.0)
            if u not in closed and (u not in open_ or g[u] > g2):
                g[u] = g2
                open_.add(u)
    return expected.reshape(n, n), closed


@pytest.mark.parametrize("mode", ["cf", "f"])
def test_the_straight_through_gradient_is_the_softmax_derivative_summed_over_steps(mode):
    free, starts, goals, values = small_problem(7, seed=11, mode=mode)
    v = torch.from_numpy(values).requires_grad_(True)
    out = differentiable(v, free, starts, goals, mode)
    weights = np.random.default_rng(0).standard_normal((7, 7)).astype(np.float32)
    (out.histories[0] * torch.from_numpy(weights)).sum().backward()
    expected, closed = replayed_gradient(mode, values[0], free[0], starts[0], goals[0], weights)
    assert bool(out.reached[0])
    assert sorted(closed) == np.flatnonzero(out.histories.detach()[0].numpy() > 0.5).tolist()
    np.testing.assert_allclose(v.grad[0].numpy(), expected, rtol=1e-4, atol=1e-6)
    assert np.abs(expected).max() > 1e-3  # a gradient there is


@pytest.mark.slow
def test_the_planner_s_modes_agree_and_its_module_differentiates_to_the_obstacles():
    """Two generated 64x64 maps, each model: `plan_paths_differentiable` gives `plan`'s paths and expansions; the
    saliency module's path map is the plan's path in value, with a finite gradient to the map that is not zero."""
    torch.set_num_threads(1)
    maps = generate_maps(2, 64, seed=2, n_starts=1)
    obstacles, starts, goals = maps.obstacles, maps.starts[:, 0], maps.goals
    for name in ("transpath-cf", "transpath-focal"):
        planner = load_planner(name, 64)
        exact = planner.plan_paths(obstacles, starts, goals)
        diff = planner.plan_paths_differentiable(obstacles, starts, goals)
        assert diff.paths == exact.paths and np.array_equal(diff.expanded, exact.expanded)
        x = torch.from_numpy(obstacles[:1].astype(np.float32)).requires_grad_(True)
        path_map = planner.differentiable_paths(x, torch.from_numpy(starts[:1]), torch.from_numpy(goals[:1]))
        on_path = np.zeros((64, 64), dtype=bool)
        on_path[tuple(exact.paths[0].T)] = True
        assert np.array_equal(path_map.detach()[0].numpy() > 0.5, on_path)
        (grad,) = torch.autograd.grad(path_map.sum(), x)
        assert torch.isfinite(grad).all() and grad.abs().max() > 0
