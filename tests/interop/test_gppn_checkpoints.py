"""Checkpoints of the GPPN authors' code as vinadv GPPN planners: `vinadv gppn import-weights`."""

import json

import numpy as np
import pytest
import torch

from tests.planners.gppn.test_gppn import plain_gppn
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.grid.actions import ACTION_DELTAS
from vinadv.interop.checkpoints import gppn_from_checkpoint
from vinadv.planners.gppn import GPPN, GPPNConfig, input_maps
from vinadv.planners.registry import load_planner

#: the GPPN code's Moore mechanism: actions N, E, W, S, NE, NW, SE, SW as (row, col) moves, rows growing south
GPPN_MOORE = [(-1, 0), (0, 1), (0, -1), (1, 0), (-1, 1), (-1, -1), (1, 1), (1, -1)]


def authors_checkpoint(path, k=6, l_h=8, f=5, n_actions=8, in_channels=2):
    """A checkpoint as the GPPN code's train.py writes it: numpy float64 state dicts, extra lists."""
    torch.manual_seed(3)
    theirs = GPPN(GPPNConfig(k=k, l_h=l_h, f=f, n_actions=n_actions))
    if in_channels != 2:
        theirs.hid = torch.nn.Conv2d(in_channels, l_h, 3, padding=1)
    state = {key: value.detach().double().numpy() for key, value in theirs.state_dict().items()}
    torch.save({"model": {key: v * 0 for key, v in state.items()}, "best_model": state, "v_total_success": [0.9]}, path)
    return theirs


def test_imported_weights_give_the_authors_logits_in_vinadvs_action_order(tmp_path, capsys):
    theirs = authors_checkpoint(tmp_path / "gppn.final.pth")
    out = tmp_path / "gppn.pt"
    assert (
        main(["gppn", "import-weights", str(tmp_path / "gppn.final.pth"), "--k", "6", "--out", str(out), "--json"]) == 0
    )
    summary = json.loads(capsys.readouterr().out)
    assert summary["config"] == {"k": 6, "l_h": 8, "f": 5, "n_actions": 8}
    assert summary["imported_from"]["entry"] == "best_model"
    planner = load_planner("gppn", 12, weights=str(out))
    maps = generate_maps(5, 12, seed=2, n_starts=1)
    ours = planner.logits(maps.obstacles, maps.goals)
    obstacles = torch.from_numpy(maps.obstacles.astype(np.float32))
    x = input_maps(obstacles, torch.from_numpy(maps.goals))
    with torch.no_grad():
        reference = plain_gppn(theirs, x[:, 0], x[:, 1]).numpy()  # the authors' model, in their action order
    for g, delta in enumerate(GPPN_MOORE):
        a = [tuple(d) for d in ACTION_DELTAS.tolist()].index(delta)
        np.testing.assert_allclose(ours[:, a], reference[:, g], rtol=1e-4, atol=1e-5)


def test_other_models_and_mechanisms_are_refused(tmp_path, capsys):
    authors_checkpoint(tmp_path / "news.pth", n_actions=4)
    with pytest.raises(InputError, match="4 actions"):
        gppn_from_checkpoint(tmp_path / "news.pth", k=6)
    authors_checkpoint(tmp_path / "3d.pth", in_channels=5)
    with pytest.raises(InputError, match="3-D"):
        gppn_from_checkpoint(tmp_path / "3d.pth", k=6)
    torch.save({"model": {"h.weight": np.zeros((4, 2, 3, 3))}}, tmp_path / "vin.pth")
    assert main(["gppn", "import-weights", str(tmp_path / "vin.pth"), "--k", "6", "--out", str(tmp_path / "o.pt")]) == 2
    assert "not a GPPN checkpoint" in capsys.readouterr().err
    # the authors' checkpoint given straight to --planner gppn: the one-line hint to convert it
    authors_checkpoint(tmp_path / "raw.pth")
    assert main(["eval", "--planner", "gppn", "--weights", str(tmp_path / "raw.pth"), "--n", "2", "--size", "8"]) == 2
    assert "gppn import-weights" in capsys.readouterr().err
