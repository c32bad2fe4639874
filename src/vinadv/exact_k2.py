"""The exact k = 2 diagnostic (`vinadv robustness --exact-k2`): how far the greedy two-obstacle attacks are from the
true worst case over two added cells (DESIGN.md "Several obstacles").

`exact_k2(planner, maps, mode)`:

1. the exact one-cell search (the `exhaustive` strategy kept by harm: every valid cell of every map,
   `vinadv.robustness.robustness`), which says which maps one cell already harms;
2. on the other valid maps (the clean path reaches the goal, a valid cell exists), every pair of addable cells
   (`vinadv.attacks.exact_pairs`), judged by harm (`vinadv.identify`, the robustness run's tolerances). Mode
   `harmful` stops a map at its first harmful pair (the harmful rate needs no more); mode `regret` plans every pair of
   those maps and keeps the most harmful (UrP, else the largest adversarial regret).

A map is harmed by at most two cells when one cell or a pair harms it: the exact harmful rate at k <= 2, over the
valid maps. Given a robustness result of the same maps and settings with at least two greedy steps (`greedy`), the
gap is the maps the exact search harms and the greedy worst case at k <= 2 (any strategy's pair at k = 1 or k = 2)
does not. A greedy pair is a valid pair of at most two cells, so the greedy never harms a map the exact search does
not: `greedy_only` counts such maps and is 0 unless something is wrong. In mode `regret`, on the searched maps, the
largest regret at k <= 2 of each (unreached: infinite) against the greedy's.

The maps harmed at one cell are not paired: their worst pair is not searched (the largest regret there is not
known), as the issue that asked for this diagnostic set out. Cost: one planner call per valid pair, about 165,000 per
28x28 map, so it suits the VIN's batched engine (docs/guide/robustness.md gives the measured cost).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from vinadv.attacks.exact_pairs import ExactPairsResult, exact_pairs
from vinadv.classify.harm import DEFAULT_TOL, check_tolerances
from vinadv.errors import InputError
from vinadv.identify import harm_order, identify
from vinadv.intervals import interval_fields
from vinadv.planners.vin.planner import as_planner
from vinadv.robustness import EXHAUSTIVE, MapOutcomes, RobustnessConfig, RobustnessResult, robustness
from vinadv.vocabulary import ADD

if TYPE_CHECKING:
    from vinadv.grid.mapset import MapSet
    from vinadv.planners.interface import Planner

HARMFUL, REGRET = "harmful", "regret"
#: the diagnostic's modes: stop a map at its first harmful pair, or plan every pair for the largest regret
MODES = (HARMFUL, REGRET)


@dataclass
class ExactK2Result:
    """The diagnostic's figures (`to_dict`) and per-map arrays (`(n,)`, map order).

    Attributes:
        mode: `harmful` or `regret`. valid: the map is valid (the clean path reaches the goal, a valid cell exists).
        harmful_k1: one cell harms it (the exhaustive search). harmful_pair: a pair harms it (searched maps only).
        regret: the largest regret over the pairs of a searched map in mode `regret` (inf: a pair leaves the goal
            unreached), NaN elsewhere. search: the pair search's result. greedy: the greedy worst case at k <= 2
            (harmful, regret as `regret`), or None.
    """

    mode: str
    valid: np.ndarray
    harmful_k1: np.ndarray
    harmful_pair: np.ndarray
    regret: np.ndarray
    search: ExactPairsResult
    greedy: MapOutcomes | None
    greedy_strategies: list[str]
    seconds: float

    @property
    def harmful(self) -> np.ndarray:
        """Harmed by at most two cells."""
        return self.harmful_k1 | self.harmful_pair

    def to_dict(self) -> dict:
        s, valid = self.search, int(self.valid.sum())
        harmful = int(self.harmful.sum())
        out = {
            "mode": self.mode,
            "maps": len(self.valid),
            "valid": valid,
            "harmful_k1": int(self.harmful_k1.sum()),
            "searched": int(s.searched.sum()),
            "complete": bool(s.complete[s.searched].all()),
            "candidate_pairs": int(s.candidate_pairs.sum()),
            "tried_pairs": int(s.tried.sum()),
            "planned_pairs": int(s.planned.sum()),
            "planner_calls": s.planner_calls,
            "harmful_pair": int(self.harmful_pair.sum()),
            "harmful": harmful,
            "harmful_rate": harmful / valid if valid else None,
            **interval_fields("harmful_rate", harmful, valid),
            "seconds": round(self.seconds, 3),
        }
        kept = ~np.isnan(self.regret)  # the searched maps with a valid pair (mode regret)
        if self.mode == REGRET:
            out["regret"] = _regret_figures(self.regret[kept], None)
        if self.greedy is not None:
            greedy = self.greedy.harmful & self.valid
            gap = int((self.harmful & ~greedy).sum())
            out["greedy"] = {
                "strategies": self.greedy_strategies,
                "harmful": int(greedy.sum()),
                "harmful_rate": int(greedy.sum()) / valid if valid else None,
                **interval_fields("harmful_rate", int(greedy.sum()), valid),
                "gap": gap,
                "gap_rate": gap / valid if valid else None,
                "greedy_only": int((greedy & ~self.harmful).sum()),
            }
            if self.mode == REGRET:
                out["greedy"]["regret"] = _regret_figures(self.greedy.regret[kept], self.regret[kept])
        out["per_map"] = self._per_map()
        return out

    def _per_map(self) -> list[dict]:
        """One row per searched map: its index, pairs, whether a pair harms it, the witness pair, the regret."""
        s = self.search
        witness = {int(m): s.pairs.added[i].tolist() for i, m in enumerate(s.pairs.map_index)}
        rows = []
        for m in np.flatnonzero(s.searched).tolist():
            row = {
                "map": m,
                "candidate_pairs": int(s.candidate_pairs[m]),
                "planned": int(s.planned[m]),
                "harmful_pairs": int(s.harmful_pairs[m]),
                "harmful": bool(self.harmful_pair[m]),
                "pair": witness.get(m),
            }
            if self.mode == REGRET:
                row["regret"] = _finite(self.regret[m])
            if self.greedy is not None:
                row["greedy_harmful"] = bool(self.greedy.harmful[m])
                if self.mode == REGRET:
                    row["greedy_regret"] = _finite(self.greedy.regret[m])
            rows.append(row)
        return rows


def _finite(x: float) -> float | str | None:
    """A regret for JSON: a float, `"inf"` (the goal left unreached) or None (NaN: none)."""
    return None if np.isnan(x) else ("inf" if np.isinf(x) else float(x))


def _regret_figures(regret: np.ndarray, exact: np.ndarray | None) -> dict:
    """The largest regrets of the searched maps (inf: unreached): how many unreached, the mean of the others; against
    `exact` (the greedy's figures), the maps where the exact search finds worse and the mean difference where both
    reach the goal."""
    reached = np.isfinite(regret)
    out = {
        "maps": len(regret),
        "unreached": int((~reached).sum()),
        "mean": float(regret[reached].mean()) if reached.any() else None,
    }
    if exact is not None:
        both = reached & np.isfinite(exact)
        out["exact_worse"] = int((exact > regret + DEFAULT_TOL).sum())
        out["mean_gap"] = float((exact[both] - regret[both]).mean()) if both.any() else None
    return out


def greedy_k2(result: RobustnessResult) -> MapOutcomes:
    """The greedy worst case at k <= 2 of a robustness result (`overall_outcomes[0]` and `[1]`): harmful when a pair of
    either harms the map, its regret the larger (inf where the goal is left unreached, NaN where not valid)."""
    if len(result.overall_outcomes) < 2:
        raise InputError("the greedy result has no k = 2 step: run it with max_obstacles >= 2", "max_obstacles")
    if result.settings.get("edit", ADD) != ADD:
        raise InputError("the exact k = 2 search adds obstacles: the greedy result must too", "edit")
    k1, k2 = result.overall_outcomes[:2]
    regrets = [np.where(o.valid & np.isnan(o.regret), np.inf, o.regret) for o in (k1, k2)]
    return MapOutcomes(
        pair=k1.pair | k2.pair,
        valid=k1.valid | k2.valid,
        broken=k1.broken | k2.broken,
        harmful=k1.harmful | k2.harmful,
        regret=np.fmax(*regrets),
        label=np.full(len(k1.pair), ""),
    )


def exact_k2(
    planner: Planner,
    maps: MapSet,
    mode: str = HARMFUL,
    *,
    harm_tol: float = DEFAULT_TOL,
    harm_rtol: float = 0.0,
    greedy: RobustnessResult | None = None,
    progress: bool = False,
) -> ExactK2Result:
    """The exact k = 2 diagnostic of `planner` on `maps` (first start of each; see the module doc); `greedy`: a
    robustness result of the same maps to measure the greedy's gap against."""
    if mode not in MODES:
        raise InputError(f"exact k = 2 mode: {mode!r} is not one of {'|'.join(MODES)}", "exact_k2")
    check_tolerances(harm_tol, harm_rtol, ("harm_tol", "harm_rtol"))
    if greedy is not None and greedy.settings["n"] != len(maps):
        raise InputError(f"the greedy result has {greedy.settings['n']} maps, not {len(maps)}", "greedy")
    greedy_outcomes = None if greedy is None else greedy_k2(greedy)
    t0 = time.perf_counter()
    planner = as_planner(planner, maps.size).for_moves(maps.moves)
    one = robustness(planner, maps, (EXHAUSTIVE,), 1, harm_tol=harm_tol, harm_rtol=harm_rtol, progress=progress)
    k1 = one.strategies[EXHAUSTIVE].outcomes[0]
    starts = maps.starts[:, 0]

    def judge(pairs):
        expert_o = (maps.expert_costs[pairs.map_index, 0], maps.expert.take(pairs.map_index * maps.n_starts))
        ident = identify(pairs, harm_tol=harm_tol, harm_rtol=harm_rtol, expert_o=expert_o)
        return ident.harm.harm == "harmful", harm_order(ident.labels, ident.harm.regret_a)

    search = exact_pairs(
        maps.obstacles,
        starts,
        maps.goals,
        planner,
        judge,
        search=k1.valid & ~k1.harmful,
        stop_at_harmful=mode == HARMFUL,
        corner_cutting=maps.corner_cutting,
        frozen=maps.frozen,
        progress=progress,
    )
    harmful_pair = search.harmful.copy()
    regret = np.full(len(maps), np.nan)
    if mode == REGRET and len(search.pairs):
        _, strength = judge(search.pairs)
        regret[search.pairs.map_index] = strength
    return ExactK2Result(
        mode=mode,
        valid=k1.valid,
        harmful_k1=k1.harmful,
        harmful_pair=harmful_pair,
        regret=regret,
        search=search,
        greedy=greedy_outcomes,
        greedy_strategies=[] if greedy is None else list(greedy.strategies),
        seconds=time.perf_counter() - t0,
    )


def run(
    config: RobustnessConfig, greedy: RobustnessResult, mode: str, *, device: str | None = None, progress: bool = False
) -> ExactK2Result:
    """The diagnostic of `config`'s planner on its maps, against `greedy` (the robustness run of `config`), in this
    process (`vinadv robustness --exact-k2`)."""
    from vinadv.planners.registry import load_planner_for  # noqa: PLC0415 (as `vinadv.robustness.run`)

    planner = load_planner_for(config.planner, config.weights, config, device)
    return exact_k2(
        planner,
        config.load_maps(),
        mode,
        harm_tol=config.harm_tolerance,
        harm_rtol=config.harm_rtol,
        greedy=greedy,
        progress=progress,
    )


__all__ = ["HARMFUL", "MODES", "REGRET", "ExactK2Result", "exact_k2", "greedy_k2", "run"]
