import numpy as np
import pytest

from vinadv.classify.rule import label_batch
from vinadv.classify.train_eval import evaluate_classifier, train_classifier
from vinadv.errors import InputError
from vinadv.testing.classify import synthetic_pairs


def test_train_then_evaluate_on_the_held_out_split():
    batch = synthetic_pairs(200, size=12, seed=3, mix=True)
    labels = label_batch(batch).labels
    model, record, arrays = train_classifier(batch, labels, model="svm", test_fraction=0.3, seed=1)
    train, test = arrays["train_index"], arrays["test_index"]
    fp_dp = np.flatnonzero(np.isin(labels, ("DP", "FP")))
    # a stratified split of exactly the FP/DP pairs, nothing else, nothing twice
    assert sorted(np.concatenate([train, test]).tolist()) == fp_dp.tolist()
    assert record["train_counts"] == {k: int(v) for k, v in zip(*np.unique(labels[train], return_counts=True))}
    model.record_, model.record_arrays_ = record, arrays
    result = evaluate_classifier(model, batch)
    assert result["scope"] == "held-out test split of the training file" and result["fp_dp"]["n"] == len(test)
    assert result["five_way"]["n"] == len(batch) - len(train)
    assert evaluate_classifier(model, batch, all_pairs=True)["fp_dp"]["n"] == len(fp_dp)


def test_bad_settings_name_the_parameter():
    batch = synthetic_pairs(30, size=12, seed=3)
    with pytest.raises(InputError, match="^test_fraction must be in") as exc:
        train_classifier(batch, label_batch(batch).labels, model="svm", test_fraction=1.0)
    assert exc.value.parameters == ("test_fraction",)
    with pytest.raises(InputError, match="mine: training needs at least 1 FP and 1 DP"):
        train_classifier(batch, np.full(len(batch), "UcP"), model="svm", source="mine")
