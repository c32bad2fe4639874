"""Human labels as a training set: one label per pair from many annotations (hand-worked cases), the stored
pairs they belong to, and `vinadv classify train --labels human`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.cli_files import command_line
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.store import Store
from vinadv.viewer.label_set import human_training_set, resolve_human_labels


def train_on_human_labels(db: str, run: int, model: str, out: str | Path, *options: str) -> int:
    """The exit status of `vinadv classify train --labels human` of a `model` on run `run` of `db`, written to
    `out`, with more `options`."""
    args = command_line("classify", "train", labels="human", db=db, run=run, model=model, out=out)
    return main([*args, *options])


def _ann(i, pair, label, who):
    return {"id": i, "pair_index": pair, "label": label, "annotator": who}


@pytest.mark.parametrize(
    "annotations,expected",
    [
        ([], ([], [])),
        ([_ann(1, 5, "FP", "a")], ([5], ["FP"])),
        # one annotator changes their mind: the latest counts
        ([_ann(1, 5, "FP", "a"), _ann(2, 5, "DP", "a")], ([5], ["DP"])),
        # two against one
        ([_ann(1, 5, "FP", "a"), _ann(2, 5, "FP", "b"), _ann(3, 5, "DP", "c")], ([5], ["FP"])),
        # a tie: the most recent annotation among the tied labels
        ([_ann(1, 5, "FP", "a"), _ann(2, 5, "DP", "b")], ([5], ["DP"])),
        ([_ann(2, 5, "FP", "a"), _ann(1, 5, "DP", "b")], ([5], ["FP"])),
        # one person labelling a pair many times counts once
        (
            [
                _ann(1, 7, "DP", "a"),
                _ann(2, 7, "DP", "a"),
                _ann(3, 7, "DP", "a"),
                _ann(4, 7, "FP", "b"),
                _ann(5, 7, "FP", "c"),
                _ann(6, 3, "UcP", "a"),
            ],
            ([3, 7], ["UcP", "FP"]),
        ),
    ],
)
def test_resolve_human_labels(annotations, expected):
    pairs, labels = resolve_human_labels(annotations)
    assert pairs.tolist() == expected[0] and labels.tolist() == expected[1]


def test_human_training_set_reads_the_labelled_pairs(db):
    url, runs = db
    run_id, records = runs["random"]
    with Store.open(url, create=False) as store:
        with pytest.raises(InputError, match="no human labels"):
            human_training_set(store, run_id)
        with pytest.raises(InputError, match="no run 999"):
            human_training_set(store, 999)
        store.add_annotations(run_id, [40, 3, 12], ["FP", "DP", "FP"], "alice")
        store.add_annotations(run_id, [3], ["FP"], "bob")  # tie on 3: bob's is the latest
        batch, labels, pairs = human_training_set(store, run_id)
    assert pairs.tolist() == [3, 12, 40] and labels.tolist() == ["FP", "FP", "FP"]
    for k, i in enumerate(pairs):
        o = batch.path_o[k]
        expect = records.path_o[i]
        assert np.array_equal(o, expect)
        assert np.array_equal(batch.goals[k], records.goals[i])


def test_classify_train_on_human_labels(db, tmp_path, capsys):
    url, runs = db
    run_id, _ = runs["random"]
    with Store.open(url, create=False) as store:
        store.add_annotations(run_id, list(range(0, 12)), ["FP", "DP"] * 6, "alice")
        store.add_annotations(run_id, [20, 21], ["UcP", "UrP"], "bob")
    out = tmp_path / "human.model"
    code = train_on_human_labels(url, run_id, "hausdorff", out, "--test-fraction", "0.25", "--json")
    assert code == 0, capsys.readouterr().err
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["labels"] == "human" and summary["n_pairs"] == 14
    assert {**summary["train_counts"], **summary["test_counts"]}.keys() == {"FP", "DP"}
    assert sum(summary["train_counts"].values()) + sum(summary["test_counts"].values()) == 12
    assert out.exists()


def test_classify_train_human_needs_run_and_labels(db, tmp_path, capsys):
    url, runs = db
    run_id, _ = runs["random"]
    model = str(tmp_path / "m.model")
    assert main(["classify", "train", "--labels", "human", "--db", url, "--model", "svm", "--out", model]) == 2
    assert "--run" in capsys.readouterr().err
    assert train_on_human_labels(url, run_id, "svm", model) == 2
    assert "no human labels" in capsys.readouterr().err
    assert train_on_human_labels(str(tmp_path / "none.db"), 1, "svm", model) == 2
    assert main(["classify", "train", "--model", "svm", "--out", model]) == 2
    assert "--pairs is required" in capsys.readouterr().err
