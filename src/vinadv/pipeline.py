"""The main job, `vinadv run`: maps -> attack -> identify -> store, shard by shard.

The work is split in shards of `shard_size` maps. Shard `k` generates its maps from the seed `(seed, k)`, attacks
them with the seed `(seed, k)`, identifies and stores its pairs; nothing in a shard depends on another, so the
stored run does not depend on how (or where) shards are computed. A pair's `pair_index` is fixed by its map and
slot: `global_map * per_map + slot` (with `per_map = 0`, all pairs: `global_map * N*N + row*N + col` of the last
added cell).

With `maps` (`maps_file_config`: a maps file, such as an MP import, instead of generated maps), shard `k` takes the
file's maps `k * shard_size ..` (the first start of each); the file's path and SHA-256 are in the run's config, and a
shard refuses a file whose checksum differs (a worker elsewhere reading another file under that path).

A shard is written in batches inside transactions and `(run_id, pair_index)` is unique; a run killed part way
resumes with `resume=True`: shards are stored in order and each completely stored shard is recorded
(`Store.set_shards_done`), so the recorded ones are skipped (and, for a run that recorded no count, the shards
before the last one holding a pair); the rest are recomputed and only their missing pairs are written. A
database fault while storing (a full disk) stops the run with one line naming the database and how to resume.
"""

from __future__ import annotations

import contextlib
import functools
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from vinadv import __version__
from vinadv.attacks.strategies import make_attack
from vinadv.classify.harm import DEFAULT_TOL, check_tolerances, cross_table, harm_summary
from vinadv.errors import InputError, OutputError
from vinadv.executor import LOCAL, Executor, resolve, shipped
from vinadv.grid.generator import MIN_SIZE, check_limits, default_obstacle_params, generate_maps
from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import DEFAULT_MOVES, check_moves
from vinadv.identify import (
    PLANNER_SPEC,
    ClassifierRef,
    Identification,
    identify,
    load_classifier,
    objective_strength,
)
from vinadv.jobs.attack import attack_maps
from vinadv.planners.interface import EMPTY_SHA256, Planner
from vinadv.planners.registry import DEFAULT_PLANNER, PlannerRef, load_planner_for, same_choice
from vinadv.planners.spec import PlannerSpec
from vinadv.planners.weights import weights_checksum
from vinadv.records import RUN, VERSION_KEY, run_config_kind, stamp
from vinadv.seeds import check_seed
from vinadv.vocabulary import ADD, LABEL_STRENGTH, success_count

STAGES = ("generate", "attack", "identify", "store")


@dataclass(frozen=True)
class RunConfig:
    """Everything that determines a run's pairs (stored with the run)."""

    n: int = 5000
    size: int = 28
    attack: str = "near-path"
    seed: int = 0
    per_map: int = 1
    budget: int = 8
    radius: int = 2
    corner_cutting: bool = True
    shard_size: int = 1000
    classifier: str | None = None
    planner: str = DEFAULT_PLANNER
    weights: str | None = None
    harm_tolerance: float = DEFAULT_TOL
    harm_rtol: float = 0.0
    objective: str = "paper"
    obstacles: int = 1
    moves: str = DEFAULT_MOVES
    #: a maps file (absolute path) to attack instead of generated maps, and its SHA-256 (`maps_file_config`)
    maps: str | None = None
    maps_sha256: str | None = None
    edit: str = ADD

    def __post_init__(self):
        # every setting is checked here, before `run_pipeline` opens the database: a value refused only when the
        # first shard uses it would leave a run row without pairs behind (and its name taken). The attack settings
        # too, whether this strategy uses them or not: they are stored with the run.
        least = {"n": 1, "shard_size": 1, "obstacles": 1, "size": MIN_SIZE, "per_map": 0, "budget": 1, "radius": 0}
        for name, bound in least.items():
            if getattr(self, name) < bound:
                raise InputError(f"{name} must be >= {bound}, got {getattr(self, name)}", name)
        check_seed(self.seed)
        make_attack(self.attack, self.per_map, self.seed, self.budget, self.radius, self.obstacles, self.edit)
        check_limits(min(self.n, self.shard_size), self.size, 1, default_obstacle_params(self.size)[0])
        check_tolerances(self.harm_tolerance, self.harm_rtol)
        objective_strength(self.objective)  # InputError for an unknown objective
        check_moves(self.moves, self.corner_cutting)
        if (self.maps is None) != (self.maps_sha256 is None):
            raise InputError("maps and maps_sha256 go together (maps_file_config gives both)", "maps")

    @property
    def n_shards(self) -> int:
        return -(-self.n // self.shard_size)

    @property
    def slots(self) -> int:
        """Pair-index slots per map."""
        return self.per_map if self.per_map > 0 else self.size * self.size

    def to_dict(self) -> dict:
        """Every setting of the config, by name (stored with the run, with its planner's spec and the record version:
        `vinadv.records.RUN`); `RunConfig(**config.to_dict())` is the same config."""
        return asdict(self)


def maps_file_config(path: str, n: int | None = None) -> dict:
    """`RunConfig`'s settings for attacking the maps file `path` (first start of each map) instead of generated maps:
    `n` (its first `n` maps; None: all), `size` and `corner_cutting` from the file, `maps` (absolute path) and
    `maps_sha256`, and its movement model `moves`. The file is read and checked here (InputError naming it and the
    field), before anything is written."""
    maps = MapSet.load(path)
    if n is None:
        n = len(maps)
    if n < 1:
        raise InputError(f"n must be >= 1, got {n}", "n")
    if n > len(maps):
        raise InputError(f"n {n}: the maps file {path} holds {len(maps)} maps", "n")
    return {
        "n": int(n),
        "size": maps.size,
        "corner_cutting": bool(maps.corner_cutting),
        "moves": maps.moves,
        "maps": str(Path(path).resolve()),
        "maps_sha256": weights_checksum(path),
    }


@functools.lru_cache(maxsize=2)
def _maps_file(path: str, sha256: str) -> MapSet:
    """The maps file of a run, read once per process; InputError if its SHA-256 is not the run's."""
    if weights_checksum(path) != sha256:
        raise InputError(
            f"maps file {path}: its SHA-256 is not the one the run recorded ({sha256}); the same file is "
            "needed (on every worker)"
        )
    return MapSet.load(path)


def shard_maps(config: RunConfig, shard: int) -> MapSet:
    """Shard `shard`'s maps, one start each: generated from the seed `(seed, shard)`, or the maps file's maps
    `shard * shard_size ..` (their first start)."""
    first_map = shard * config.shard_size
    n_maps = min(config.shard_size, config.n - first_map)
    if config.maps is None:
        return generate_maps(
            n_maps,
            config.size,
            seed=(config.seed, shard),
            n_starts=1,
            corner_cutting=config.corner_cutting,
            moves=config.moves,
        )
    maps = _maps_file(config.maps, config.maps_sha256).take(slice(first_map, first_map + n_maps))
    return MapSet(
        obstacles=maps.obstacles,
        goals=maps.goals,
        starts=maps.starts[:, :1],
        expert_costs=maps.expert_costs[:, :1],
        expert=maps.expert.take(np.arange(len(maps)) * maps.n_starts),
        corner_cutting=maps.corner_cutting,
        seed=maps.seed,
        moves=maps.moves,
    )


@dataclass
class ShardResult:
    """One shard's identified pairs and what making them cost."""

    shard: int
    identification: Identification
    pair_index: np.ndarray
    n_maps: int
    no_valid_cell: int
    planner_calls: int
    seconds: dict = field(default_factory=dict)


def compute_shard(
    config: RunConfig, shard: int, planner: Planner, classifier=None, label_source: str = "rule"
) -> ShardResult:
    """Generate, attack and identify shard `shard` of the run: deterministic for `(config, shard)`."""
    first_map = shard * config.shard_size
    seconds = {}
    t0 = time.perf_counter()
    maps = shard_maps(config, shard)
    n_maps = len(maps)
    t1 = time.perf_counter()
    result = attack_maps(
        config.attack,
        {
            "per_map": config.per_map,
            "seed": (config.seed, shard),
            "budget": config.budget,
            "radius": config.radius,
            "obstacles": config.obstacles,
            "edit": config.edit,
        },
        maps.obstacles,
        maps.starts[:, 0],
        maps.goals,
        planner,
        config.corner_cutting,
        objective=config.objective,
    )
    t2 = time.perf_counter()
    # the generator's expert paths of the original maps: harm then searches only adversarial maps (and few of them)
    pairs = result.pairs
    expert_o = (maps.expert_costs[pairs.map_index, 0], maps.expert.take(pairs.map_index * maps.n_starts))
    ident = identify(
        pairs, classifier, label_source, harm_tol=config.harm_tolerance, harm_rtol=config.harm_rtol, expert_o=expert_o
    )
    t3 = time.perf_counter()
    seconds.update(generate=t1 - t0, attack=t2 - t1, identify=t3 - t2)
    global_map = first_map + pairs.map_index
    if config.per_map > 0:
        first_of_map = np.searchsorted(pairs.map_index, pairs.map_index, side="left")
        slot = np.arange(len(pairs)) - first_of_map
    else:  # one pair per valid cell of the last step: that cell is the slot
        slot = pairs.added[:, -1, 0] * config.size + pairs.added[:, -1, 1]
    return ShardResult(
        shard, ident, global_map * config.slots + slot, n_maps, len(result.no_valid_cell), result.planner_calls, seconds
    )


def shard_records(result: ShardResult):
    """The store's `PairRecords` of one shard."""
    return result.identification.records(pair_index=result.pair_index)


@dataclass
class RunSummary:
    """What a run made: counts per category, success rate, time per stage. After a resume (`whole_run`) the counts
    are the whole run's, the shards skipped included; `stored`, the time per stage and `pairs_per_second` are this
    time's, and the planner calls, not recorded per shard, are known only when no shard was skipped (else None)."""

    run_id: int
    name: str | None
    db: str
    planner: PlannerSpec
    n_maps: int = 0
    n_pairs: int = 0
    stored: int = 0
    skipped_shards: int = 0
    no_valid_cell: int = 0
    planner_calls: int | None = 0
    #: pairs computed this time (`n_pairs` before `whole_run`)
    computed: int = 0
    counts: dict = field(default_factory=lambda: {label: 0 for label in LABEL_STRENGTH})
    harm_table: dict = field(default_factory=lambda: cross_table([], []))
    seconds: dict = field(default_factory=lambda: {stage: 0.0 for stage in STAGES})
    wall_seconds: float = 0.0

    def add(self, result: ShardResult, stored: int, store_seconds: float) -> None:
        self.n_maps += result.n_maps
        self.n_pairs += len(result.identification)
        self.computed += len(result.identification)
        self.stored += stored
        self.no_valid_cell += result.no_valid_cell
        self.planner_calls += result.planner_calls
        for label, count in result.identification.counts().items():
            self.counts[label] += count
        for label, row in result.identification.harm_table().items():
            for value, count in row.items():
                self.harm_table[label][value] += count
        for stage, sec in result.seconds.items():
            self.seconds[stage] += sec
        self.seconds["store"] += store_seconds

    def to_dict(self) -> dict:
        valid = self.n_pairs - self.counts["invalid"]
        success = success_count(self.counts)
        return {
            "run_id": self.run_id,
            "name": self.name,
            "db": self.db,
            "planner": self.planner,
            "maps": self.n_maps,
            "pairs": self.n_pairs,
            "stored": self.stored,
            "skipped_shards": self.skipped_shards,
            "maps_without_valid_cell": self.no_valid_cell,
            "counts": dict(self.counts),
            "valid_pairs": valid,
            "successful": success,
            "success_rate": success / valid if valid else None,
            **harm_summary(self.harm_table),
            "planner_calls": self.planner_calls,
            "planner_calls_per_success": self.planner_calls / success
            if success and self.planner_calls is not None
            else None,
            "seconds": {k: round(v, 3) for k, v in self.seconds.items()},
            "wall_seconds": round(self.wall_seconds, 3),
            "pairs_per_second": self.computed / self.wall_seconds if self.wall_seconds else None,
        }

    def whole_run(self, store, config: RunConfig) -> None:
        """Make the summary of a resumed run, once every shard is stored, the whole run's: its maps, its pairs per
        label and harm as stored (the shards skipped this time included), the maps without a pair (no valid cell);
        the planner calls become None when shards were skipped (their calls were not recorded)."""
        stored = store.label_counts(self.run_id)
        self.counts = {label: stored.get(label, 0) for label in LABEL_STRENGTH}
        self.n_pairs = sum(self.counts.values())
        self.harm_table = cross_table([], [])
        for label, row in store.harm_counts(self.run_id).items():
            for value, count in row.items():
                if value in self.harm_table.get(label, {}):
                    self.harm_table[label][value] += count
        self.n_maps = config.n
        maps_with_pairs = len(np.unique(store.stored_indices(self.run_id) // config.slots))
        self.no_valid_cell = config.n - maps_with_pairs
        if self.skipped_shards:
            self.planner_calls = None


def resolve_planner(config: RunConfig, device: str | None = None) -> Planner:
    """The planner of a run (`config.planner` with `config.weights`, for the run's map size, move rule and movement
    model: a planner of another model is refused, see `Planner.for_moves`), its forward on `device`
    (`load_planner`; None: the planner's default)."""
    return load_planner_for(config.planner, config.weights, config, device)


def open_run(store, config: RunConfig, name: str | None, resume: bool, planner: Planner, classifier_name: str):
    """The run to write into: a new one, or with `resume` the latest run called `name` (the same config and the same
    planner, weights checksum included, only). A new run records `planner.spec()` in its config and the weights
    checksum in `runs.weights_checksum`."""
    if resume:
        run_id, info = _run_to_resume(store, name)
        stored_config = stored_settings(info)
        given = config.to_dict()
        # one planner however named: an old spelling (vin_robust), or a family with its planner's weights
        if same_choice((stored_config["planner"], stored_config["weights"]), (config.planner, config.weights)):
            stored_config = {**stored_config, "planner": given["planner"], "weights": given["weights"]}
        if stored_config != given:
            diff = sorted(k for k in given if stored_config.get(k) != given[k])
            raise InputError(
                f"resume: run '{name}' was made with other settings ({', '.join(diff)}); "
                "use the same options or another name",
                "resume",
                "name",
            )
        _check_same_planner(name, info, planner)
        store.set_run_status(run_id, "running")  # again, after "interrupted" or "failed"
        return run_id
    return store.create_run(
        name,
        config=stamp(RUN, {**config.to_dict(), PLANNER_SPEC: planner.spec()}),
        seed=config.seed,
        weights_checksum=planner.checksum,
        attack=config.attack,
        classifier=classifier_name,
        version=__version__,
        moves=config.moves,
    )


def _run_to_resume(store, name: str | None) -> tuple[int, dict]:
    """The id and row (`Store.run_info`) of the latest run called `name`, to resume; InputError when there is none
    or it was not made by `vinadv run`."""
    if not name:
        raise InputError("resume needs name (the run to resume)", "resume", "name")
    run_id = store.find_run(name)
    if run_id is None:
        raise InputError(f"resume: no run named '{name}' in {store.url}", "resume")
    info = store.run_info(run_id)  # the config upgraded to today's form (`vinadv.records`)
    if run_config_kind(info["config"]) != RUN:
        raise InputError(f"resume: run '{name}' was not made by `vinadv run`; use another name", "resume", "name")
    return run_id, info


def stored_settings(info: dict) -> dict:
    """The `RunConfig` settings a run was made with, from its row (`Store.run_info`: the config in today's form)."""
    return {k: v for k, v in info["config"].items() if k not in (PLANNER_SPEC, VERSION_KEY)}


def resumed_config(db: str | None, name: str, **given) -> RunConfig:
    """The config to resume the run `name` in `db` with (`run(..., resume=True)`): the settings it was made with,
    read from the database, and the settings `given` (the options a user gave); `run` refuses a given setting that
    differs from the stored one, naming it. InputError as `run` for a name that is no `vinadv run` run there."""
    from vinadv.store import Store  # noqa: PLC0415 (SQLAlchemy: computing a shard needs no store)

    with Store.open(db) as store:
        _, info = _run_to_resume(store, name)
    return RunConfig(**{**stored_settings(info), **given})


def _check_same_planner(name: str, info: dict, planner: Planner) -> None:
    """Refuse (InputError) to resume the run `name` (its row `info`) with another planner than it was made with:
    other weights (checksum), or a bring-your-own planner whose source file changed since (its recorded SHA-256)."""
    stored_checksum = info["weights_checksum"]
    if stored_checksum == EMPTY_SHA256:  # a planner without weights: recorded as None or as the empty SHA-256
        stored_checksum = None
    if stored_checksum != planner.checksum:
        raise InputError(
            f"resume: run '{name}' was made with another {planner.name!r} planner (weights sha256 "
            f"{info['weights_checksum']}, now {planner.checksum}); use the same planner or another name",
            "resume",
            "planner",
        )
    stored_spec = info["config"][PLANNER_SPEC] or {}
    stored_source = (stored_spec.get("config") or {}).get("source_sha256")
    source = planner.config.get("source_sha256")
    if stored_source is not None and stored_source != source:
        raise InputError(
            f"resume: run '{name}' was made with another source of planner {planner.name!r} (source sha256 "
            f"{stored_source}, now {source}); use the same planner file or another name",
            "resume",
            "planner",
        )


def run(
    config: RunConfig,
    executor: Executor = LOCAL,
    *,
    db: str | None = None,
    name: str | None = None,
    resume: bool = False,
    progress: bool = False,
    device: str | None = None,
) -> RunSummary:
    """Run the main job and store it in `db` (as the run `name`; with `resume`, go on with the latest run of that
    name); returns the summary. The shards are computed on `executor` (`vinadv.executor`: in this process by
    default), stored in shard order as they come back. `device`: where the planner's forward runs (`load_planner`),
    not part of the config: a run may be resumed on another device. The run records its type in the planner's spec
    (`PLANNER_SPEC`)."""
    from vinadv.store import Store  # noqa: PLC0415 (SQLAlchemy: computing a shard needs no store)
    from vinadv.store.runs import check_run_name  # noqa: PLC0415 (SQLAlchemy, as above)

    # everything that can be refused is refused before the database is opened (opening may create it)
    if resume and not name:
        raise InputError("resume needs name (the run to resume)", "resume", "name")
    if name is not None:
        check_run_name(name)
    t_start = time.perf_counter()
    planner = resolve_planner(config, device)
    classifier, classifier_name = load_classifier(config.classifier)
    with Store.open(db) as store:
        run_id = open_run(store, config, name, resume, planner, classifier_name)
        summary = RunSummary(run_id, name, store.url, planner.spec())
        shards = range(config.n_shards)  # a range, not a list: a huge --n streams shard by shard
        if resume:
            summary.skipped_shards = _complete_shards(store, run_id, config)
            shards = shards[summary.skipped_shards :]
        task = functools.partial(
            _shard_task,
            config,
            shipped(
                executor, planner, lambda: PlannerRef.of(planner, config.planner, config.weights, config.corner_cutting)
            ),
            shipped(executor, classifier, lambda: ClassifierRef.of(config.classifier)),
            classifier_name,
        )
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=max(0, config.n - summary.skipped_shards * config.shard_size), desc="maps", unit="map")
        done = summary.skipped_shards
        try:
            for result in executor.map(task, shards):
                t0 = time.perf_counter()
                # a remote executor may deliver a shard twice: what is stored is skipped
                written = store.write_pairs(run_id, shard_records(result), skip_stored=resume or executor.remote)
                if result.shard == done:  # shards arrive in order: 0 .. done-1 are all stored
                    done += 1
                    store.set_shards_done(run_id, done)
                summary.add(result, written, time.perf_counter() - t0)
                if bar is not None:
                    bar.update(result.n_maps)
        except OutputError as exc:  # a fault of the database: no status can be recorded there
            raise OutputError(f"{exc}; run {run_id} {_stopped(summary, name)}") from None
        except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM (the command line raises a KeyboardInterrupt for it)
            _record_status(store, run_id, "interrupted")
            raise type(exc)(f"run {run_id} {_stopped(summary, name)}") from None
        except Exception as exc:  # the planner broke its contract, or a bug: the run did not finish
            _record_status(store, run_id, "failed")
            if isinstance(exc, InputError):
                raise type(exc)(f"{exc}; run {run_id} marked failed", *exc.parameters) from None
            raise
        finally:
            if bar is not None:
                bar.close()
        summary.wall_seconds = time.perf_counter() - t_start
        timings = {**summary.to_dict()["seconds"], "wall": summary.wall_seconds}
        if resume:
            summary.whole_run(store, config)
            if done == summary.skipped_shards:  # nothing computed this time (a finished run): its timings stay
                timings = store.run_info(run_id)["timings"] or timings
        store.finish_run(run_id, timings=timings)
    return summary


def _stopped(summary: RunSummary, name: str | None) -> str:
    """What a run stopped part way has stored, and how to go on with it (the end of a one-line message)."""
    how = (
        f"resume it with the same options and --name {name} --resume"
        if name
        else "it has no --name, so it cannot be resumed (give runs a --name)"
    )
    return f"stopped with {summary.stored:,} pairs stored this time: {how}"


def _record_status(store, run_id: int, status: str) -> None:
    """Record the status of a run stopped part way, as far as the database lets: what stopped the run is what the
    user is told, not a second fault of the database on the way out."""
    with contextlib.suppress(Exception):
        store.set_run_status(run_id, status)


def _complete_shards(store, run_id: int, config: RunConfig) -> int:
    """How many shards of the run, from shard 0 on, are completely stored (`--resume` skips them): the count the
    run recorded, or, for a run that recorded none, the shards before the last one holding a pair."""
    recorded = store.shards_done(run_id)
    stored = store.stored_indices(run_id, lo=recorded * config.shard_size * config.slots)
    before_last = int(stored.max()) // (config.shard_size * config.slots) if len(stored) else 0
    return min(config.n_shards, max(recorded, before_last))


def _shard_task(config: RunConfig, planner, classifier, label_source: str, shard: int) -> ShardResult:
    """The task of `run`: shard `shard` (`compute_shard`), with the models (or references to them) given."""
    return compute_shard(config, shard, resolve(planner), resolve(classifier), label_source)


def run_pipeline(
    config: RunConfig,
    db: str | None = None,
    name: str | None = None,
    resume: bool = False,
    progress: bool = True,
    executor: Executor = LOCAL,
    device: str | None = None,
) -> RunSummary:
    """`run` with the settings as positional arguments after `config` (a progress bar by default)."""
    return run(config, executor, db=db, name=name, resume=resume, progress=progress, device=device)
