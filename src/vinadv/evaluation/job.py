"""`vinadv evaluate` as a job: `EvaluateConfig` (a stored run and the classifier comparison's options),
`run(config, executor)` and `EvaluateResult` (the stored rows and measurements, `to_dict()` the summary).

The job evaluates a run already stored (its planner is the run's, read from the store: the config names none) and
stores what it measured beside it: the planner's quality and the processing time (`planner_quality`, `timing`)
first, so that a run with too few FP/DP pairs for the comparison still gets them, then the comparison's rows
(`classifiers.evaluate_run`).
"""

from __future__ import annotations

import functools
from dataclasses import asdict, dataclass

from vinadv.errors import InputError
from vinadv.evaluation.classifiers import CLASSIFIERS, DEFAULT_SIZES, SETTINGS, evaluate_run, parse_list, parse_sizes
from vinadv.evaluation.planner_quality import QUALITY_MAPS, evaluate_planner_quality
from vinadv.evaluation.timing import evaluate_timing
from vinadv.executor import LOCAL, Executor
from vinadv.seeds import check_seed


@dataclass(frozen=True)
class EvaluateConfig:
    """What `vinadv evaluate` does; checked when made (InputError naming the field).

    `db`: the database (URL or SQLite file; None: `$VINADV_DB`, else `vinadv.db`) holding the run, where the results
    are stored; `run`: the run's id or name (its latest run), None for the latest run; `classifiers`: names from
    `CLASSIFIERS` (a tuple, or joined by commas); `setting`: 'baseline' or 'tuned'; `sizes`: the training-set
    fractions of fig. 8, in (0, 1] (1.0 always added); `seed`: of the split, augmentation and training;
    `quality_maps`: the most of the run's maps its planner's quality is measured on (`planner_quality.run_maps`: the
    first, in pair-index order)."""

    db: str | None = None
    run: str | int | None = None
    classifiers: tuple[str, ...] = CLASSIFIERS
    setting: str = "baseline"
    sizes: tuple[float, ...] = DEFAULT_SIZES
    seed: int = 0
    quality_maps: int = QUALITY_MAPS

    def __post_init__(self):
        object.__setattr__(self, "classifiers", tuple(parse_list(self.classifiers, CLASSIFIERS, "classifiers")))
        object.__setattr__(self, "sizes", tuple(parse_sizes(self.sizes)))
        if self.setting not in SETTINGS:
            raise InputError(f"setting: {self.setting!r} not in {','.join(SETTINGS)}", "setting")
        check_seed(self.seed)
        if isinstance(self.quality_maps, bool) or not isinstance(self.quality_maps, int) or self.quality_maps < 1:
            raise InputError(f"quality_maps: at least 1 map, got {self.quality_maps!r}", "quality_maps")

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class EvaluateResult:
    """What `run` stored: the config, the run's id, the comparison's rows (`evaluations` columns; `metrics`,
    `curves` as dicts), the planner's quality and the processing time; `url`: the database's."""

    config: EvaluateConfig
    run_id: int
    rows: list[dict]
    planner_quality: dict
    timing: dict
    url: str

    def to_dict(self) -> dict:
        """The summary `vinadv evaluate --json` prints: the rows without their curve points."""
        return {
            "run_id": self.run_id,
            "rows": [{k: v for k, v in r.items() if k != "curves"} for r in self.rows],
            "planner_quality": self.planner_quality,
            "timing": self.timing,
        }


def _latest_run(store) -> int:
    runs = store.list_runs()
    if not runs:
        raise InputError(f"database {store.url}: no runs stored yet (run `vinadv run` first)")
    return int(runs[-1]["id"])


def _evaluate_task(config: EvaluateConfig, progress: bool, chunk: int) -> EvaluateResult:
    """The task of `run`: the whole evaluation (one chunk: the comparison's fits share the run's pairs)."""
    from vinadv.store import Store  # noqa: PLC0415 (SQLAlchemy: loaded when the job runs)

    with Store.open(config.db, create=False) as store:
        run_id = store.resolve_run(config.run, "run") if config.run is not None else _latest_run(store)
        # the measurements first: a run with too few FP/DP pairs to compare classifiers still gets them
        quality = evaluate_planner_quality(store, run_id, config.quality_maps)
        timing = evaluate_timing(store, run_id)
        rows = evaluate_run(
            store, run_id, config.classifiers, config.setting, config.sizes, config.seed, progress=progress
        )
        return EvaluateResult(config, run_id, rows, quality, timing, str(store.url))


def run(config: EvaluateConfig, executor: Executor = LOCAL, *, progress: bool = False) -> EvaluateResult:
    """Evaluate the stored run of `config` and store the results (`vinadv evaluate`), on `executor` as one task (it
    reads and writes `config.db`, which a remote worker must reach by the same URL)."""
    task = functools.partial(_evaluate_task, config, progress and not executor.remote)
    return next(iter(executor.map(task, [0])))


__all__ = ["EvaluateConfig", "EvaluateResult", "run"]
