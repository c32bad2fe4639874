"""The identification pipeline (paper, Algorithm 1): map pairs in, identified pairs out.

Plan both maps (or take the paths already planned by the attack), label each path pair (default: the exact
rule labeller; or a trained classifier, run as the paper's hybrid: path features first, the image classifier
for the FP/DP rest), mark attack success (UrP or FP), and return `D_adversarial`, the successful pairs.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from vinadv.attacks.pairs import PairSet
from vinadv.classify import (
    HybridClassifier,
    PairClassifier,
    PathPairBatch,
    RuleClassifier,
    SUCCESS_LABELS,
    label_batch,
    load_model,
    path_distances,
)
from vinadv.classify.harm import DEFAULT_TOL, PairHarm, cross_table, pairset_harm
from vinadv.errors import InputError
from vinadv.planners.engine import plan_batch
from vinadv.planners.vin import VIN

#: strength of each label for choosing among attacks: UrP > FP > DP > UcP > invalid
LABEL_STRENGTH = {"invalid": 0, "UcP": 1, "DP": 2, "FP": 3, "UrP": 4}
BUILTIN_CLASSIFIERS = ("rule",)


def load_classifier(spec: str | os.PathLike | None) -> tuple[PairClassifier, str]:
    """A five-way classifier and its name from `spec`: None or 'rule' (the exact rule labeller), or a model
    file written by `vinadv classify train` (an FP/DP model runs inside the paper's hybrid)."""
    if spec is None or str(spec) == "rule":
        return RuleClassifier(), "rule"
    if not os.path.exists(spec):
        raise InputError(f"--classifier {spec}: neither a built-in classifier ({', '.join(BUILTIN_CLASSIFIERS)}) "
                         "nor an existing model file")
    model = load_model(spec)
    if not isinstance(model, (HybridClassifier, RuleClassifier)):
        model = HybridClassifier(model)
        model.classes_ = np.array(list(LABEL_STRENGTH))
    return model, f"{model.kind}:{os.path.basename(str(spec))}"


@dataclass
class Identification:
    """Identified pairs: `pairs` with one label each.

    Attributes:
        pairs: the map pairs with both paths.
        labels: `(n,)` str, 'invalid' | 'UrP' | 'UcP' | 'DP' | 'FP'.
        attack: `(n,)` bool, attack success (UrP or FP).
        score: `(n,)` float64, the classifier's FP score for pairs it decided, NaN elsewhere.
        dh, dv: `(n,)` int64, the rule's horizontal/vertical distances for DP/FP pairs, -1 elsewhere.
        label_source: the classifier's name.
        harm: the pairs' harm (costs, regrets, expert label, harmful/harmless/invalid; `vinadv.classify.harm`).
    """

    pairs: PairSet
    labels: np.ndarray
    attack: np.ndarray
    score: np.ndarray
    dh: np.ndarray
    dv: np.ndarray
    label_source: str
    harm: PairHarm

    def __len__(self) -> int:
        return len(self.labels)

    def adversarial(self) -> np.ndarray:
        """Indices of `D_adversarial`: the successful attacks."""
        return np.flatnonzero(self.attack)

    def counts(self) -> dict[str, int]:
        return {label: int(np.sum(self.labels == label)) for label in LABEL_STRENGTH}

    def harm_table(self) -> dict[str, dict[str, int]]:
        """Pairs per (label, harm): `{label: {harm: count}}`."""
        return cross_table(self.labels, self.harm.harm)


def replan(pairs: PairSet, model: VIN) -> PairSet:
    """`pairs` with both paths planned again by `model` (say, another planner's weights)."""
    o = plan_batch(pairs.obstacles_o, pairs.starts, pairs.goals, model, pairs.corner_cutting)
    a = plan_batch(pairs.obstacles_a, pairs.starts, pairs.goals, model, pairs.corner_cutting)
    return PairSet(
        pairs.obstacles_o, pairs.obstacles_a, pairs.starts, pairs.goals, pairs.added, pairs.map_index,
        o.path_cells, o.path_offsets, a.path_cells, a.path_offsets, o.termination_names, a.termination_names,
        pairs.strategy, dict(pairs.params), pairs.corner_cutting,
    )


def identify(pairs: PairSet, classifier: PairClassifier | None = None, label_source: str = "rule", *,
             harm_tol: float = DEFAULT_TOL, harm_rtol: float = 0.0, expert_o=None) -> Identification:
    """Label every pair of `pairs` with `classifier` (default: the exact rule labeller) and compute its harm
    (tolerances `harm_tol`, `harm_rtol`; `expert_o`: the original maps' expert data if already computed, see
    `vinadv.classify.harm.pair_harm`)."""
    classifier = classifier or RuleClassifier()
    batch = PathPairBatch.from_pairset(pairs)
    if isinstance(classifier, RuleClassifier):
        result = label_batch(batch, classifier.t)  # exact: no classifier score
        labels, dh, dv, score = result.labels, result.dh, result.dv, np.full(len(pairs), np.nan)
    else:
        labels = np.asarray(classifier.predict(batch)).astype("<U7")
        score = np.asarray(classifier.fp_decision(batch), dtype=np.float64)
        dh, dv = path_distances(batch.o_cells, batch.o_offsets, batch.a_cells, batch.a_offsets, batch.size)
    fork_or_detour = np.isin(labels, ("DP", "FP"))
    return Identification(
        pairs=pairs,
        labels=labels,
        attack=np.isin(labels, SUCCESS_LABELS),
        score=score,
        dh=np.where(fork_or_detour, dh, -1).astype(np.int64),
        dv=np.where(fork_or_detour, dv, -1).astype(np.int64),
        label_source=label_source,
        harm=pairset_harm(pairs, labels, tol=harm_tol, rtol=harm_rtol, t=getattr(classifier, "t", None),
                          expert_o=expert_o),
    )


def rule_strength(pairs: PairSet) -> np.ndarray:
    """Attack strength by the rule labeller (UrP > FP > DP > UcP > invalid), for the ranking attacks."""
    return label_strength(label_batch(PathPairBatch.from_pairset(pairs)).labels)  # no harm needed here


def harm_strength(pairs: PairSet) -> np.ndarray:
    """Attack strength by harm, for the ranking attacks: UrP strongest, then the largest `regret_a` (the adversarial
    path's excess over the optimum; a map's candidates share the original path, so this ranks the harm), invalid
    pairs weakest. `(n,)` float64."""
    labels = label_batch(PathPairBatch.from_pairset(pairs)).labels
    regret_a = pairset_harm(pairs, labels).regret_a
    return np.where(labels == "UrP", np.inf, np.where(labels == "invalid", -np.inf, np.nan_to_num(regret_a)))


#: what "strongest" means for the ranking attacks (`--objective`): the paper's label order, or harm
OBJECTIVES = {"paper": rule_strength, "harm": harm_strength}


def objective_strength(objective: str):
    """The strength function of `objective` ('paper' or 'harm')."""
    if objective not in OBJECTIVES:
        raise InputError(f"--objective: {objective!r} is not one of {'|'.join(OBJECTIVES)}")
    return OBJECTIVES[objective]


def label_strength(labels: np.ndarray) -> np.ndarray:
    """`LABEL_STRENGTH` of each label, `(n,)` int64."""
    names = np.array(sorted(LABEL_STRENGTH))
    values = np.array([LABEL_STRENGTH[name] for name in names], dtype=np.int64)
    return values[np.searchsorted(names, np.asarray(labels))]
