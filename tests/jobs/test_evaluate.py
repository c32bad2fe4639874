"""`vinadv.evaluation.job`: the config refuses a bad value naming the field and normalises its lists; `run` on a
database without runs says so in one line."""

import re

import pytest

from vinadv.errors import InputError
from vinadv.evaluation.job import EvaluateConfig, run
from vinadv.store import Store


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("classifiers", "svm,knn", "classifiers: knn not in"),
        ("sizes", (0.0, 1.0), "sizes: fractions must be in (0, 1], got 0.0"),
        ("setting", "fast", "setting: 'fast' not in baseline,tuned"),
        ("seed", -1, "seed"),
    ],
)
def test_a_config_refuses_a_bad_value_naming_the_field(field, value, message):
    with pytest.raises(InputError, match=re.escape(message)) as info:
        EvaluateConfig(**{field: value})
    assert field in info.value.parameters


def test_a_config_normalises_the_lists_as_the_command_gave_them():
    config = EvaluateConfig(classifiers="rule, svm,rule", sizes="0.5")
    assert config.classifiers == ("rule", "svm") and config.sizes == (0.5, 1.0)


def test_a_database_without_runs_is_refused(tmp_path):
    db = str(tmp_path / "empty.db")
    Store.open(db).close()
    with pytest.raises(InputError, match="no runs stored yet"):
        run(EvaluateConfig(db=db, classifiers="rule"))
