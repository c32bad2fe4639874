"""`vinadv bench run` as a job: `BenchConfig` (a suite by name, the planner by its spec), `run(config, executor)`
and `BenchResult` (the entry, `to_dict()`; `vinadv.bench.scoring`)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

from vinadv.bench.scoring import entry_json, run_bench
from vinadv.bench.suites import Suite, get_suite
from vinadv.executor import LOCAL, Executor


@dataclass(frozen=True)
class BenchConfig:
    """What determines a bench entry: the suite (`vinadv.bench.suites`, by name), the planner's spec and weights,
    and the folder of a data suite's files (`data`); checked when made (an unknown suite: InputError naming it)."""

    suite: str
    planner: str | None = None
    weights: str | None = None
    data: str | None = None

    def __post_init__(self):
        get_suite(self.suite)

    def to_dict(self) -> dict:
        return asdict(self)

    @property
    def frozen_suite(self) -> Suite:
        return get_suite(self.suite)


@dataclass
class BenchResult:
    """A bench entry (`vinadv.bench.scoring.make_entry`)."""

    entry: dict

    def to_dict(self) -> dict:
        return self.entry

    def json(self) -> str:
        """The entry as written (`entry_json`)."""
        return entry_json(self.entry)


def run(
    config: BenchConfig,
    executor: Executor = LOCAL,
    *,
    db: str | None = None,
    resume: bool = False,
    progress: bool = False,
    device: str | None = None,
) -> BenchResult:
    """The entry of the planner of `config` on its suite (`run_bench`), its chunks computed on `executor`; with `db`
    each chunk stored when done, with `resume` the stored ones read. `device`: where the planner's forward runs."""
    from vinadv.errors import InputError  # noqa: PLC0415 (light; beside the planners' import)
    from vinadv.planners.registry import PlannerRef, load_planner  # noqa: PLC0415 (loaded when a job runs)

    if resume and db is None:
        raise InputError("resume: only with db", "resume", "db")
    suite = config.frozen_suite
    # the planner runs under the suite's rule (a planner trained on other maps too: its entry's `other_rules` flag)
    cuts = suite.cuts_corners()
    planner = load_planner(
        config.planner, suite.size, weights=config.weights, corner_cutting=cuts, device=device, moves=suite.movement()
    )
    ref = PlannerRef.of(planner, config.planner, config.weights, corner_cutting=cuts) if executor.remote else None
    entry = run_bench(
        suite, planner, db=db, resume=resume, progress=progress, data=config.data, executor=executor, planner_ref=ref
    )
    return BenchResult(entry)


__all__ = ["BenchConfig", "BenchResult", "run"]
