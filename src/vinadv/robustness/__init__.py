"""How robust is a planner? The attack suite, run worst case per map on a fixed set of held-out maps.

`robustness(planner, maps, strategies, max_obstacles)` attacks every map of `maps` (first start of each) with each
strategy, one pair per map, greedily adding 1..`max_obstacles` cells (`vinadv.attacks.strategies`: the pairs of k
obstacles are the first k steps of one greedy attack of `max_obstacles`), labels every pair and computes its harm
(`vinadv.identify`), and reports, for each strategy and for the worst case over the strategies, at each k:

- paper success rate: maps whose pair is UrP or FP (the paper's successful attack), over the valid maps;
- harmful rate: maps whose pair is harmful (UrP, or an adversarial path further from optimal than the original
  path was; DESIGN.md "Harm"), over the valid maps;
- mean regret: the mean `regret_a` (adversarial path cost minus the optimal cost on the adversarial map, cost units)
  over the valid maps whose adversarial path reaches the goal, with its seeded percentile bootstrap 95% interval over
  those maps (`mean_regret_low`, `mean_regret_high`: `vinadv.intervals.bootstrap_mean_interval`).

A map is valid for a strategy when it got a pair (a valid cell at every step) and the planner reaches the goal on the
clean map (else the pair is `invalid`: it says nothing about the attack). Worst case per map: a map counts as broken
(paper) or harmful when ANY strategy's pair is; it is valid when the clean path reaches the goal and some strategy made
a pair; its regret is that of its worst pair (the most harmful: none when some strategy left the planner unreached,
else the largest `regret_a` over the strategies). The clean figures are the planner's on the unattacked maps: rollout
success and the mean regret of the reached paths.

For a planner that reports its expansions (`Capabilities.expansions`: a search planner), each strategy and the worst
case also have the effort-harmful rate: valid maps whose pair is effort-harmful (the planner's search grew more than
`EFFORT_TOL` times beyond A*'s on the same pair; DESIGN.md "Search effort", `vinadv.classify.effort`), over the valid
maps; the worst case counts a map when any strategy's pair is. Other planners' figures have no such field.

The ranking strategies keep, per map and step, the strongest candidate by `objective`: `harm` (default: UrP, then
the largest `regret_a`, so the exhaustive harmful rate is exactly the share of maps some single cell harms), `paper`
(UrP > FP > DP > UcP) or `effort` (the most cells expanded on the adversarial map, a search planner only). The paper
success rate is that of the kept pairs, so under `harm` it can be below what `vinadv attack --objective paper`
finds, and the other way round.

With `edit="remove"` every strategy frees obstacle cells instead of adding them (DESIGN.md "Obstacle removal"): k
cells freed greedily, the same figures; the settings then say `edit: remove` (absent: `add`).

As a job: `RobustnessConfig` (the maps by their settings or a maps file, the strategies and their options, the planner
by its spec; checked when made), `run(config, executor)` and the `RobustnessResult` (`to_dict()`: what `--json`
prints and the database stores). Provenance: the settings record the maps file (path and SHA-256, None for generated
maps), the planner's full spec (`planner`: `wastar:w=3`, `vinadv.planners.registry.spec_label`; the result's
`planner` holds its `PlannerSpec`, weights SHA-256 included) and the run's name (`name`, `--name`; None: none).

`heldout_maps(n, size, seed)` makes the fixed maps: the generator's first `n` maps of `seed` (default 1000, the
held-out seed of the evaluation tables), one start each. Results go to a database's `robustness` table
(`save_robustness`) and into the report (`vinadv.report`).
"""

from __future__ import annotations

import functools
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import numpy as np

from vinadv.attacks.strategies import STRATEGIES, make_attack
from vinadv.classify.effort import EFFORT_TOL, effort_figures
from vinadv.classify.harm import DEFAULT_TOL, check_tolerances
from vinadv.errors import InputError
from vinadv.executor import LOCAL, Executor, resolve, shipped
from vinadv.grid.generator import MIN_SIZE, generate_maps
from vinadv.grid.moves import DEFAULT_MOVES, check_moves
from vinadv.identify import identify, objective_strength
from vinadv.intervals import bootstrap_mean_interval
from vinadv.planners.registry import spec_label
from vinadv.planners.vin.planner import as_planner
from vinadv.records import ROBUSTNESS_SETTINGS, stamp
from vinadv.robustness.results import (
    WORST_CASE as WORST_CASE,
)
from vinadv.robustness.results import (
    Figures,
    MapOutcomes,
    RobustnessResult,
    StrategyResult,
    worst_case,
)
from vinadv.seeds import check_seed
from vinadv.vocabulary import ADD, SUCCESS_LABELS, label_counts

if TYPE_CHECKING:  # names for the annotations only: the planners and the grid load when a benchmark runs
    from vinadv.grid.mapset import MapSet
    from vinadv.planners.interface import Planner

#: the strategies run by default; `exhaustive` only on request (it plans every valid cell of every map)
DEFAULT_STRATEGIES = ("key-points", "saliency", "near-path", "random")
EXHAUSTIVE = "exhaustive"
#: the held-out seed of the evaluation tables (`vinadv vin eval --seed 1000`): never used in training
HELDOUT_SEED = 1000


def heldout_maps(
    n: int = 1000, size: int = 28, seed: int = HELDOUT_SEED, corner_cutting: bool = True, moves: str = DEFAULT_MOVES
):
    """The held-out maps of a robustness run: the generator's first `n` maps of `seed` (not a seed the planners were
    trained on), one start each, of the movement model `moves` (a `MapSet`)."""
    return generate_maps(n, size, seed=seed, n_starts=1, corner_cutting=corner_cutting, moves=moves)


def check_strategies(strategies, exhaustive: bool = False) -> tuple[str, ...]:
    """The strategies `vinadv robustness` runs: `strategies` ('all' or None: `DEFAULT_STRATEGIES`; else names joined
    by commas, 'all' among them standing for the defaults), plus `exhaustive` with `exhaustive`. InputError for an
    unknown name, a repeated one, or exhaustive named without `exhaustive` (it is slow: the flag says so)."""
    if strategies is None or strategies == "all":
        names = list(DEFAULT_STRATEGIES)
    else:
        names = [s.strip() for s in str(strategies).split(",")]
        if "all" in names:
            at = names.index("all")
            names = [*names[:at], *DEFAULT_STRATEGIES, *names[at + 1 :]]
    if EXHAUSTIVE in names and not exhaustive:
        raise InputError(
            "strategies: add exhaustive to run the exhaustive strategy (it plans every valid cell of "
            "every map at every step: slow)",
            "strategies",
            "exhaustive",
        )
    if exhaustive and EXHAUSTIVE not in names:
        names.append(EXHAUSTIVE)
    return _known(names)


def _known(names) -> tuple[str, ...]:
    """`names` as a tuple, each a strategy of `vinadv.attacks.strategies.STRATEGIES`, none twice, at least one."""
    names = tuple(names)
    for name in names:
        if name not in STRATEGIES:
            raise InputError(
                f"strategies: unknown strategy {name!r}; choose from all, {', '.join(STRATEGIES)}", "strategies"
            )
    if len(set(names)) != len(names):
        raise InputError(f"strategies: a strategy named twice in {','.join(names)}", "strategies")
    if not names:
        raise InputError("strategies: none given", "strategies")
    return names


def robustness(
    planner: Planner,
    maps: MapSet,
    strategies: Sequence[str] = DEFAULT_STRATEGIES,
    max_obstacles: int = 3,
    *,
    objective: str = "harm",
    seed: int = 0,
    budget: int = 8,
    radius: int = 2,
    harm_tol: float | None = None,
    harm_rtol: float = 0.0,
    edit: str = ADD,
    first_map: int = 0,
    progress: bool = False,
    maps_source: dict | None = None,
    run_name: str | None = None,
    start: np.ndarray | None = None,
) -> RobustnessResult:
    """Run the robustness benchmark of `planner` on `maps` (see the module doc).

    Args:
        planner: a `vinadv.planners.interface.Planner` (or a VIN), for the maps' size.
        maps: a `MapSet` (`heldout_maps`); the first start of each map is attacked.
        strategies: names of `vinadv.attacks.strategies.STRATEGIES`, run in this order (exhaustive included only when
            named; see `check_strategies`).
        max_obstacles: the curve's largest k, >= 1.
        objective: 'harm', 'paper' or 'effort' (a search planner only), what the ranking strategies keep
            (`vinadv.identify.objective_strength`).
        seed: the randomised strategies' seed.
        budget: key-points/saliency candidates per map and step.
        radius: near-path's distance to the path.
        harm_tol: the harm test's absolute tolerance (default `vinadv.classify.harm.DEFAULT_TOL`).
        harm_rtol: the harm test's relative tolerance (times the optimal cost), default 0.
        edit: `add` obstacles (default) or `remove` them (`vinadv.vocabulary.EDITS`).
        first_map: `maps` are maps `first_map..` of a larger benchmark (`Attack.attack`): the randomised strategies
            draw as they would for those maps there, so a benchmark run in chunks makes the whole one's pairs.
        progress: show a progress bar.
        maps_source: where `maps` came from when not from `heldout_maps` (a maps file: `{"maps": path,
            "maps_sha256": ...}`), recorded in the settings.
        run_name: the run's name (`--name`), recorded in the settings (`name`) to tell runs apart; None: none.
        start: `(n, j, 2)` cells every strategy's chain starts from (`StrategyResult.cells` of another strategy: the
            exhaustive one-cell optimum; -1 where a map has none), or None: the figures are then those of k = j +
            1..`max_obstacles` (`by_k[0].k` is j + 1), and the settings record `start_cells: j`.
    """
    harm_tol = DEFAULT_TOL if harm_tol is None else harm_tol
    check_tolerances(harm_tol, harm_rtol, ("harm_tol", "harm_rtol"))
    if int(max_obstacles) < 1:
        raise InputError(f"max_obstacles must be >= 1, got {max_obstacles}", "max_obstacles")
    strategies = _known(strategies.split(",") if isinstance(strategies, str) else strategies)
    strength = objective_strength(objective)
    check_name(run_name)
    if len(maps) < 1:
        raise InputError("maps: no maps to attack", "n")
    if int(max_obstacles) > maps.size**2:  # the curve has a point per k: bounded before any is computed
        raise InputError(
            f"max_obstacles {max_obstacles}: more than the {maps.size**2} cells of a {maps.size}x{maps.size} map",
            "max_obstacles",
        )
    t_start = time.perf_counter()
    # the maps' movement model: costs, regret and harm are its; a planner of another model is refused in one line
    planner = as_planner(planner, maps.size).for_moves(maps.moves)
    if objective == "effort" and not planner.capabilities.expansions:
        raise InputError(
            f"objective: effort ranks by the cells a search expands; planner {planner.name!r} reports no expansions "
            "(a search planner does: astar, wastar, neural-astar, transpath-*)",
            "objective",
        )
    n = len(maps)
    starts, goals, cc = maps.starts[:, 0], maps.goals, maps.corner_cutting
    clean = _clean(planner, maps)
    first_k = 1 if start is None else np.asarray(start).shape[1] + 1
    if first_k > int(max_obstacles):
        raise InputError(f"max_obstacles {max_obstacles}: not above the {first_k - 1} start cells", "max_obstacles")

    results: dict[str, StrategyResult] = {}
    for name in strategies:
        t0 = time.perf_counter()
        attack = make_attack(
            name, per_map=1, seed=seed, budget=budget, radius=radius, obstacles=max_obstacles, edit=edit
        )
        result = attack.attack(
            maps.obstacles,
            starts,
            goals,
            planner,
            cc,
            strength=strength,
            progress=progress,
            first_map=first_map,
            frozen=maps.frozen,
            start=start,
        )
        by_k, outcomes, cells = [], [], []
        for k in range(first_k, int(max_obstacles) + 1):
            kept = np.full((n, k, 2), -1, dtype=np.int64)
            if k - first_k < len(result.steps):
                pairs = result.steps[k - first_k]
                expert_o = (maps.expert_costs[pairs.map_index, 0], maps.expert.take(pairs.map_index * maps.n_starts))
                ident = identify(pairs, harm_tol=harm_tol, harm_rtol=harm_rtol, expert_o=expert_o)
                outcome = _outcomes(n, pairs, ident.labels, ident.harm.harm, ident.harm.regret_a)
                counts = label_counts(ident.labels)
                kept[pairs.map_index] = pairs.added
            # else: every map ran out of cells at the last step made (`AttackResult.steps`): no pair, as there
            outcomes.append(outcome)
            cells.append(kept)
            by_k.append(Figures.of(k, outcome, counts=counts))
        results[name] = StrategyResult(
            name, by_k, time.perf_counter() - t0, result.planner_calls, outcomes, attack.ranked_as(planner), cells
        )
    overall_outcomes = [worst_case([r.outcomes[i] for r in results.values()]) for i in range(len(outcomes))]
    overall = [Figures.of(first_k + i, o) for i, o in enumerate(overall_outcomes)]
    settings = {
        "n": n,
        "size": maps.size,
        "maps_seed": int(maps.seed),
        "corner_cutting": bool(cc),
        "strategies": list(strategies),
        "max_obstacles": int(max_obstacles),
        "objective": objective,
        "seed": seed,
        "budget": budget,
        "radius": radius,
        "harm_tolerance": harm_tol,
        "harm_rtol": harm_rtol,
        "moves": maps.moves,
        "maps": None,
        "maps_sha256": None,
        **(maps_source or {}),
        "edit": edit,
        "planner": spec_label(planner.spec()),
        "name": run_name,
        "effort_tolerance": EFFORT_TOL if planner.capabilities.expansions else None,
        **({} if start is None else {"start_cells": first_k - 1}),
    }
    return RobustnessResult(
        planner=planner.spec(),
        settings=stamp(ROBUSTNESS_SETTINGS, settings),
        clean=clean,
        strategies=results,
        overall=overall,
        seconds=time.perf_counter() - t_start,
        overall_outcomes=overall_outcomes,
    )


def attack_settings(settings) -> dict:
    """The keyword arguments of `robustness` that a benchmark's settings hold (a `RobustnessConfig`, a bench suite):
    the ranking objective, the randomised strategies' seed, the budget, the radius and the harm tolerances."""
    return {
        "objective": settings.objective,
        "seed": settings.seed,
        "budget": settings.budget,
        "radius": settings.radius,
        "harm_tol": settings.harm_tolerance,
        "harm_rtol": settings.harm_rtol,
    }


def _clean(planner, maps) -> dict:
    """The planner on the unattacked maps: rollout success and the mean regret of the reached paths."""
    plans = planner.plan(maps.obstacles, maps.starts[:, 0], maps.goals, maps.corner_cutting, maps.moves)
    reached = plans.reached
    regret = plans.paths.costs(maps.moves)[reached] - maps.expert_costs[reached, 0]
    low, high = bootstrap_mean_interval(regret)
    return {
        "maps": len(maps),
        "reached": int(reached.sum()),
        "success_rate": float(reached.mean()),
        "mean_regret": float(regret.mean()) if len(regret) else None,
        "mean_regret_low": low,
        "mean_regret_high": high,
    }


def _outcomes(n: int, pairs, labels, harm, regret_a) -> MapOutcomes:
    """Per-map outcomes of one pair per map (`pairs.map_index`), the maps without a pair empty."""
    map_index = pairs.map_index
    pair = np.zeros(n, dtype=bool)
    pair[map_index] = True
    label = np.full(n, "", dtype="<U7")
    label[map_index] = labels
    valid = pair & (label != "invalid")
    broken = valid & np.isin(label, SUCCESS_LABELS)
    harmful = np.zeros(n, dtype=bool)
    harmful[map_index] = np.asarray(harm) == "harmful"
    regret = np.full(n, np.nan)
    regret[map_index] = regret_a
    regret[~valid] = np.nan  # NaN already where the adversarial path misses the goal
    effort_harmful = effort = None
    if pairs.expanded_o is not None and pairs.astar_expansions_a is not None:
        figures = effort_figures(
            pairs.expansions_o, pairs.expansions_a, pairs.astar_expansions_o, pairs.astar_expansions_a
        )
        effort_harmful = np.zeros(n, dtype=bool)
        effort_harmful[map_index] = np.equal(figures["effort_harmful"], True)
        effort_harmful &= valid
        effort = np.full(n, np.nan)
        effort[map_index] = figures["effort_ratio"]
        effort[~valid] = np.nan  # a pair that is not valid says nothing of the attack
    return MapOutcomes(
        pair=pair,
        valid=valid,
        broken=broken,
        harmful=harmful & valid,
        regret=regret,
        label=label,
        effort_harmful=effort_harmful,
        effort=effort,
    )


@dataclass(frozen=True)
class RobustnessConfig:
    """Everything that determines a robustness benchmark (`vinadv robustness`); checked when made (InputError naming
    the field). The maps: the generator's first `n` maps of `seed` at `size` (`heldout_maps`), or the first `n`
    maps of the maps file `maps` (its `size`, `corner_cutting` and `moves` given with it, and its SHA-256:
    `vinadv.pipeline.maps_file_config`). `seed` also seeds the randomised strategies. `strategies`: names, or names
    joined by commas (`check_strategies` expands 'all')."""

    planner: str | None = None
    weights: str | None = None
    n: int = 1000
    size: int = 28
    seed: int = HELDOUT_SEED
    corner_cutting: bool = True
    moves: str = DEFAULT_MOVES
    maps: str | None = None
    maps_sha256: str | None = None
    strategies: tuple[str, ...] = DEFAULT_STRATEGIES
    max_obstacles: int = 3
    objective: str = "harm"
    budget: int = 8
    radius: int = 2
    edit: str = ADD
    harm_tolerance: float = DEFAULT_TOL
    harm_rtol: float = 0.0
    name: str | None = None

    def __post_init__(self):
        check_name(self.name)
        strategies = self.strategies.split(",") if isinstance(self.strategies, str) else self.strategies
        object.__setattr__(self, "strategies", _known(s.strip() for s in strategies))
        least = {"n": 1, "max_obstacles": 1, "budget": 1, "radius": 0, "size": MIN_SIZE}
        for name, bound in least.items():
            if getattr(self, name) < bound:
                raise InputError(f"{name} must be >= {bound}, got {getattr(self, name)}", name)
        check_seed(self.seed)
        check_tolerances(self.harm_tolerance, self.harm_rtol)
        check_moves(self.moves, self.corner_cutting)
        objective_strength(self.objective)
        make_attack(self.strategies[0], 1, self.seed, self.budget, self.radius, self.max_obstacles, self.edit)
        if (self.maps is None) != (self.maps_sha256 is None):
            raise InputError("maps and maps_sha256 go together (maps_file_config gives both)", "maps")

    def to_dict(self) -> dict:
        """Every field (the strategies as a tuple); the stored settings are the result's (`RobustnessResult`)."""
        return asdict(self)

    def load_maps(self) -> MapSet:
        """The benchmark's maps: generated, or the maps file's first `n` (refused if its SHA-256 changed)."""
        if self.maps is None:
            return heldout_maps(self.n, self.size, seed=self.seed, corner_cutting=self.corner_cutting, moves=self.moves)
        from vinadv.grid.mapset import MapSet  # noqa: PLC0415 (as the planners: loaded when a benchmark runs)
        from vinadv.planners.weights import weights_checksum  # noqa: PLC0415 (a file's SHA-256)

        if weights_checksum(self.maps) != self.maps_sha256:
            raise InputError(f"maps file {self.maps}: its SHA-256 is not {self.maps_sha256}", "maps")
        return MapSet.load(self.maps).take(slice(0, self.n))


def _robustness_task(config: RobustnessConfig, planner, maps, progress: bool, chunk: int) -> RobustnessResult:
    """The task of `run`: the whole benchmark (one chunk), the planner given or by reference."""
    source = None if config.maps is None else {"maps": config.maps, "maps_sha256": config.maps_sha256}
    return robustness(
        resolve(planner),
        maps,
        config.strategies,
        config.max_obstacles,
        edit=config.edit,
        progress=progress,
        maps_source=source,
        run_name=config.name,
        **attack_settings(config),
    )


def run(
    config: RobustnessConfig,
    executor: Executor = LOCAL,
    *,
    db: str | None = None,
    device: str | None = None,
    progress: bool = False,
) -> RobustnessResult:
    """The robustness benchmark of `config` (`robustness`), on `executor` (as one task: its strategies share the
    maps and their figures the per-map outcomes), the planner's forward on `device`; with `db`, stored there
    (`save_robustness`, the row's id in `result.id`); a database that will be refused is refused before the work."""
    from vinadv.planners.registry import PlannerRef, load_planner_for  # noqa: PLC0415 (loaded when a benchmark runs)

    # the planner first (one of another movement model than the maps' is refused in one line), then the maps
    planner = load_planner_for(config.planner, config.weights, config, device)
    if db is not None:
        from vinadv.store import Store  # noqa: PLC0415 (SQLAlchemy: only to store the result)

        with Store.open(db):
            pass
    maps = config.load_maps()
    planner_x = shipped(
        executor, planner, lambda: PlannerRef.of(planner, config.planner, config.weights, config.corner_cutting)
    )
    task = functools.partial(_robustness_task, config, planner_x, maps, progress and not executor.remote)
    result = next(iter(executor.map(task, [0])))
    if db is not None:
        result.id = save_robustness(result, db)
    return result


def save_robustness(result: RobustnessResult, db: str | None) -> int:
    """Store `result` as a row of the database's `robustness` table (the planner's full spec, its weights' SHA-256,
    the run's name); return its id."""
    from vinadv.store import Store  # noqa: PLC0415 (SQLAlchemy: only to store the result)

    with Store.open(db) as store:
        return store.add_robustness(
            result.settings.get("planner") or spec_label(result.planner),
            result.planner["weights_sha256"],
            result.settings,
            result.to_dict(),
            run_name=result.settings.get("name"),
        )


def check_name(name: str | None) -> None:
    """InputError naming `name` unless it is None or a run name the store takes (`vinadv.store.runs`' rule)."""
    if name is not None:
        from vinadv.store.runs import check_run_name  # noqa: PLC0415 (SQLAlchemy: only with a name)

        check_run_name(name)


__all__ = [
    "HELDOUT_SEED",
    "DEFAULT_STRATEGIES",
    "Figures",
    "MapOutcomes",
    "RobustnessConfig",
    "RobustnessResult",
    "StrategyResult",
    "attack_settings",
    "heldout_maps",
    "check_strategies",
    "robustness",
    "run",
    "save_robustness",
    "worst_case",
]
