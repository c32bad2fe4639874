"""`+d4` planners: the dihedral average against an equivariant oracle, its equivariance on a planner that is not,
and the registry's `SPEC+d4`."""

import json

import numpy as np
import pytest
import torch
from torch import nn

from vinadv.cli import main
from vinadv.grid import generate_maps
from vinadv.grid.actions import ACTION_DELTAS
from vinadv.grid.dihedral import INVERSE, transform_actions, transform_cells, transform_grids
from vinadv.planners.gppn import GPPN, GPPNConfig
from vinadv.planners.interface import PlannerError
from vinadv.planners.registry import load_planner
from vinadv.planners.symmetric import DihedralAverage

SIZE = 9


@pytest.mark.parametrize("g", range(8))
def test_actions_move_as_their_cells(g):
    # a move from a cell to its neighbour, both cells transformed, is the move of the renamed action
    cell = np.array([[4, 4]])
    perm = transform_actions(g)
    for a, delta in enumerate(ACTION_DELTAS):
        moved = transform_cells(cell + delta, SIZE, g) - transform_cells(cell, SIZE, g)
        assert moved[0].tolist() == ACTION_DELTAS[perm[a]].tolist()
    grid = np.arange(2 * SIZE * SIZE).reshape(2, SIZE, SIZE)
    assert np.array_equal(transform_grids(transform_grids(grid, g), INVERSE[g]), grid)


class Greedy(nn.Module):
    """Logits = minus the obstacle-free octile distance to the goal after each move: equivariant by construction."""

    def forward(self, obstacles, goals):
        n = obstacles.shape[-1]
        rows = torch.arange(n).view(1, n, 1)
        cols = torch.arange(n).view(1, 1, n)
        out = []
        for dr, dc in ACTION_DELTAS.tolist():
            r = (rows + dr - goals[:, 0].view(-1, 1, 1)).abs().double()
            c = (cols + dc - goals[:, 1].view(-1, 1, 1)).abs().double()
            out.append(-(torch.maximum(r, c) + (2**0.5 - 1) * torch.minimum(r, c)) + 0.1 * obstacles)
        return torch.stack(out, dim=1)


def test_an_equivariant_planner_is_its_own_average():
    maps = generate_maps(6, SIZE, seed=2)
    obs = torch.from_numpy(maps.obstacles.astype(np.float64))
    goals = torch.from_numpy(maps.goals)
    plain = torch.log_softmax(Greedy()(obs, goals), dim=1)
    torch.testing.assert_close(DihedralAverage(Greedy())(obs, goals), plain)


def test_the_average_is_equivariant_and_differentiable():
    torch.manual_seed(0)
    gppn = GPPN(GPPNConfig(k=5, l_h=6)).double()
    model = DihedralAverage(gppn)
    maps = generate_maps(3, SIZE, seed=4)
    obs = torch.from_numpy(maps.obstacles.astype(np.float64)).requires_grad_()
    out = model(obs, torch.from_numpy(maps.goals))
    plain = torch.log_softmax(gppn(obs, torch.from_numpy(maps.goals)), dim=1)
    assert (out - plain).abs().max() > 1e-3  # the untrained GPPN itself is not equivariant
    for g in range(8):
        moved = model(
            transform_grids(obs, g).contiguous(), torch.from_numpy(transform_cells(maps.goals, SIZE, g))
        )  # (B, 8, N, N) on the moved map: action perm[a] at cell g(p) is action a at p
        back = transform_grids(moved, INVERSE[g], axes=(2, 3))[:, transform_actions(g)]
        torch.testing.assert_close(back, out)
    out[:, 0].sum().backward()
    assert obs.grad is not None and obs.grad.abs().sum() > 0


def test_registry_spec(tmp_path, capsys):
    plain, sym = load_planner("gppn", 28), load_planner("gppn+d4", 28)
    assert sym.name == "gppn+d4" and sym.checksum == plain.checksum
    assert sym.config == {**plain.config, "average": "d4"}
    assert isinstance(sym.module, DihedralAverage) and sym.logits_module is sym.module
    vin = load_planner("vin+d4", 28)
    assert vin.name == "vin+d4" and vin.checksum == load_planner("vin", 28).checksum
    custom = load_planner("examples/my_planner.py:make+d4", 12)
    assert custom.name == "examples/my_planner.py:make+d4"
    with pytest.raises(PlannerError, match="'optimal' has no torch module"):
        load_planner("optimal+d4", 28)
    for bad in ("+d4", "gppn+d4+d4"):
        with pytest.raises(PlannerError, match="follows one planner"):
            load_planner(bad, 28)
    with pytest.raises(PlannerError, match="takes no weights"):
        load_planner("optimal+d4", 28, weights="w.pt")
    # from the command line: the run of a planner spec, its name in the figures
    assert main(["eval", "--planner", "vin+d4", "--n", "3", "--size", "28", "--starts", "2", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["planner"]["name"] == "vin+d4" and figures["vinadv"]["rollouts"] == 6
    assert main(["planners", "--json"]) == 0
    assert "+d4" in json.loads(capsys.readouterr().out)["symmetric"]
