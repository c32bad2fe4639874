"""TransPath's network and weights: the authors' state dicts read by the allow-list reader and checked key by key,
the restated forward against the plain functional one (bit for bit), the shipped conversions, the import command and
its record, the refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from tests.needs import public_data
from tests.planners.transpath.literal import WEIGHTS, example_tasks, plain_forward, state
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.planners.transpath.checkpoint import from_authors_state_dict
from vinadv.planners.transpath.model import TransPath, load_transpath, positional_grid
from vinadv.planners.weights import weights_checksum


@pytest.mark.parametrize("mode", ["cf", "f"])
def test_the_forward_equals_the_plain_one_bit_for_bit_on_the_examples(mode):
    torch.set_num_threads(1)
    obstacles, starts, goals = (a[:3] for a in example_tasks()[:3])  # one batch of three, as the authors batch
    model = from_authors_state_dict(public_data(WEIGHTS[mode]), mode)
    s = None if mode == "cf" else starts
    with torch.no_grad():
        ours = model.outputs(
            torch.from_numpy(obstacles.astype(np.float32)), torch.from_numpy(starts), torch.from_numpy(goals)
        )
        plain = plain_forward(state(mode), obstacles, s, goals)[:, 0]
    assert torch.equal(ours, plain)
    assert 0 <= float(ours.min()) and float(ours.max()) <= 1  # tanh reaches -1 in float32: a factor 0


def test_the_focal_model_reads_the_start_and_the_cf_model_does_not():
    obstacles, starts, goals, _ = example_tasks()
    o, g = torch.from_numpy(obstacles[:1].astype(np.float32)), torch.from_numpy(goals[:1])
    moved = torch.from_numpy(starts[:1] + 1)
    with torch.no_grad():
        for mode, reads in (("cf", False), ("f", True)):
            model = load_transpath(None, mode)
            a, b = model.outputs(o, torch.from_numpy(starts[:1]), g), model.outputs(o, moved, g)
            assert (not torch.equal(a, b)) == reads


@pytest.mark.parametrize("mode", ["cf", "f"])
def test_the_shipped_weights_are_the_authors_tensors(mode):
    model = load_transpath(None, mode)
    authors = state(mode)
    assert model.mode == mode and model.record["mode"] == mode
    assert model.record["imported_from"]["sha256"] == weights_checksum(public_data(WEIGHTS[mode]))
    assert "MIT License" in model.record["license"]
    assert set(model.state_dict()) == set(authors) and len(authors) == 158
    assert all(torch.equal(model.state_dict()[k], authors[k]) for k in authors)
    assert torch.equal(authors["pos.grid"], positional_grid())  # the authors' grid, as vinadv builds it


def test_import_weights_writes_the_weights_and_a_record(tmp_path, capsys):
    out = tmp_path / "cf.pt"
    source = "AIRI-Institute/TransPath, commit 7e471c8, weights/cf.pth"
    assert (
        main(
            [
                "transpath",
                "import-weights",
                str(public_data(WEIGHTS["cf"])),
                "--mode",
                "cf",
                "--source",
                source,
                "--out",
                str(out),
                "--json",
            ]
        )
        == 0
    )
    record = json.loads(capsys.readouterr().out)
    assert record["planner"] == "transpath-cf" and record["imported_from"]["source"] == source
    assert record["imported_from"]["sha256"] == weights_checksum(public_data(WEIGHTS["cf"]))
    assert "Copyright (c) 2024 AI Research" in record["license"]
    assert json.loads(out.with_suffix(".json").read_text()) == record
    assert load_transpath(out, "cf").record == record
    with pytest.raises(InputError, match="mode 'cf', expected 'f'"):
        load_transpath(out, "f")


def _saved(tmp_path, data, name="x.pth"):
    path = tmp_path / name
    torch.save(data, path)
    return path


def test_other_files_are_refused_in_one_line(tmp_path):
    authors = state("cf")
    missing = dict(authors)
    del missing["decoder.conv_out.bias"]
    with pytest.raises(InputError, match="missing decoder.conv_out.bias"):
        from_authors_state_dict(_saved(tmp_path, missing), "cf")
    with pytest.raises(InputError, match="unexpected keys extra"):
        from_authors_state_dict(_saved(tmp_path, {**authors, "extra": torch.zeros(1)}), "cf")
    wrong = {**authors, "encoder.layers.0.weight": torch.zeros(64, 3, 5, 5)}
    with pytest.raises(InputError, match=r"encoder.layers.0.weight \(64, 3, 5, 5\)"):
        from_authors_state_dict(_saved(tmp_path, wrong), "cf")
    nan = {**authors, "pos.linear.bias": torch.full((64,), float("nan"))}
    with pytest.raises(InputError, match="NaN or infinite"):
        from_authors_state_dict(_saved(tmp_path, nan), "cf")
    with pytest.raises(InputError, match="training checkpoint"):
        from_authors_state_dict(_saved(tmp_path, {"state_dict": authors}), "cf")
    with pytest.raises(InputError, match="mode 'k'"):
        from_authors_state_dict(public_data(WEIGHTS["cf"]), "k")
    with pytest.raises(InputError, match="the authors' state dict, not a vinadv TransPath weights file"):
        load_transpath(public_data(WEIGHTS["cf"]), "cf")


def test_maps_of_another_size_are_refused():
    with pytest.raises(InputError, match="64x64 maps"):
        TransPath("cf").outputs(torch.zeros(1, 32, 32), None, torch.zeros(1, 2, dtype=torch.int64))
