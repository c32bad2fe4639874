"""`vinadv attack` as a job: `AttackConfig` (a maps file, a strategy and its options, the planner by its spec),
`run(config, executor)` and `AttackOutcome` (the pairs, their labels and harm, `to_dict()` the summary).

`attack_maps` is the one attack call: make the strategy's attack and run it on maps (their first start) with the
strength of an objective; `vinadv.pipeline`'s shards and this job's chunks both make their pairs with it.

On a remote executor the maps are cut in chunks of `shard_size` (`Executor.bounds`): each chunk is attacked as maps
`lo..` of the file (`first_map`: the randomised strategies draw as they would for the whole file), and the chunks'
pairs joined, so the pairs are the same wherever they were made.
"""

from __future__ import annotations

import functools
import time
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import numpy as np

from vinadv.attacks.strategies import AttackResult, make_attack
from vinadv.classify.harm import DEFAULT_TOL, check_tolerances
from vinadv.errors import InputError
from vinadv.executor import LOCAL, Executor, resolve, shipped
from vinadv.identify import Identification, identify, objective_strength, pairs_summary
from vinadv.planners.spec import PlannerSpec
from vinadv.seeds import check_seed
from vinadv.vocabulary import ADD

if TYPE_CHECKING:
    from vinadv.planners.interface import Planner

#: `make_attack`'s options that a config holds (the strategy aside)
ATTACK_OPTIONS = ("per_map", "seed", "budget", "radius", "obstacles", "edit")


def attack_maps(
    strategy: str,
    options: dict,
    obstacles,
    starts,
    goals,
    planner: Planner,
    corner_cutting: bool,
    *,
    objective: str = "paper",
    first_map: int = 0,
    progress: bool = False,
    frozen=None,
) -> AttackResult:
    """`strategy`'s attack (`make_attack(strategy, **options)`) of the maps `obstacles`, `starts` (one per map),
    `goals` with `planner`, keeping the strongest candidates by `objective` ('paper' | 'harm'); the maps are maps
    `first_map..` of a larger set (`Attack.attack`); `frozen` `(B, N, N)`: cells no edit may touch, or None."""
    attack = make_attack(strategy, **options)
    return attack.attack(
        obstacles,
        starts,
        goals,
        planner,
        corner_cutting,
        strength=objective_strength(objective),
        progress=progress,
        first_map=first_map,
        frozen=frozen,
    )


@dataclass(frozen=True)
class AttackConfig:
    """Everything that determines the pairs of `vinadv attack`; checked when made (InputError naming the field)."""

    maps: str
    strategy: str
    per_map: int = 1
    seed: int = 0
    budget: int = 8
    radius: int = 2
    obstacles: int = 1
    edit: str = ADD
    objective: str = "paper"
    planner: str | None = None
    weights: str | None = None
    harm_tolerance: float = DEFAULT_TOL
    harm_rtol: float = 0.0
    shard_size: int = 1000

    def __post_init__(self):
        check_seed(self.seed)
        make_attack(self.strategy, **self.options())  # the strategy and its options, each named when refused
        objective_strength(self.objective)
        check_tolerances(self.harm_tolerance, self.harm_rtol)
        if self.shard_size < 1:
            raise InputError(f"shard_size must be >= 1, got {self.shard_size}", "shard_size")

    def options(self) -> dict:
        """`make_attack`'s keyword arguments."""
        return {name: getattr(self, name) for name in ATTACK_OPTIONS}

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class AttackOutcome:
    """What `run` made: the attack's result (`result.pairs`: the pairs file's content), their identification, and
    what the summary says (`to_dict`)."""

    config: AttackConfig
    result: AttackResult
    identification: Identification
    n_maps: int
    seconds: float
    params: dict
    planner: PlannerSpec
    planner_name: str
    ranked_as: str | None

    @property
    def pairs(self):
        return self.result.pairs

    def to_dict(self) -> dict:
        ident = self.identification
        out = pairs_summary(
            ident.labels,
            self.n_maps,
            len(self.result.no_valid_cell),
            self.result.planner_calls,
            self.seconds,
            harm_table=ident.harm_table(),
        )
        out.update(
            strategy=self.config.strategy,
            params=self.params,
            planner=self.planner,
            objective=self.config.objective,
            edit=self.config.edit,
        )
        if self.ranked_as:  # saliency without gradients (optimal, most search planners): ranked as key-points
            out["ranked_as"] = self.ranked_as
        return out


def _attack_chunk(strategy: str, options: dict, objective: str, planner, corner_cutting: bool, progress: bool, chunk):
    """The task of `run`: chunk `(first_map, obstacles, starts, goals, frozen)` attacked (`attack_maps`)."""
    first_map, obstacles, starts, goals, frozen = chunk
    return attack_maps(
        strategy,
        options,
        obstacles,
        starts,
        goals,
        resolve(planner),
        corner_cutting,
        objective=objective,
        first_map=first_map,
        progress=progress,
        frozen=frozen,
    )


def run(
    config: AttackConfig, executor: Executor = LOCAL, *, device: str | None = None, progress: bool = False
) -> AttackOutcome:
    """Attack the maps of `config.maps` (the first start of each) with the planner of `config` (its forward on
    `device`), on `executor`, and identify the pairs (labels and harm)."""
    from vinadv.grid.mapset import MapSet  # noqa: PLC0415 (as the planners: loaded when a job runs)
    from vinadv.planners.registry import PlannerRef, load_planner_for  # noqa: PLC0415 (as above)

    maps = MapSet.load(config.maps)
    planner = load_planner_for(config.planner, config.weights, maps, device)
    attack = make_attack(config.strategy, **config.options())
    planner_x = shipped(
        executor, planner, lambda: PlannerRef.of(planner, config.planner, config.weights, maps.corner_cutting)
    )
    bounds = executor.bounds(len(maps), config.shard_size)
    task = functools.partial(
        _attack_chunk,
        config.strategy,
        config.options(),
        config.objective,
        planner_x,
        maps.corner_cutting,
        progress and len(bounds) == 1,
    )
    frozen = maps.frozen
    chunks = (
        (lo, maps.obstacles[lo:hi], maps.starts[lo:hi, 0], maps.goals[lo:hi], None if frozen is None else frozen[lo:hi])
        for lo, hi in bounds
    )
    t0 = time.perf_counter()
    bar = None
    if progress and len(bounds) > 1:
        from tqdm import tqdm  # noqa: PLC0415 (only with a progress bar)

        bar = tqdm(total=len(maps), desc=f"attack {config.strategy}", unit="map")
    parts = []
    for (lo, hi), part in zip(bounds, executor.map(task, chunks)):
        parts.append(part)
        if bar is not None:
            bar.update(hi - lo)
    if bar is not None:
        bar.close()
    if len(parts) == 1:
        result = parts[0]
    else:
        result = _joined(parts, bounds, attack, maps, config.strategy)
    seconds = time.perf_counter() - t0
    ident = identify(result.pairs, harm_tol=config.harm_tolerance, harm_rtol=config.harm_rtol)
    return AttackOutcome(
        config=config,
        result=result,
        identification=ident,
        n_maps=len(maps),
        seconds=seconds,
        params=attack.params(),
        planner=planner.spec(),
        planner_name=planner.name,
        ranked_as=attack.ranked_as(planner),
    )


def _joined(parts: list[AttackResult], bounds, attack, maps, strategy: str) -> AttackResult:
    """The attack of all the maps from its chunks' (`bounds[i]` the maps of `parts[i]`, map indices local)."""
    from vinadv.attacks.pairs import PairSet  # noqa: PLC0415 (loaded with the attack)

    params = parts[0].pairs.params if parts else attack.params()  # the planner's spec included
    steps = []
    # each greedy step's pairs, the chunks' joined (the last: the result); a chunk whose maps ran out of cells stopped
    # early (`AttackResult.steps`) and adds none to the later steps
    for k in range(max((len(p.steps) for p in parts), default=1)):
        shifted = []
        for (lo, _), part in zip(bounds, parts):
            if k >= len(part.steps):
                continue
            step = part.steps[k]
            step.map_index = step.map_index + lo
            shifted.append(step)
        steps.append(
            PairSet.concat(
                shifted,
                size=maps.size,
                n_added=k + 1,
                strategy=strategy,
                params=params,
                corner_cutting=maps.corner_cutting,
            )
        )
    no_valid = (
        np.concatenate([p.no_valid_cell + lo for (lo, _), p in zip(bounds, parts)]).astype(np.int64)
        if parts
        else np.zeros(0, np.int64)
    )
    return AttackResult(steps[-1], no_valid, int(sum(p.planner_calls for p in parts)), steps)


__all__ = ["ATTACK_OPTIONS", "AttackConfig", "AttackOutcome", "attack_maps", "pairs_summary", "run"]
