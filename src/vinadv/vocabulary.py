"""vinadv's words, defined once: path pair labels, their strength order, rollout terminations, results.

DESIGN.md is the contract these names follow. Every module that names a label or a termination imports it from
here (this module imports nothing of vinadv but its error type, so any stage may use it).
"""

from __future__ import annotations

import numpy as np

from vinadv.errors import InputError

#: The five path pair labels, in DESIGN.md order (paper, section 3.2).
LABELS = ("invalid", "UrP", "UcP", "DP", "FP")
#: The labels the path features leave to the FP/DP rule (or an image classifier): both paths reach the goal and differ.
FORK_OR_DETOUR = ("DP", "FP")
#: Labels that mean a successful attack: the adversarial path does not reach the goal, or it forks away.
SUCCESS_LABELS = ("UrP", "FP")
#: Labels by attack strength, strongest first: UrP > FP > DP > UcP > invalid (the paper's table 4 order).
STRENGTH_ORDER = ("UrP", "FP", "DP", "UcP", "invalid")
#: Strength of each label for choosing among attacks (higher is stronger).
LABEL_STRENGTH = {label: strength for strength, label in enumerate(reversed(STRENGTH_ORDER))}
#: The identification result of each valid label (paper, Algorithm 1); `invalid` pairs have none.
RESULT_NAMES = {"UrP": "Success-UrP", "FP": "Success-FP", "DP": "Unsuccess-DP", "UcP": "Unsuccess-UcP"}

#: The edits an adversarial map makes to the original (DESIGN.md "Obstacle removal"): `add` obstacle cells (the
#: paper's setting) or `remove` them (free obstacle cells; never a border wall). A pairs file or a database row
#: without an edit reads as `add`.
EDITS = ("add", "remove")
ADD, REMOVE = EDITS

#: Why a rollout ended, by code: `termination` int arrays hold indices into this tuple.
TERMINATIONS = ("goal", "collision", "loop", "step_limit")
GOAL, COLLISION, LOOP, STEP_LIMIT = range(len(TERMINATIONS))

#: The harm verdicts of a pair (DESIGN.md "Harm"), beside the paper's label.
HARMS = ("harmful", "harmless", "invalid")
#: A pair's harm figures: the costs (move-cost units) and regrets, then the expert label and the harm verdict; the
#: same names are the `map_pairs` columns and the export fields.
HARM_FLOAT_FIELDS = ("opt_cost_o", "opt_cost_a", "cost_o", "cost_a", "regret_o", "regret_a")
HARM_FIELDS = (*HARM_FLOAT_FIELDS, "expert_label", "harm")
#: what the evaluation stage (`vinadv evaluate`) measures of a run besides the classifier comparison, one stored
#: result each (`Store.add_measurement`): the planner's quality and the processing time of the paper's 100 pairs
PLANNER_QUALITY = "planner_quality"
TIMING = "timing"
MEASUREMENTS = (PLANNER_QUALITY, TIMING)


def is_success(labels) -> np.ndarray:
    """`(n,)` bool: which labels are successful attacks (`SUCCESS_LABELS`)."""
    return np.isin(np.asarray(labels), SUCCESS_LABELS)


def label_counts(labels) -> dict[str, int]:
    """How many pairs carry each label, every label present (0 where none), weakest first (the order of
    `LABEL_STRENGTH`, which is the order vinadv prints and writes counts in)."""
    labels = np.asarray(labels)
    return {label: int(np.count_nonzero(labels == label)) for label in LABEL_STRENGTH}


def success_count(counts: dict[str, int]) -> int:
    """The successful attacks among label counts (as from `label_counts`)."""
    return sum(int(counts.get(label, 0)) for label in SUCCESS_LABELS)


def label_strength(labels) -> np.ndarray:
    """`LABEL_STRENGTH` of each label, `(n,)` int64 (raises InputError naming an unknown label)."""
    labels = np.asarray(labels)
    names = np.array(sorted(LABEL_STRENGTH))
    values = np.array([LABEL_STRENGTH[name] for name in names], dtype=np.int64)
    pos = np.minimum(np.searchsorted(names, labels), len(names) - 1)
    bad = names[pos] != labels
    if np.any(bad):
        raise InputError(f"labels: {str(labels[bad].reshape(-1)[0])!r} is not one of {'|'.join(LABELS)}")
    return values[pos]


def termination_names(codes) -> np.ndarray:
    """`(n,)` str names of termination codes (indices into `TERMINATIONS`)."""
    return np.array(TERMINATIONS)[np.asarray(codes, dtype=np.int64)]
