"""The records vinadv writes as JSON and reads back, each with a version, and the one place where a record written in
an older form is brought to today's: `upgrade(kind, record)`.

A record carries its version under `VERSION_KEY`; a record without one is version 0, the form written before records
had versions. Writers write every field and the version (`stamp`); readers call `upgrade`, which runs the version steps
in order from the record's version to `RECORD_VERSIONS[kind]`, each step filling what the writers of its version left
out. A step is history: it writes the values as they were meant when that version was written (literal values, not
today's defaults, which may change), and never changes once released. Upgrading a current record returns it unchanged.

The kinds (the readers that call `upgrade` in brackets):
- `RUN`: a `vinadv run` config (`vinadv.pipeline.RunConfig.to_dict` plus the planner's spec), `runs.config`
  (`vinadv.store` when it reads a run).
- `IDENTIFY`: a `vinadv identify` config (`vinadv.identify.identify_and_store`), `runs.config` (as `RUN`).
- `ROBUSTNESS_SETTINGS`: a robustness benchmark's settings (`vinadv.robustness.robustness`), `robustness.settings`
  and inside `ROBUSTNESS` (`vinadv.store` when it reads the table).
- `ROBUSTNESS`: a robustness benchmark's result (`RobustnessResult.to_dict`), `robustness.result` (as above).
- `BENCH_CHUNK`: a finished chunk of a benchmark entry (`vinadv.bench.scoring.compute_chunk`), `bench_chunks.result`
  (`vinadv.store`).
- `TRAINING`: the record of a training, in a weights file and beside it (`vinadv.planners.records.TrainingRecord`;
  `vinadv.planners.weights.trained_moves`).

Records with a format name of their own (the `.npz` files, the benchmark entries, the weights files) keep it: this
module versions the records inside the database and the training record.
"""

from __future__ import annotations

from collections.abc import Callable

from vinadv.errors import InputError

#: the field holding a record's version (absent: version 0)
VERSION_KEY = "record_version"

RUN = "run"
IDENTIFY = "identify"
ROBUSTNESS_SETTINGS = "robustness-settings"
ROBUSTNESS = "robustness"
BENCH_CHUNK = "bench-chunk"
TRAINING = "training"

#: each kind's current version: what its writers write
RECORD_VERSIONS = {RUN: 1, IDENTIFY: 1, ROBUSTNESS_SETTINGS: 2, ROBUSTNESS: 2, BENCH_CHUNK: 1, TRAINING: 1}


def _run_1(config: dict) -> dict:
    """Version 0 -> 1 of a `vinadv run` config. Version 0 left out the settings added to the run after its first
    form, and the fields that held their default: `planner` (no planner setting: the VIN) and its `planner_spec`
    (None: none recorded), `obstacles` (one),
    `objective` (`paper`), `harm_tolerance` and `harm_rtol` (1e-6 and 0), `moves` (`octile`; the run's model is also
    in `runs.moves`), `maps` and `maps_sha256` (generated maps: None), `edit` (`add`). Version 1 writes every field."""
    filled = {
        "planner": "vin",
        "planner_spec": None,
        "obstacles": 1,
        "objective": "paper",
        "harm_tolerance": 1e-6,
        "harm_rtol": 0.0,
        "moves": "octile",
        "maps": None,
        "maps_sha256": None,
        "edit": "add",
    }
    return {**filled, **config}


def _identify_1(config: dict) -> dict:
    """Version 0 -> 1 of a `vinadv identify` config. Version 0 left out the settings added after its first form:
    `planner`, `weights`, `planner_spec` and `attack_planner` (None: none recorded), `harm_tolerance` and `harm_rtol`
    (1e-6 and 0); its pairs' edit was only in the pairs file's `params` (`edit` there for a removal, else none: `add`).
    Version 1 writes every field and the pairs' `edit`."""
    params = config.get("params") if isinstance(config.get("params"), dict) else {}
    filled = {
        "planner": None,
        "weights": None,
        "planner_spec": None,
        "attack_planner": None,
        "harm_tolerance": 1e-6,
        "harm_rtol": 0.0,
        "edit": params.get("edit", "add"),
    }
    return {**filled, **config}


def _robustness_settings_1(settings: dict) -> dict:
    """Version 0 -> 1 of a robustness benchmark's settings. Version 0 left out the fields that held their default:
    `moves` (`octile`), `maps` and `maps_sha256` (generated maps: None), `edit` (`add`)."""
    return {"moves": "octile", "maps": None, "maps_sha256": None, "edit": "add", **settings}


def _robustness_1(result: dict) -> dict:
    """Version 0 -> 1 of a robustness benchmark's result: its `settings` as `ROBUSTNESS_SETTINGS` reads them, and
    each strategy's `ranked_as` (version 0 left it out where the strategy ranked its own way: None)."""
    out = dict(result)
    if isinstance(out.get("settings"), dict):
        out["settings"] = upgrade(ROBUSTNESS_SETTINGS, out["settings"])
    if isinstance(out.get("strategies"), dict):
        out["strategies"] = {
            name: {"ranked_as": None, **s} if isinstance(s, dict) else s for name, s in out["strategies"].items()
        }
    return out


def _robustness_settings_2(settings: dict) -> dict:
    """Version 1 -> 2 of a robustness benchmark's settings: its provenance and the effort test. Version 1 recorded
    neither the planner's full spec (`planner`, `wastar:w=3`: None, the stored row's planner name stands for it) nor a
    run name (`name`: None) nor the effort-harmful tolerance (`effort_tolerance`: None, no effort figures)."""
    return {"planner": None, "name": None, "effort_tolerance": None, **settings}


def _robustness_2(result: dict) -> dict:
    """Version 1 -> 2 of a robustness benchmark's result: its `settings` as `ROBUSTNESS_SETTINGS` reads them (the
    figures gained the effort-harmful count and rate only for planners that report expansions: none before)."""
    out = dict(result)
    if isinstance(out.get("settings"), dict):
        out["settings"] = upgrade(ROBUSTNESS_SETTINGS, out["settings"])
    return out


def _bench_chunk_1(chunk: dict) -> dict:
    """Version 0 -> 1 of a benchmark chunk: the version only (version 0 already wrote every field)."""
    return dict(chunk)


def _training_1(record: dict) -> dict:
    """Version 0 -> 1 of a training record: the maps file it read (`data`) without `moves` was `octile` (records
    written before movement models). A record without `data` (weights trained elsewhere, or by `train_model` itself)
    stays without it."""
    data = record.get("data")
    if isinstance(data, dict) and "moves" not in data:
        return {**record, "data": {**data, "moves": "octile"}}
    return dict(record)


#: (kind, version) -> the step from that version to the next
STEPS: dict[tuple[str, int], Callable[[dict], dict]] = {
    (RUN, 0): _run_1,
    (IDENTIFY, 0): _identify_1,
    (ROBUSTNESS_SETTINGS, 0): _robustness_settings_1,
    (ROBUSTNESS, 0): _robustness_1,
    (ROBUSTNESS_SETTINGS, 1): _robustness_settings_2,
    (ROBUSTNESS, 1): _robustness_2,
    (BENCH_CHUNK, 0): _bench_chunk_1,
    (TRAINING, 0): _training_1,
}


def record_version(kind: str, record: dict) -> int:
    """The version of `record`, a record of `kind`: its `VERSION_KEY` (0 when absent). InputError for an unknown kind,
    a version that is not a whole number >= 0, or one newer than this vinadv reads."""
    if kind not in RECORD_VERSIONS:
        raise InputError(f"record kind {kind!r}: not one of {', '.join(RECORD_VERSIONS)}")
    version = record.get(VERSION_KEY, 0)
    if isinstance(version, bool) or not isinstance(version, int) or version < 0:
        raise InputError(f"{kind} record: {VERSION_KEY} {version!r} is not a version (a whole number >= 0)")
    if version > RECORD_VERSIONS[kind]:
        raise InputError(
            f"{kind} record: version {version} is newer than this vinadv reads ({RECORD_VERSIONS[kind]}); "
            "read it with a newer vinadv"
        )
    return version


def upgrade(kind: str, record: dict) -> dict:
    """`record`, a record of `kind` as stored, in today's form (version `RECORD_VERSIONS[kind]`, every field): the
    version steps from its own version on, in order. A new dict; `record` itself is left as it is. InputError as
    `record_version`, and for a record that is not a dict."""
    if not isinstance(record, dict):
        raise InputError(f"{kind} record: expected a JSON object, got {type(record).__name__}")
    version = record_version(kind, record)
    out = dict(record)
    while version < RECORD_VERSIONS[kind]:
        out = STEPS[kind, version](out)
        version += 1
        out[VERSION_KEY] = version
    return out


def stamp(kind: str, record: dict) -> dict:
    """`record` as a writer of `kind` writes it: with the current version (`VERSION_KEY` last)."""
    if kind not in RECORD_VERSIONS:
        raise InputError(f"record kind {kind!r}: not one of {', '.join(RECORD_VERSIONS)}")
    return {**{k: v for k, v in record.items() if k != VERSION_KEY}, VERSION_KEY: RECORD_VERSIONS[kind]}


def run_config_kind(config) -> str | None:
    """The kind of a run's stored config: `IDENTIFY` (it names its pairs file), `RUN` (it has the run's shards), or
    None for a config no vinadv job wrote (None, or a dict of neither kind), which is read as stored."""
    if not isinstance(config, dict):
        return None
    if "pairs" in config and "strategy" in config:
        return IDENTIFY
    if "shard_size" in config and "attack" in config:
        return RUN
    return None


def upgrade_run_config(config):
    """A run's stored config in today's form (`upgrade` of its `run_config_kind`); a config of no kind as stored."""
    kind = run_config_kind(config)
    return config if kind is None else upgrade(kind, config)


__all__ = [
    "BENCH_CHUNK",
    "IDENTIFY",
    "RECORD_VERSIONS",
    "ROBUSTNESS",
    "ROBUSTNESS_SETTINGS",
    "RUN",
    "STEPS",
    "TRAINING",
    "VERSION_KEY",
    "record_version",
    "run_config_kind",
    "stamp",
    "upgrade",
    "upgrade_run_config",
]
