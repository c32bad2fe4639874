import json
import math

import numpy as np
import pytest

from vinadv.attacks.pairs import PairSet
from vinadv.classify import label_batch
from vinadv.cli import main
from vinadv.testing.classify import synthetic_pairs


@pytest.fixture(scope="module")
def pairs_file(tmp_path_factory):
    """A pairs file holding synthetic path pairs (maps are placeholders: classify reads only the paths)."""
    batch = synthetic_pairs(260, size=12, seed=2, mix=True)
    n, size = len(batch), batch.size
    obstacles = np.zeros((n, size, size), dtype=bool)
    obstacles[:, 0, :] = True
    obstacles_a = obstacles.copy()
    obstacles_a[:, size - 1, size - 1] = True
    last = lambda paths: paths.cells[np.maximum(paths.offsets[1:] - 1, 0)]  # noqa: E731
    term = lambda paths: np.where(np.all(last(paths) == batch.goals, 1), "goal", "collision")  # noqa: E731
    pairs = PairSet(
        obstacles_o=obstacles,
        obstacles_a=obstacles_a,
        starts=batch.path_o.cells[batch.path_o.offsets[:-1]],
        goals=batch.goals,
        added=np.tile([size - 1, size - 1], (n, 1)),
        map_index=np.arange(n),
        path_o=batch.path_o,
        path_a=batch.path_a,
        term_o=term(batch.path_o),
        term_a=term(batch.path_a),
        strategy="synthetic",
    )
    path = tmp_path_factory.mktemp("classify") / "pairs.npz"
    pairs.save(path)
    return path, label_batch(batch).labels


@pytest.mark.slow
def test_train_and_eval_on_held_out_split(pairs_file, tmp_path, capsys):
    path, labels = pairs_file
    model = tmp_path / "svm.model"
    assert (
        main(["classify", "train", "--pairs", str(path), "--model", "svm", "--out", str(model), "--balance", "--json"])
        == 0
    )
    record = json.loads(capsys.readouterr().out)
    fp_dp = np.isin(labels, ("DP", "FP"))
    assert sum(record["test_counts"].values()) == math.ceil(0.3 * fp_dp.sum())  # scikit-learn rounds the test part up
    counts = record["train_counts_balanced"]
    assert counts["DP"] == counts["FP"]
    assert main(["classify", "eval", "--pairs", str(path), "--model", str(model), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["scope"].startswith("held-out")
    assert result["fp_dp"]["n"] == sum(record["test_counts"].values())
    assert sum(map(sum, result["fp_dp"]["confusion_matrix"])) == result["fp_dp"]["n"]
    assert result["prediction_seconds_per_100_pairs"] >= 0
    assert main(["classify", "eval", "--pairs", str(path), "--model", str(model), "--all"]) == 0
    out = capsys.readouterr().out
    assert f"FP/DP on {fp_dp.sum()} pairs" in out and "ROC AUC" in out


def test_cli_errors_exit_2(pairs_file, tmp_path, capsys):
    path, _ = pairs_file
    model = tmp_path / "h.model"
    assert (
        main(["classify", "train", "--pairs", str(path), "--model", "hausdorff", "--out", str(model), "--quiet"]) == 0
    )
    with np.load(model, allow_pickle=False) as archive:
        entries = {k: archive[k] for k in archive.files}
    entries["format"] = np.array("vinadv.classifier/9")
    bad = tmp_path / "bad.model"
    with open(bad, "wb") as handle:
        np.savez(handle, **entries)
    capsys.readouterr()
    assert main(["classify", "eval", "--pairs", str(path), "--model", str(bad)]) == 2
    assert "vinadv.classifier/9" in capsys.readouterr().err
    assert main(["classify", "eval", "--pairs", str(tmp_path / "missing.npz"), "--model", str(model)]) == 2
    assert (
        main(["classify", "train", "--pairs", str(path), "--model", "svm", "--out", str(model), "--labels", "human"])
        == 2
    )
    assert "--db" in capsys.readouterr().err
    assert (
        main(
            ["classify", "train", "--pairs", str(path), "--model", "svm", "--out", str(model), "--test-fraction", "1.5"]
        )
        == 2
    )
    assert main(["classify", "eval", "--pairs", str(path), "--model", str(path)]) == 2
