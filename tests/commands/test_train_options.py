"""The train commands' shared run (`vinadv.commands.train_options.train_and_save`): a run stopped by `--time-limit`
keeps its checkpoint, and `--resume` continues from it to the weights of an uninterrupted run (it used to be
removed, so `--resume` silently trained again from epoch 1). Tiny maps, two epochs: cheap."""

import pytest
import torch

from vinadv.cli import main
from vinadv.grid import generate_maps

TRAIN = {
    "neural-astar": ["--epochs", "2", "--batch-size", "3", "--depth", "1", "--seed", "3", "--val-fraction", "0.34"],
    "vin": ["--epochs", "2", "--batch-size", "4", "--seed", "2", "--val-fraction", "0.34", "--k", "4"],
}
MOVES = {"neural-astar": "moore", "vin": "octile"}


def _weights(path):
    return torch.load(path, weights_only=True)["state_dict"]


@pytest.mark.parametrize("planner", ["neural-astar", "vin"])
def test_a_time_limited_run_keeps_its_checkpoint_and_resume_continues_it(planner, tmp_path, capsys):
    maps = tmp_path / "maps.npz"
    generate_maps(6, 8, seed=5, n_starts=1, moves=MOVES[planner]).save(maps)
    straight, stopped = tmp_path / "straight.pt", tmp_path / "stopped.pt"
    base = [planner, "train", "--data", str(maps), *TRAIN[planner], "--threads", "1"]
    assert main([*base, "--out", str(straight), "--quiet"]) == 0
    assert not straight.with_name("straight.pt.ckpt").exists()  # a finished run removes its checkpoint
    assert main([*base, "--out", str(stopped), "--quiet", "--time-limit", "1e-9"]) == 0
    checkpoint = stopped.with_name("stopped.pt.ckpt")
    assert checkpoint.exists() and torch.load(checkpoint, weights_only=True)["epoch"] == 1
    capsys.readouterr()
    assert main([*base, "--out", str(stopped), "--resume"]) == 0
    out = capsys.readouterr().out
    assert f"resumed from {checkpoint} after epoch 1" in out and "epoch 1/2" not in out
    assert not checkpoint.exists()
    want, got = _weights(straight), _weights(stopped)
    assert want.keys() == got.keys() and want
    for key, value in want.items():
        assert torch.equal(value, got[key]), key
