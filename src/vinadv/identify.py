"""The identification pipeline (paper, Algorithm 1): map pairs in, identified pairs out.

Plan both maps (or take the paths already planned by the attack), label each path pair (default: the exact
rule labeller; or a trained classifier, run as the paper's hybrid: path features first, the image classifier
for the FP/DP rest), mark attack success (UrP or FP), and return `D_adversarial`, the successful pairs.

`vinadv identify` is this module's job: `IdentifyConfig` (a pairs file, the classifier, the planner that plans the
pairs again by its spec, the harm tolerances), `run(config, executor)` (labelled and stored as a run) and
`StoredIdentification` (`to_dict()` the summary).
"""

from __future__ import annotations

import functools
import os
import time
from dataclasses import asdict, dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from vinadv.attacks.pairs import PairSet
from vinadv.classify.batch import PathPairBatch
from vinadv.classify.harm import (
    DEFAULT_TOL,
    PairHarm,
    check_tolerances,
    cross_table,
    harm_summary,
    pairset_harm,
)
from vinadv.classify.rule import label_batch, path_distances
from vinadv.errors import InputError
from vinadv.executor import LOCAL, Executor, resolve, shipped
from vinadv.grid.columns import Columns
from vinadv.planners.interface import Planner
from vinadv.planners.registry import PlannerRef, load_planner_for
from vinadv.planners.spec import PlannerSpec
from vinadv.planners.vin.planner import as_planner
from vinadv.planners.weights import weights_checksum
from vinadv.records import IDENTIFY, RECORD_VERSIONS, VERSION_KEY
from vinadv.vocabulary import (
    EDITS,
    FORK_OR_DETOUR,
    LABEL_STRENGTH,
    LABELS,
    is_success,
    label_counts,
    label_strength,
    success_count,
)

if TYPE_CHECKING:  # scikit-learn comes with it; the rule labeller needs none
    from vinadv.classify.base import PairClassifier

BUILTIN_CLASSIFIERS = ("rule",)


def load_classifier(spec: str | os.PathLike | None) -> tuple[PairClassifier | None, str]:
    """A five-way classifier and its name from `spec`: None or 'rule' give `(None, "rule")`, the exact rule labeller
    (which `identify` runs without a classifier object, so the rule needs no scikit-learn); a model file written by
    `vinadv classify train` gives the model (an FP/DP model inside the paper's hybrid)."""
    if spec is None or str(spec) == "rule":
        return None, "rule"
    from vinadv.classify.base import load_model  # noqa: PLC0415 (scikit-learn: the rule labeller does without it)
    from vinadv.classify.hybrid import HybridClassifier, RuleClassifier  # noqa: PLC0415 (as above)

    check_classifier(spec)
    model = load_model(spec)
    if not isinstance(model, (HybridClassifier, RuleClassifier)):
        model = HybridClassifier(model)
        model.classes_ = np.array(list(LABEL_STRENGTH))
    return model, f"{model.kind}:{os.path.basename(str(spec))}"


@dataclass(kw_only=True, eq=False)
class Identification(Columns):
    """Identified pairs: `pairs` with one label each (`take`/`concat` from `Columns`).

    Attributes:
        pairs: the n map pairs with both paths (`PairSet`).
        labels: `(n,)` str, one of `vocabulary.LABELS`.
        attack: `(n,)` bool, attack success (`vocabulary.SUCCESS_LABELS`: UrP or FP).
        score: `(n,)` float64, the classifier's FP score for pairs it decided, NaN elsewhere.
        dh, dv: `(n,)` int64, the rule's horizontal/vertical distances for DP/FP pairs, -1 elsewhere.
        label_source: the classifier's name.
        harm: the pairs' harm (costs, regrets, expert label, harmful/harmless/invalid; `vinadv.classify.harm`).
    """

    META = ("label_source",)

    pairs: PairSet
    labels: np.ndarray
    attack: np.ndarray
    score: np.ndarray
    dh: np.ndarray
    dv: np.ndarray
    label_source: str
    harm: PairHarm

    def adversarial(self) -> np.ndarray:
        """Indices of `D_adversarial`: the successful attacks."""
        return np.flatnonzero(self.attack)

    def counts(self) -> dict[str, int]:
        """Pairs per label, weakest first (`vocabulary.label_counts`)."""
        return label_counts(self.labels)

    def records(self, pair_index: np.ndarray | None = None):
        """The store's `PairRecords` of these pairs (`pair_index` defaults to `0..n-1`)."""
        from vinadv.store.records import PairRecords  # noqa: PLC0415 (SQLAlchemy: identify needs no store)

        return PairRecords.from_pairs(
            self.pairs,
            label=self.labels,
            attack=self.attack,
            label_source=self.label_source,
            score=self.score,
            dh=self.dh,
            dv=self.dv,
            pair_index=pair_index,
            harm=self.harm,
        )

    def harm_table(self) -> dict[str, dict[str, int]]:
        """Pairs per (label, harm): `{label: {harm: count}}`."""
        return cross_table(self.labels, self.harm.harm)


def replan(pairs: PairSet, planner: Planner) -> PairSet:
    """`pairs` with both paths planned again by `planner` (a `Planner` or a `VIN`): the attacks found on one
    planner, tried on another (transfer)."""
    planner = as_planner(planner, pairs.size)
    o = planner.plan(pairs.obstacles_o, pairs.starts, pairs.goals, pairs.corner_cutting, pairs.moves)
    a = planner.plan(pairs.obstacles_a, pairs.starts, pairs.goals, pairs.corner_cutting, pairs.moves)
    expanded_o, expanded_a = getattr(o, "expanded_cells", None), getattr(a, "expanded_cells", None)
    effort = expanded_o is not None and expanded_a is not None
    astar = {}
    if effort:  # A*'s counts depend on the maps alone: kept where the pairs carry them
        from vinadv.planners.classical.astar import reference_expansions  # noqa: PLC0415 (Numba: search planners)

        for side in ("o", "a"):
            known = getattr(pairs, f"astar_expansions_{side}")
            if known is None or (known < 1).any():
                obstacles = getattr(pairs, f"obstacles_{side}")
                known = reference_expansions(obstacles, pairs.starts, pairs.goals, pairs.corner_cutting, pairs.moves)
            astar[f"astar_expansions_{side}"] = known
    return replace(
        pairs,
        path_o=o.paths,
        path_a=a.paths,
        term_o=o.termination_names,
        term_a=a.termination_names,
        params=dict(pairs.params),
        expanded_o=expanded_o if effort else None,
        expanded_a=expanded_a if effort else None,
        astar_expansions_o=astar.get("astar_expansions_o"),
        astar_expansions_a=astar.get("astar_expansions_a"),
    )


def identify(
    pairs: PairSet,
    classifier: PairClassifier | None = None,
    label_source: str = "rule",
    *,
    harm_tol: float = DEFAULT_TOL,
    harm_rtol: float = 0.0,
    expert_o=None,
) -> Identification:
    """Label every pair of `pairs` with `classifier` (None: the exact rule labeller) and compute its harm
    (tolerances `harm_tol`, `harm_rtol`; `expert_o`: the original maps' expert data if already computed, see
    `vinadv.classify.harm.pair_harm`)."""
    batch = PathPairBatch.from_pairs(pairs)
    exact_rule = classifier is None
    if not exact_rule:  # a classifier object: scikit-learn is loaded already
        from vinadv.classify.hybrid import RuleClassifier  # noqa: PLC0415 (as above)

        exact_rule = isinstance(classifier, RuleClassifier)
    if exact_rule:
        result = label_batch(batch, getattr(classifier, "t", None))  # exact: no classifier score
        labels, dh, dv, score = result.labels, result.dh, result.dv, np.full(len(pairs), np.nan)
    else:
        labels = np.asarray(classifier.predict(batch)).astype("<U7")
        score = np.asarray(classifier.fp_decision(batch), dtype=np.float64)
        dh, dv = path_distances(batch.path_o, batch.path_a, batch.size)
    fork_or_detour = np.isin(labels, FORK_OR_DETOUR)
    return Identification(
        pairs=pairs,
        labels=labels,
        attack=is_success(labels),
        score=score,
        dh=np.where(fork_or_detour, dh, -1).astype(np.int64),
        dv=np.where(fork_or_detour, dv, -1).astype(np.int64),
        label_source=label_source,
        harm=pairset_harm(
            pairs, labels, tol=harm_tol, rtol=harm_rtol, t=getattr(classifier, "t", None), expert_o=expert_o
        ),
    )


def rule_strength(pairs: PairSet) -> np.ndarray:
    """Attack strength by the rule labeller (UrP > FP > DP > UcP > invalid), for the ranking attacks."""
    return label_strength(label_batch(PathPairBatch.from_pairs(pairs)).labels)  # no harm needed here


def harm_strength(pairs: PairSet) -> np.ndarray:
    """Attack strength by harm, for the ranking attacks: UrP strongest, then the largest `regret_a` (the adversarial
    path's excess over the optimum; a map's candidates share the original path, so this ranks the harm), invalid
    pairs weakest. `(n,)` float64."""
    labels = label_batch(PathPairBatch.from_pairs(pairs)).labels
    return harm_order(labels, pairset_harm(pairs, labels).regret_a)


def harm_order(labels, regret_a) -> np.ndarray:
    """`harm_strength` from pairs' labels and adversarial regrets already computed (an `Identification`'s)."""
    labels = np.asarray(labels)
    return np.where(labels == "UrP", np.inf, np.where(labels == "invalid", -np.inf, np.nan_to_num(regret_a)))


def effort_strength(pairs: PairSet) -> np.ndarray:
    """Attack strength by search effort, for the ranking attacks: the cells the planner's search expanded on the
    adversarial map (a map's candidates share the original search, so this ranks the growth of the search), invalid
    pairs weakest. `(n,)` float64. InputError naming `objective` for pairs without expansions (a planner that does
    not report them: `Capabilities.expansions`)."""
    if pairs.expanded_a is None:
        raise InputError(
            "objective: effort ranks by the cells a search expands; the planner reports no expansions "
            "(use a search planner: astar, wastar, neural-astar, transpath-*)",
            "objective",
        )
    return np.where(pairs.reached_o, pairs.expansions_a.astype(np.float64), -np.inf)


#: what "strongest" means for the ranking attacks (`--objective`): the paper's label order, harm, or search effort
OBJECTIVES = {"paper": rule_strength, "harm": harm_strength, "effort": effort_strength}


def objective_strength(objective: str):
    """The strength function of `objective` ('paper', 'harm' or 'effort')."""
    if objective not in OBJECTIVES:
        raise InputError(f"objective: {objective!r} is not one of {'|'.join(OBJECTIVES)}", "objective")
    return OBJECTIVES[objective]


#: the key of a run's stored config holding its planner's `Planner.spec()` (a `PlannerSpec`)
PLANNER_SPEC = "planner_spec"


@dataclass(frozen=True)
class ClassifierRef:
    """A classifier model file by reference, for another process to load the same one (`vinadv.executor.shipped`):
    its absolute path and the SHA-256 the client's file has; `load` refuses a file that differs."""

    path: str
    checksum: str

    @classmethod
    def of(cls, spec: str | os.PathLike) -> ClassifierRef:
        path = os.path.abspath(os.fspath(spec))  # another process may run in another folder: same path, same file
        return cls(path, weights_checksum(path))

    def load(self) -> PairClassifier | None:
        found = weights_checksum(self.path)
        if found != self.checksum:
            raise InputError(
                f"classifier file {self.path} on this worker differs from the client's (sha256 {found} != "
                f"{self.checksum})",
                "classifier",
            )
        return load_classifier(self.path)[0]


def _identify_chunk(planner, classifier, label_source: str, harm_tol: float, harm_rtol: float, pairs: PairSet):
    """The task of `identify_and_store` on a slice of pairs: plan again (with `planner`, unless None), label,
    and compute the harm (`planner`, `classifier`: models, or references to them, `vinadv.executor.resolve`)."""
    planner = resolve(planner)
    if planner is not None:
        pairs = replan(pairs, planner)
    return identify(pairs, resolve(classifier), label_source, harm_tol=harm_tol, harm_rtol=harm_rtol)


def identify_pairs(
    pairs: PairSet,
    planner: Planner | None,
    classifier: str | None,
    executor: Executor = LOCAL,
    *,
    planner_ref: PlannerRef | None = None,
    harm_tol: float = DEFAULT_TOL,
    harm_rtol: float = 0.0,
    shard_size: int = 1000,
) -> Identification:
    """`identify` of `pairs` (after `replan` with `planner`, unless None) on `executor`, in slices of `shard_size`
    pairs where it cuts them (`Executor.bounds`): the same `Identification` wherever it runs. `planner_ref`: the
    planner by reference, for a remote executor (`PlannerRef.of`)."""
    classifier_model, classifier_name = load_classifier(classifier)
    planner_x = shipped(executor, planner, lambda: planner_ref)
    classifier_x = shipped(executor, classifier_model, lambda: ClassifierRef.of(classifier))
    task = functools.partial(_identify_chunk, planner_x, classifier_x, classifier_name, harm_tol, harm_rtol)
    bounds = executor.bounds(len(pairs), shard_size)
    if bounds == [(0, len(pairs))]:
        return next(iter(executor.map(task, [pairs])))
    parts = list(executor.map(task, (pairs.take(np.arange(lo, hi)) for lo, hi in bounds)))
    if not parts:
        return identify(pairs, None, classifier_name, harm_tol=harm_tol, harm_rtol=harm_rtol)
    return Identification.concat(parts, label_source=classifier_name)


def pairs_summary(
    labels, n_maps: int, no_valid: int, planner_calls: int, seconds: float, harm_table: dict | None = None
) -> dict:
    """The summary of labelled pairs: counts, the paper's success rate, and with `harm_table` (a
    `vinadv.classify.harm.cross_table`) the harm counts, the harmful rate and the label x harm table."""
    counts = label_counts(labels)
    valid = len(labels) - counts["invalid"]
    success = success_count(counts)
    return {
        "maps": n_maps,
        "pairs": len(labels),
        "maps_without_valid_cell": no_valid,
        "counts": counts,
        "success_rate": success / valid if valid else None,
        "planner_calls": planner_calls,
        "planner_calls_per_success": planner_calls / success if success else None,
        "seconds": round(seconds, 3),
        **({} if harm_table is None else harm_summary(harm_table)),
    }


def check_classifier(spec: str | os.PathLike | None) -> None:
    """InputError naming `classifier` unless `spec` is a built-in classifier, None (the rule) or an existing file."""
    if spec is not None and str(spec) not in BUILTIN_CLASSIFIERS and not os.path.exists(spec):
        raise InputError(
            f"classifier {spec}: neither a built-in classifier ({', '.join(BUILTIN_CLASSIFIERS)}) "
            "nor an existing model file",
            "classifier",
        )


@dataclass(frozen=True)
class IdentifyConfig:
    """Everything that determines the labels of `vinadv identify`; checked when made (InputError naming the field).

    `pairs`: a pairs file; `classifier`: 'rule' (None) or a model file of `vinadv classify train`; `planner`,
    `weights`: a planner by its spec (`vinadv.planners.registry.load_planner`) that plans both maps of every pair
    again (the file's attacks tried on another planner: transfer), or neither (the file's paths are kept);
    `harm_tolerance`, `harm_rtol`: the harm test's; `shard_size`: pairs per task where the executor cuts them."""

    pairs: str
    classifier: str | None = None
    planner: str | None = None
    weights: str | None = None
    harm_tolerance: float = DEFAULT_TOL
    harm_rtol: float = 0.0
    shard_size: int = 1000

    def __post_init__(self):
        object.__setattr__(self, "pairs", os.fspath(self.pairs))
        check_classifier(self.classifier)
        check_tolerances(self.harm_tolerance, self.harm_rtol)
        if self.shard_size < 1:
            raise InputError(f"shard_size must be >= 1, got {self.shard_size}", "shard_size")

    @property
    def replans(self) -> bool:
        """Whether the pairs are planned again (a planner or weights given)."""
        return self.planner is not None or self.weights is not None

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class StoredIdentification:
    """What `run` did: the identification, the run it was stored as, and how long it took; `to_dict()` the summary
    (`pairs_summary` of the labels, the run id and the number of successful attacks)."""

    identification: Identification
    run_id: int
    seconds: float

    def to_dict(self) -> dict:
        ident = self.identification
        out = pairs_summary(ident.labels, len(ident), 0, 0, self.seconds, harm_table=ident.harm_table())
        out.update(run_id=self.run_id, adversarial=int(ident.attack.sum()))
        return out


def run(
    config: IdentifyConfig,
    executor: Executor = LOCAL,
    *,
    db: str | None = None,
    name: str | None = None,
    device: str | None = None,
) -> StoredIdentification:
    """`vinadv identify`: label the pairs of `config.pairs` and store them as a new run `name` in `db`, with their
    harm. With a planner in `config`, both maps of every pair are planned again by it first; the run's config
    records both planners (`attack_planner`: the file's).

    `executor` computes the identification (`identify_pairs`: in this process by default; `vinadv.cluster.
    DaskExecutor` on a cluster, `config.shard_size` pairs per task) after the inputs are checked, so a bad file is
    refused before any worker starts. `device`: where the planner plans (`load_planner`); refused without one in
    `config` (the file's paths are kept then: nothing runs on it)."""
    from vinadv.store import Store  # noqa: PLC0415 (SQLAlchemy: identify needs no store)
    from vinadv.store.runs import check_run_name  # noqa: PLC0415 (SQLAlchemy, as above)

    if name is not None:
        check_run_name(name)  # before the work and the database: it is refused, not found, after them
    if device is not None and not config.replans:
        raise InputError(
            "device: only with planner or weights (without them the file's paths are kept, nothing is planned)",
            "device",
            "planner",
            "weights",
        )
    pairs = PairSet.load(config.pairs)
    t0 = time.perf_counter()
    replanner = ref = None
    if config.replans:
        replanner = load_planner_for(config.planner, config.weights, pairs, device)
        if executor.remote:
            ref = PlannerRef.of(replanner, config.planner, config.weights, pairs.corner_cutting)
    ident = identify_pairs(
        pairs,
        replanner,
        config.classifier,
        executor,
        planner_ref=ref,
        harm_tol=config.harm_tolerance,
        harm_rtol=config.harm_rtol,
        shard_size=config.shard_size,
    )
    elapsed = time.perf_counter() - t0
    # the spec of the planner that made the file, where its params record one
    attack_planner: PlannerSpec | None = pairs.params.get("planner")
    used: PlannerSpec | None = replanner.spec() if replanner is not None else attack_planner
    with Store.open(db) as store:
        run_id = store.create_run(
            name,
            config={
                "pairs": config.pairs,
                "strategy": pairs.strategy,
                "params": pairs.params,
                "classifier": config.classifier,
                "planner": None if used is None else used["name"],
                "weights": config.weights,
                PLANNER_SPEC: used,
                "attack_planner": attack_planner,
                "harm_tolerance": config.harm_tolerance,
                "harm_rtol": config.harm_rtol,
                "edit": str(pairs.edit[0]) if len(pairs) else EDITS[0],
                VERSION_KEY: RECORD_VERSIONS[IDENTIFY],
            },
            weights_checksum=None if used is None else used["weights_sha256"],
            attack=pairs.strategy,
            classifier=ident.label_source,
            moves=pairs.moves,
        )
        store.write_pairs(run_id, ident.records())
        store.finish_run(run_id, timings={"identify": elapsed})
    return StoredIdentification(ident, run_id, elapsed)


def identify_and_store(
    pairs_path: str | os.PathLike,
    db: str | None = None,
    *,
    classifier: str | None = None,
    planner: str | None = None,
    weights: str | None = None,
    name: str | None = None,
    harm_tol: float = DEFAULT_TOL,
    harm_rtol: float = 0.0,
    executor: Executor = LOCAL,
    shard_size: int = 1000,
    device: str | None = None,
) -> StoredIdentification:
    """`run` of the `IdentifyConfig` these arguments make: the one call, without building a config first."""
    config = IdentifyConfig(pairs_path, classifier, planner, weights, harm_tol, harm_rtol, shard_size)
    return run(config, executor, db=db, name=name, device=device)


__all__ = [
    "BUILTIN_CLASSIFIERS",
    "ClassifierRef",
    "IdentifyConfig",
    "LABELS",
    "Identification",
    "StoredIdentification",
    "check_classifier",
    "identify",
    "identify_and_store",
    "identify_pairs",
    "load_classifier",
    "pairs_summary",
    "replan",
    "rule_strength",
    "run",
]
