import numpy as np
import pytest

from vinadv.errors import InputError
from vinadv.vocabulary import (
    LABEL_STRENGTH,
    LABELS,
    RESULT_NAMES,
    STRENGTH_ORDER,
    SUCCESS_LABELS,
    TERMINATIONS,
    is_success,
    label_counts,
    label_strength,
    success_count,
    termination_names,
)


def test_the_words_of_design_md():
    assert LABELS == ("invalid", "UrP", "UcP", "DP", "FP")
    assert TERMINATIONS == ("goal", "collision", "loop", "step_limit")
    assert set(SUCCESS_LABELS) == {"UrP", "FP"}
    # UrP > FP > DP > UcP > invalid
    strongest_first = sorted(LABELS, key=LABEL_STRENGTH.get, reverse=True)
    assert strongest_first == list(STRENGTH_ORDER) == ["UrP", "FP", "DP", "UcP", "invalid"]
    assert RESULT_NAMES == {"UrP": "Success-UrP", "FP": "Success-FP", "DP": "Unsuccess-DP", "UcP": "Unsuccess-UcP"}


def test_helpers_against_plain_python():
    labels = np.array(["FP", "UcP", "UrP", "invalid", "FP", "DP"])
    assert is_success(labels).tolist() == [lab in ("UrP", "FP") for lab in labels]
    counts = label_counts(labels)
    assert counts == {"invalid": 1, "UcP": 1, "DP": 1, "FP": 2, "UrP": 1} and list(counts) == list(LABEL_STRENGTH)
    assert success_count(counts) == 3
    assert label_strength(labels).tolist() == [3, 1, 4, 0, 3, 2]
    assert termination_names([0, 3, 1]).tolist() == ["goal", "step_limit", "collision"]
    with pytest.raises(InputError, match="'XX' is not one of"):
        label_strength(["FP", "XX"])
