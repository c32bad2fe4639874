"""The figures of a robustness benchmark: per-map outcomes, their worst case over strategies, the figures at each k
and the results of a strategy and of a whole run (the engine that makes them: `vinadv.robustness`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from vinadv.intervals import bootstrap_mean_interval, figure_intervals, interval_fields
from vinadv.planners.spec import PlannerSpec
from vinadv.records import ROBUSTNESS, stamp

#: the name of the worst case over the strategies in tables and dicts
WORST_CASE = "worst case"


@dataclass(kw_only=True, eq=False)
class MapOutcomes:
    """What one strategy did to each of n maps at k added obstacles (`(n,)` arrays, map order).

    Attributes:
        pair: a pair was made (the map had a valid cell at every step).
        valid: a pair was made and the planner reaches the goal on the clean map.
        broken: valid and the pair is UrP or FP.
        harmful: valid and the pair is harmful.
        regret: `regret_a` of a valid pair whose adversarial path reaches the goal, NaN elsewhere.
        label: the pair's paper label, '' without a pair.
        effort_harmful: valid and the pair is effort-harmful (`vinadv.classify.effort`); None for a planner that
            reports no expansions.
        effort: the pair's effort ratio `E_a / E_o` (`vinadv.classify.effort`) where the pair is valid, NaN
            elsewhere (and where a count is missing); None for a planner that reports no expansions.
    """

    pair: np.ndarray
    valid: np.ndarray
    broken: np.ndarray
    harmful: np.ndarray
    regret: np.ndarray
    label: np.ndarray
    effort_harmful: np.ndarray | None = None
    effort: np.ndarray | None = None


def worst_case(outcomes: list[MapOutcomes]) -> MapOutcomes:
    """The worst case per map over the strategies' `outcomes` (of the same maps and k; see the module doc)."""
    pair = np.any([o.pair for o in outcomes], axis=0)
    valid = np.any([o.valid for o in outcomes], axis=0)
    broken = np.any([o.broken for o in outcomes], axis=0)
    harmful = np.any([o.harmful for o in outcomes], axis=0)
    unreached = np.any([o.valid & (o.label == "UrP") for o in outcomes], axis=0)
    regrets = np.array([o.regret for o in outcomes])
    reached = ~np.isnan(regrets)
    largest = np.where(reached.any(axis=0), np.where(reached, regrets, -np.inf).max(axis=0), np.nan)
    regret = np.where(valid & ~unreached, largest, np.nan)
    efforts = [o.effort_harmful for o in outcomes if o.effort_harmful is not None]
    ratios = [o.effort for o in outcomes if o.effort is not None]
    return MapOutcomes(
        pair=pair,
        valid=valid,
        broken=broken,
        harmful=harmful,
        regret=regret,
        label=np.full(len(pair), ""),
        effort_harmful=np.any(efforts, axis=0) if efforts else None,
        # each map's largest effort ratio over the strategies (NaN only where none has one)
        effort=np.fmax.reduce(ratios, axis=0) if ratios else None,
    )


@dataclass
class Figures:
    """The figures of one strategy (or the worst case) at k added obstacles, over `maps` maps."""

    k: int
    maps: int
    attacked: int  # maps with a pair
    valid: int  # maps with a pair whose clean path reaches the goal: the rates' denominator
    broken: int
    harmful: int
    reached: int  # valid maps whose (worst) adversarial path reaches the goal: the mean regret's denominator
    mean_regret: float | None
    counts: dict[str, int] | None = None  # pairs per paper label (a strategy's own pairs; None for the worst case)
    effort_harmful: int | None = (
        None  # valid maps with an effort-harmful pair (None: the planner reports no expansions)
    )

    @property
    def effort_harmful_rate(self) -> float | None:
        return self.effort_harmful / self.valid if self.valid and self.effort_harmful is not None else None

    #: the per-map regrets behind `mean_regret` (`(reached,)`), for its bootstrap interval; None where unknown
    regrets: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def paper_success_rate(self) -> float | None:
        return self.broken / self.valid if self.valid else None

    @property
    def harmful_rate(self) -> float | None:
        return self.harmful / self.valid if self.valid else None

    @classmethod
    def of(cls, k: int, outcome: MapOutcomes, counts: dict[str, int] | None = None) -> Figures:
        regrets = outcome.regret[~np.isnan(outcome.regret)]
        return cls(
            k=k,
            maps=len(outcome.pair),
            attacked=int(outcome.pair.sum()),
            valid=int(outcome.valid.sum()),
            broken=int(outcome.broken.sum()),
            harmful=int(outcome.harmful.sum()),
            reached=len(regrets),
            mean_regret=float(regrets.mean()) if len(regrets) else None,
            counts=counts,
            effort_harmful=None if outcome.effort_harmful is None else int(outcome.effort_harmful.sum()),
            regrets=regrets,
        )

    def to_dict(self, intervals: bool = False) -> dict:
        """The figures, JSON-able; with `intervals`, each rate's Wilson 95% interval too (`{rate}_low`, `{rate}_high`:
        `vinadv.intervals`) and the mean regret's bootstrap interval over the maps (`mean_regret_low`,
        `mean_regret_high`; None without the per-map regrets), as a robustness result carries them (an entry does
        not: its readers compute the rates' intervals)."""
        out = {
            "k": self.k,
            "maps": self.maps,
            "attacked": self.attacked,
            "valid": self.valid,
            "broken": self.broken,
            "paper_success_rate": self.paper_success_rate,
            "harmful": self.harmful,
            "harmful_rate": self.harmful_rate,
            "reached": self.reached,
            "mean_regret": self.mean_regret,
            **({} if self.counts is None else {"counts": self.counts}),
            **(
                {}
                if self.effort_harmful is None
                else {"effort_harmful": self.effort_harmful, "effort_harmful_rate": self.effort_harmful_rate}
            ),
        }
        if not intervals:
            return out
        low, high = (None, None) if self.regrets is None else bootstrap_mean_interval(self.regrets)
        return {**out, **figure_intervals(out), "mean_regret_low": low, "mean_regret_high": high}


@dataclass
class StrategyResult:
    """One strategy's figures at k = 1..max (`by_k[k - 1]`), its time and planner calls, and the per-map outcomes
    (`outcomes[k - 1]`; not in `to_dict`)."""

    name: str
    by_k: list[Figures]
    seconds: float
    planner_calls: int
    outcomes: list[MapOutcomes] = field(default_factory=list, repr=False)
    #: the strategy whose ranking this one used on the planner, where it could not rank its own way (saliency
    #: without gradients: "key-points"), else None (`Attack.ranked_as`)
    ranked_as: str | None = None
    #: the cells each map's pair edits at each k (`cells[i]`: `(n, k, 2)`, -1 where the map has no pair; not in
    #: `to_dict`): what a chain started from this strategy's pairs starts from (`robustness(start=...)`)
    cells: list[np.ndarray] = field(default_factory=list, repr=False)

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "seconds": round(self.seconds, 3),
            "planner_calls": self.planner_calls,
            "ranked_as": self.ranked_as,
            "by_obstacles": [f.to_dict(intervals=True) for f in self.by_k],
        }


@dataclass
class RobustnessResult:
    """A planner's robustness benchmark (see the module doc).

    Attributes:
        planner: the planner's `spec()` (name, size, config, weights checksum).
        settings: maps (n, size, seed, corner cutting, movement model, the maps file and its SHA-256 or None),
            strategies, max_obstacles, objective, budget, radius, seed of the randomised strategies, harm tolerances,
            edit: every field, and the record version (`vinadv.records.ROBUSTNESS_SETTINGS`).
        clean: the unattacked maps: maps, reached, success_rate, mean_regret (of the reached paths).
        strategies: {name: StrategyResult}, in the order run.
        overall: the worst case over the strategies at k = 1..max (`overall[k - 1]`).
        seconds: wall time of the whole benchmark.
    """

    planner: PlannerSpec
    settings: dict
    clean: dict
    strategies: dict[str, StrategyResult]
    overall: list[Figures]
    seconds: float
    overall_outcomes: list[MapOutcomes] = field(default_factory=list, repr=False)
    #: its row in the database `run` stored it in (`save_robustness`), else None; not in `to_dict`
    id: int | None = None

    def figures(self, strategy: str = WORST_CASE, k: int = 1) -> Figures:
        """The figures of `strategy` (or the worst case) at `k` obstacles."""
        by_k = self.overall if strategy == WORST_CASE else self.strategies[strategy].by_k
        return by_k[k - 1]

    def to_dict(self) -> dict:
        """Every figure, JSON-able (what `--json` prints and the database stores: the record
        `vinadv.records.ROBUSTNESS`, its version included), each rate with its Wilson 95% interval (`{rate}_low`,
        `{rate}_high`; readers compute them from the counts, so a result stored without them has them too)."""
        result = {
            "planner": self.planner,
            "settings": self.settings,
            "clean": {
                **self.clean,
                **interval_fields("success_rate", self.clean.get("reached"), self.clean.get("maps")),
            },
            "strategies": {name: s.to_dict() for name, s in self.strategies.items()},
            "overall": [f.to_dict(intervals=True) for f in self.overall],
            "seconds": round(self.seconds, 3),
        }
        return stamp(ROBUSTNESS, result)
