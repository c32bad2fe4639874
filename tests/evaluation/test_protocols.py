"""The kentsommer and GPPN protocols against plain-Python re-readings of the two codebases' evaluation loops."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from tests.interop.conftest import borderless
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.evaluation.planner_metrics import evaluate_vin
from vinadv.evaluation.protocols import evaluate_protocol, gppn_protocol
from vinadv.grid import MapSet, generate_maps
from vinadv.grid.shortest_paths import expert_paths
from vinadv.planners.classical.optimal import OptimalPlanner
from vinadv.planners.interface import PlannerError
from vinadv.planners.vin import make_input
from vinadv.testing.planners import planning_vin

OURS = [(-1, 0), (1, 0), (0, 1), (0, -1), (-1, 1), (-1, -1), (1, 1), (1, -1)]


@pytest.fixture(scope="module")
def model():
    return planning_vin(10, seed=7, noise=0.5)


@pytest.fixture(scope="module", params=["border", "borderless"])
def maps(request):
    base = generate_maps(10, 10, seed=12, n_starts=3)
    if request.param == "border":
        return base
    obstacles = borderless(base, seed=4)
    costs, expert = expert_paths(obstacles, base.goals, base.starts)
    return MapSet(obstacles=obstacles, goals=base.goals, starts=base.starts, expert_costs=costs, expert=expert)


def port_logits(model, obstacles, goal, r, c, prior):
    """What the port's test.py does at each step: the whole network on the map, logits at the agent's cell."""
    x = make_input(obstacles[None], np.array([goal]))
    x[0, 1] = torch.where(x[0, 1] == 0, torch.tensor(prior), x[0, 1])
    with torch.no_grad():
        return model(x, torch.tensor([r]), torch.tensor([c]))[0].numpy()


@pytest.mark.parametrize("prior", [-1.0, 0.0])
def test_kentsommer_protocol_matches_the_ports_loop(model, maps, prior):
    got = evaluate_protocol(model, maps, "kentsommer", prior=prior)
    n = maps.size
    correct = total = hits = states = 0
    for i in range(len(maps)):
        goal = tuple(int(v) for v in maps.goals[i])
        for s in range(maps.n_starts):
            path = [tuple(int(v) for v in cell) for cell in maps.expert_path(i, s)]
            for (r, c), (r2, c2) in zip(path[:-1], path[1:]):  # single-label accuracy on trajectory states
                hits += int(
                    np.argmax(port_logits(model, maps.obstacles[i], goal, r, c, prior)) == OURS.index((r2 - r, c2 - c))
                )
                states += 1
            big_l = len(path) * 2
            r, c = path[0]
            for _ in range(1, big_l):
                a = int(np.argmax(port_logits(model, maps.obstacles[i], goal, r, c, prior)))
                nr, nc = max(0, min(r + OURS[a][0], n - 1)), max(0, min(c + OURS[a][1], n - 1))
                if not maps.obstacles[i, nr, nc]:
                    r, c = nr, nc
                if (r, c) == goal:
                    break
            correct += (r, c) == goal
            total += 1
    assert got["rollouts"] == total and got["trajectory_states"] == states
    assert got["success_rate"] == pytest.approx(correct / total)
    assert got["action_accuracy_single_label"] == pytest.approx(hits / states)


def brute_gppn_figures(maps, policies) -> tuple[float, float]:
    """GPPN's (%Suc, %Opt) from the argmax action of every cell, `policies (B, N, N)`, in plain Python: breadth-first
    search for the move counts, every free cell's policy followed step by step."""
    n = maps.size
    opt_sum = suc_sum = 0.0
    for i in range(len(maps)):
        obstacles, goal = maps.obstacles[i], tuple(int(v) for v in maps.goals[i])
        policy = policies[i]
        dist = {goal: 0}  # breadth-first search, every Moore move costs 1
        frontier = [goal]
        while frontier:
            nxt = []
            for r, c in frontier:
                for dr, dc in OURS:
                    rr, cc = r + dr, c + dc
                    if 0 <= rr < n and 0 <= cc < n and not obstacles[rr, cc] and (rr, cc) not in dist:
                        dist[(rr, cc)] = dist[(r, c)] + 1
                        nxt.append((rr, cc))
            frontier = nxt
        optimal = success = free = 0
        for r0 in range(n):
            for c0 in range(n):
                if obstacles[r0, c0]:
                    continue
                free += 1
                r, c, moves = r0, c0, 0
                while (r, c) != goal and moves <= n * n:
                    dr, dc = OURS[policy[r, c]]
                    if 0 <= r + dr < n and 0 <= c + dc < n and not obstacles[r + dr, c + dc]:
                        r, c = r + dr, c + dc
                    moves += 1
                reached = (r, c) == goal
                success += reached
                optimal += ((r0, c0) not in dist) or (reached and moves == dist[(r0, c0)])
        opt_sum += optimal / free
        suc_sum += success / free
    return suc_sum / len(maps), opt_sum / len(maps)


def test_gppn_protocol_matches_gppns_definitions(model, maps):
    got = evaluate_protocol(model, maps, "gppn")
    with torch.no_grad():
        policies = np.argmax(model.action_logits(make_input(maps.obstacles, maps.goals)).numpy(), axis=-1)
    suc, opt = brute_gppn_figures(maps, policies)
    assert got["percent_optimal"] == pytest.approx(opt)
    assert got["percent_success"] == pytest.approx(suc)
    assert 0 < got["percent_success"] < 1


def test_gppn_protocol_plans_the_maps_movement_model():
    # the exact planner for the maps' model is optimal from every cell, as GPPN counts moves (NEWS's on news maps);
    # the planner is the one for the maps' moves, not the octile default's (which would cut across)
    news = generate_maps(4, 12, seed=5, n_starts=1, moves="news")
    got = gppn_protocol(OptimalPlanner(12), news)
    reachable = []  # per map, the share of free cells with a NEWS path to the goal (breadth-first, plain Python)
    for obstacles, goal in zip(news.obstacles, news.goals):
        seen, frontier = {tuple(goal)}, [tuple(goal)]
        while frontier:
            r, c = frontier.pop()
            for nr, nc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
                if 0 <= nr < 12 and 0 <= nc < 12 and not obstacles[nr, nc] and (nr, nc) not in seen:
                    seen.add((nr, nc))
                    frontier.append((nr, nc))
        reachable.append(len(seen) / (~obstacles).sum())
    assert got["percent_optimal"] == 1.0 and got["percent_success"] == pytest.approx(np.mean(reachable))
    with pytest.raises(PlannerError, match="plans octile moves .* the maps use 'news' moves"):
        gppn_protocol(planning_vin(12), news)


def test_vinadv_protocol_is_evaluate_vin(model, maps):
    got = evaluate_protocol(model, maps, "vinadv")
    assert got.pop("protocol") == "vinadv" and got == evaluate_vin(model, maps)


def test_bad_protocol_options(model, maps):
    with pytest.raises(InputError, match="protocol must be one of vinadv, kentsommer, gppn"):
        evaluate_protocol(model, maps, "other")
    with pytest.raises(InputError, match="prior applies to the kentsommer protocol only"):
        evaluate_protocol(model, maps, "gppn", prior=0.0)


def test_cli_vin_eval_protocol(tmp_path, capsys):
    maps = generate_maps(5, 28, seed=3, n_starts=2)
    maps.save(tmp_path / "m.npz")
    assert main(["vin", "eval", "--data", str(tmp_path / "m.npz"), "--protocol", "gppn", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["protocol"] == "gppn" and 0 <= out["percent_success"] <= 1
    assert main(["vin", "eval", "--data", str(tmp_path / "m.npz"), "--protocol", "kentsommer", "--prior", "0"]) == 0
    assert "single-label" in capsys.readouterr().out
    assert main(["vin", "eval", "--data", str(tmp_path / "m.npz"), "--prior", "0"]) == 2
