"""Learned planners trained on `moore` and `news` maps: expert labels of the maps' movement model against the
brute-force oracle, the model's action set (news: 4 actions), the movement model in the training record and the
weights' record, planners that plan it, and a planner of one model refused (one line) on maps of another. Tiny data
(a few 8x8 maps, one epoch, a narrow model): cheap."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from tests.grid.oracle import optimal_action_mask
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.planners.gppn import save_gppn
from vinadv.planners.gppn.training import train_gppn
from vinadv.planners.imitation import TrainConfig, bits_to_mask, optimal_action_bits
from vinadv.planners.padding import pad_actions
from vinadv.planners.registry import load_planner
from vinadv.planners.vin.training import train_vin
from vinadv.planners.vin.weights import save_vin
from vinadv.planners.weights import trained_moves

OTHER = {"octile": "moore", "moore": "news", "news": "octile"}


@pytest.mark.parametrize("moves", ["moore", "news"])
def test_expert_labels_follow_the_maps_movement_model(moves):
    maps = generate_maps(3, 8, seed=5, n_starts=1, moves=moves)
    mask = bits_to_mask(torch.from_numpy(optimal_action_bits(maps))).numpy()
    for i in range(len(maps)):
        want = optimal_action_mask(maps.obstacles[i].tolist(), tuple(maps.goals[i]), True, moves)
        np.testing.assert_array_equal(mask[i], np.array(want), err_msg=f"{moves} map {i}")
    if moves == "news":  # a diagonal is never a label: the 4-action model's targets are its own actions
        assert not mask[..., 4:].any()


def _train(planner: str, moves: str, tmp_path):
    """A one-epoch planner trained on 4 maps of 8x8 of `moves`, saved; returns (path, record, maps)."""
    maps = generate_maps(4, 8, seed=1, n_starts=2, moves=moves)
    if planner == "vin":
        config = TrainConfig(epochs=1, batch_size=2, l_h=8, l_q=8, k=6)
        model, record = train_vin(maps, config, progress=False)
        save_vin(model, tmp_path / "w.pt", record)
    else:
        config = TrainConfig(epochs=1, batch_size=2, planner="gppn", l_h=4, k=4, kernel=3, lr=0.001)
        model, record = train_gppn(maps, config, progress=False)
        save_gppn(model, tmp_path / "w.pt", record)
    return tmp_path / "w.pt", record, maps


@pytest.mark.parametrize("planner", ["vin", "gppn"])
@pytest.mark.parametrize("moves", ["moore", "news"])
def test_a_planner_trained_on_a_movement_model_plans_it_and_refuses_others(planner, moves, tmp_path):
    path, record, maps = _train(planner, moves, tmp_path)
    n_actions = 4 if moves == "news" else 8
    assert record["moves"] == moves and record["model"]["n_actions"] == n_actions
    assert trained_moves(path, record) == moves
    loaded = load_planner(planner, 8, weights=str(path), moves=moves)
    assert loaded.moves == moves
    logits = loaded.logits(maps.obstacles, maps.goals)
    assert logits.shape == (4, 8, 8, 8)  # the contract's 8 actions; news' diagonals masked
    assert np.isneginf(logits[:, 4:]).all() == (moves == "news") and np.isfinite(logits[:, :n_actions]).all()
    result = loaded.plan(maps.obstacles, maps.starts, maps.goals)
    steps = np.abs(np.diff(result.paths.cells.astype(np.int64), axis=0))
    inside = np.ones(len(steps), dtype=bool)
    inside[result.paths.offsets[1:-1] - 1] = False  # the step from one path's end to the next path's start
    if moves == "news":  # a news planner moves N, S, E or W only
        assert (steps[inside].sum(axis=1) <= 1).all()
    other = OTHER[moves]
    with pytest.raises(InputError, match=f"planner '{planner}' plans {moves} moves .*the maps use '{other}' moves"):
        load_planner(planner, 8, weights=str(path), moves=other)


def test_an_octile_vin_starts_a_moore_training_and_a_news_one_is_refused(tmp_path):
    octile, _, _ = _train("vin", "octile", tmp_path)
    moore = generate_maps(4, 8, seed=2, n_starts=1, moves="moore")
    _, record = train_vin(
        moore, TrainConfig(epochs=1, batch_size=2, l_h=8, l_q=8, k=6, init=str(octile)), progress=False
    )
    assert record["moves"] == "moore" and record["init_moves"] == "octile"  # the same 8 actions: allowed, recorded
    news = generate_maps(4, 8, seed=2, n_starts=1, moves="news")
    with pytest.raises(InputError, match="n_actions=8.*n_actions=4"):
        train_vin(news, TrainConfig(epochs=1, batch_size=2, l_h=8, l_q=8, k=6, init=str(octile)), progress=False)


def test_weights_whose_actions_do_not_fit_their_model_are_refused(tmp_path):
    path, record, _ = _train("gppn", "news", tmp_path)
    from vinadv.planners.gppn import load_gppn  # noqa: PLC0415 (the file's model, relabelled below)

    save_gppn(load_gppn(path, size=8), tmp_path / "bad.pt", {**record, "moves": "moore"})  # 4 actions, 'moore'
    with pytest.raises(InputError, match="bad.pt: GPPN weights with 4 actions plan 'moore' moves, which have 8"):
        load_planner("gppn", 8, weights=str(tmp_path / "bad.pt"), moves="moore")


def test_pad_actions_masks_the_missing_moves_with_minus_infinity():
    logits = torch.randn(2, 4, 3, 3, requires_grad=True)
    padded = pad_actions(logits)
    assert padded.shape == (2, 8, 3, 3) and torch.equal(padded[:, :4], logits)
    assert torch.isneginf(padded[:, 4:]).all()
    torch.log_softmax(padded, dim=1)[:, 0].sum().backward()  # the masked moves give finite gradients
    assert torch.isfinite(logits.grad).all()
    full = torch.randn(1, 8, 2, 2)
    assert pad_actions(full) is full


def test_the_train_commands_record_the_model_and_the_planners_refuse_other_maps(tmp_path, capsys):
    generate_maps(4, 8, seed=1, n_starts=2, moves="news").save(tmp_path / "news.npz")
    generate_maps(3, 8, seed=4, n_starts=2).save(tmp_path / "octile.npz")
    out = tmp_path / "g.pt"
    argv = ["gppn", "train", "--data", str(tmp_path / "news.npz"), "--out", str(out), "--epochs", "1", "--quiet"]
    assert main([*argv, "--l-h", "4", "--k", "4", "--kernel", "3", "--batch-size", "2"]) == 0
    record = json.loads(out.with_suffix(".json").read_text())
    assert record["moves"] == record["data"]["moves"] == "news" and record["model"]["n_actions"] == 4
    capsys.readouterr()
    assert main(["eval", "--planner", "gppn", "--weights", str(out), "--data", str(tmp_path / "octile.npz")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "planner 'gppn' plans news moves" in err and "'octile' moves" in err
    assert (
        main(["eval", "--planner", "gppn", "--weights", str(out), "--data", str(tmp_path / "news.npz"), "--json"]) == 0
    )
    figures = json.loads(capsys.readouterr().out)
    assert figures["vinadv"]["rollouts"] == 8
