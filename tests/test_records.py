"""The records stored as JSON (`vinadv.records`): every old form written as a literal (the oracle) reads as today's;
today's writers write every field and the version, and what they write reads back unchanged; upgrading is idempotent
and leaves the stored record as it was."""

from __future__ import annotations

import copy
import dataclasses
import inspect
import json

import pytest
import sqlalchemy as sa
from hypothesis import given, settings
from hypothesis import strategies as st

from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.identify import identify_pairs
from vinadv.pipeline import RunConfig, run
from vinadv.planners.weights import trained_moves
from vinadv.records import (
    BENCH_CHUNK,
    IDENTIFY,
    RECORD_VERSIONS,
    ROBUSTNESS,
    ROBUSTNESS_SETTINGS,
    RUN,
    STEPS,
    TRAINING,
    VERSION_KEY,
    run_config_kind,
    stamp,
    upgrade,
    upgrade_run_config,
)
from vinadv.robustness import robustness, save_robustness
from vinadv.store import Store

#: the first form of a `vinadv run` config (version 0): the settings of the first release, no planner
RUN_V0_FIRST = {
    "n": 300,
    "size": 11,
    "attack": "near-path",
    "seed": 7,
    "per_map": 1,
    "budget": 8,
    "radius": 2,
    "corner_cutting": True,
    "shard_size": 100,
    "classifier": None,
    "weights": None,
}
#: the last form of version 0 for an octile run of generated maps that adds obstacles: `moves`, `maps`,
#: `maps_sha256` and `edit` left out
RUN_V0_DEFAULTS_LEFT_OUT = {
    "n": 30,
    "size": 9,
    "attack": "key-points",
    "seed": 4,
    "per_map": 2,
    "budget": 8,
    "radius": 2,
    "corner_cutting": True,
    "shard_size": 25,
    "classifier": None,
    "planner": "gppn",
    "weights": "g.pt",
    "harm_tolerance": 1e-6,
    "harm_rtol": 0.0,
    "objective": "harm",
    "obstacles": 2,
    "planner_spec": {"name": "gppn", "size": 9, "config": {"k": 6}, "weights_sha256": "ab" * 32},
}
#: version 0 of a run with none of its fields at a default: every field written, no version
RUN_V0_EVERY_FIELD = {
    **RUN_V0_DEFAULTS_LEFT_OUT,
    "moves": "moore",
    "maps": "/data/m.npz",
    "maps_sha256": "cd" * 32,
    "edit": "remove",
}


def run_defaults(config: dict) -> dict:
    """Today's `RunConfig` defaults of the fields `config` leaves out, and no planner spec: what a version 0 run config
    meant by leaving a field out, as it wrote only the settings of its day and those away from their default (a
    default changed since would need a new record version, which this test would then ask for)."""
    fields = {f.name: f.default for f in dataclasses.fields(RunConfig) if f.name not in config}
    return {**fields, "planner_spec": None}


#: the first form of a `vinadv identify` config, and one of a removal attack's pairs file (its params say `edit`)
IDENTIFY_V0_FIRST = {"pairs": "/p/pairs.npz", "strategy": "random", "params": {"per_map": 1}, "classifier": None}
IDENTIFY_V0_REMOVE = {
    "pairs": "/p/pairs.npz",
    "strategy": "near-path",
    "params": {"per_map": 1, "seed": 3, "obstacles": 1, "edit": "remove"},
    "classifier": "rule",
    "planner": "optimal",
    "weights": None,
    "planner_spec": {"name": "optimal", "size": 9, "config": {}, "weights_sha256": None},
    "attack_planner": None,
    "harm_tolerance": 0.5,
    "harm_rtol": 0.1,
}

ROBUSTNESS_SETTINGS_V0 = {
    "n": 10,
    "size": 9,
    "maps_seed": 1000,
    "corner_cutting": True,
    "strategies": ["random", "saliency"],
    "max_obstacles": 2,
    "objective": "harm",
    "seed": 1000,
    "budget": 8,
    "radius": 2,
    "harm_tolerance": 1e-6,
    "harm_rtol": 0.0,
}
ROBUSTNESS_V0 = {
    "planner": {"name": "vin", "size": 9, "config": {}, "weights_sha256": None},
    "settings": ROBUSTNESS_SETTINGS_V0,
    "clean": {"maps": 10, "reached": 9, "success_rate": 0.9, "mean_regret": 0.0},
    "strategies": {
        "random": {"name": "random", "seconds": 0.1, "planner_calls": 3, "by_obstacles": []},
        "saliency": {
            "name": "saliency",
            "seconds": 0.2,
            "planner_calls": 4,
            "ranked_as": "key-points",
            "by_obstacles": [],
        },
    },
    "overall": [],
    "seconds": 0.4,
}

TRAINING_V0 = {
    "format": "vinadv.train/1",
    "planner": "vin",
    "command": "vinadv vin train --maps m.npz",
    "data": {"path": "m.npz", "sha256": "ef" * 32, "maps": 10, "size": 9, "seed": 0, "corner_cutting": True},
}


def test_every_kind_has_a_step_from_each_older_version():
    assert {(kind, v) for kind, last in RECORD_VERSIONS.items() for v in range(last)} == set(STEPS)


@pytest.mark.parametrize(
    ("stored", "expected"),
    [
        (RUN_V0_FIRST, {**run_defaults(RUN_V0_FIRST), **RUN_V0_FIRST, VERSION_KEY: 1}),
        (
            RUN_V0_DEFAULTS_LEFT_OUT,
            {**RUN_V0_DEFAULTS_LEFT_OUT, "moves": "octile", "maps": None, "maps_sha256": None, "edit": "add"}
            | {VERSION_KEY: 1},
        ),
        (RUN_V0_EVERY_FIELD, {**RUN_V0_EVERY_FIELD, VERSION_KEY: 1}),
    ],
)
def test_a_run_config_of_version_0_reads_with_every_field(stored, expected):
    kept = copy.deepcopy(stored)
    assert run_config_kind(stored) == RUN
    assert upgrade_run_config(stored) == expected
    assert stored == kept  # the stored record itself is left as it was
    # today's writer writes the same fields: a version 1 config is a RunConfig's fields, its spec and the version
    assert set(expected) == {f.name for f in dataclasses.fields(RunConfig)} | {"planner_spec", VERSION_KEY}


def test_an_identify_config_of_version_0_reads_with_every_field_and_its_edit():
    # no planner recorded; the tolerances `identify_pairs`'s defaults (version 0 wrote none); an addition attack
    tol = {key: inspect.signature(identify_pairs).parameters[key].default for key in ("harm_tol", "harm_rtol")}
    filled = dict.fromkeys(("planner", "weights", "planner_spec", "attack_planner"))
    filled |= {"harm_tolerance": tol["harm_tol"], "harm_rtol": tol["harm_rtol"], "edit": "add"}
    assert run_config_kind(IDENTIFY_V0_FIRST) == IDENTIFY
    assert upgrade_run_config(IDENTIFY_V0_FIRST) == {**filled, **IDENTIFY_V0_FIRST, VERSION_KEY: 1}
    assert upgrade_run_config(IDENTIFY_V0_REMOVE) == {**IDENTIFY_V0_REMOVE, "edit": "remove", VERSION_KEY: 1}


@pytest.mark.parametrize("config", [None, {}, {"n": 300, "size": 11}, [1, 2]])
def test_a_config_no_job_wrote_reads_as_stored(config):
    assert run_config_kind(config) is None and upgrade_run_config(config) is config


def test_robustness_records_of_version_0_read_with_every_field():
    settings = {
        **ROBUSTNESS_SETTINGS_V0,
        "moves": "octile",
        "maps": None,
        "maps_sha256": None,
        "edit": "add",
        "planner": None,  # version 2's provenance and effort test: none recorded before
        "name": None,
        "effort_tolerance": None,
        VERSION_KEY: 2,
    }
    assert upgrade(ROBUSTNESS_SETTINGS, ROBUSTNESS_SETTINGS_V0) == settings
    strategies = copy.deepcopy(ROBUSTNESS_V0["strategies"])
    strategies["random"]["ranked_as"] = None
    assert upgrade(ROBUSTNESS, ROBUSTNESS_V0) == {
        **ROBUSTNESS_V0,
        "settings": settings,
        "strategies": strategies,
        VERSION_KEY: 2,
    }


def test_a_training_record_of_version_0_reads_with_its_maps_movement_model():
    upgraded = upgrade(TRAINING, TRAINING_V0)
    assert upgraded == {**TRAINING_V0, "data": {**TRAINING_V0["data"], "moves": "octile"}, VERSION_KEY: 1}
    assert upgrade(TRAINING, {}) == {VERSION_KEY: 1}  # weights from elsewhere: a record that names no maps
    moore = {**TRAINING_V0, "data": {**TRAINING_V0["data"], "moves": "moore"}}
    assert trained_moves("w.pt", moore) == "moore" and trained_moves("w.pt", TRAINING_V0) == "octile"


def test_a_bench_chunk_of_version_0_gains_its_version_only():
    chunk = {"first_map": 0, "maps": 2, "clean": {"reached": [True, False]}, "attacks": {}, "seconds": 0.1}
    assert upgrade(BENCH_CHUNK, chunk) == {**chunk, VERSION_KEY: 1}


@pytest.mark.parametrize(
    ("record", "message"),
    [
        ({VERSION_KEY: 2}, r"version 2 is newer than this vinadv reads \(1\)"),
        ({VERSION_KEY: "1"}, "is not a version"),
        ({VERSION_KEY: -1}, "is not a version"),
        ({VERSION_KEY: True}, "is not a version"),
        ([], "expected a JSON object"),
    ],
)
def test_a_record_of_no_version_this_vinadv_reads_is_refused_in_one_line(record, message):
    with pytest.raises(InputError, match=message):
        upgrade(RUN, record)
    with pytest.raises(InputError, match="not one of"):
        upgrade("runs", {})


#: version 0 run configs: any subset of the version 1 fields (the writers left fields out), with some values
V0_RUN_CONFIGS = st.fixed_dictionaries(
    {"n": st.integers(1, 10**6), "attack": st.sampled_from(["random", "near-path"]), "shard_size": st.integers(1, 99)},
    optional={
        **{k: st.just(v) for k, v in RUN_V0_EVERY_FIELD.items() if k not in ("n", "attack", "shard_size")},
        "planner": st.sampled_from(["vin", "optimal", "vin_robust"]),
        "moves": st.sampled_from(["octile", "moore", "news"]),
        "edit": st.sampled_from(["add", "remove"]),
    },
)


@settings(derandomize=True, max_examples=60, deadline=None)
@given(config=V0_RUN_CONFIGS, kind=st.sampled_from([RUN, IDENTIFY, ROBUSTNESS_SETTINGS, TRAINING, BENCH_CHUNK]))
def test_upgrading_is_idempotent_and_keeps_what_was_stored(config, kind):
    kept = copy.deepcopy(config)
    once = upgrade(kind, config)
    assert upgrade(kind, once) == once and config == kept
    assert once[VERSION_KEY] == RECORD_VERSIONS[kind]
    assert {k: once[k] for k in config} == config  # a step fills what was left out, never changes what was stored
    assert stamp(kind, once) == once


def raw_json(url: str, column: str, table: str, row_id: int) -> dict:
    """The JSON as stored in the database, read without vinadv's store."""
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.connect() as conn:
        text = conn.execute(sa.text(f"SELECT {column} FROM {table} WHERE id = :i"), {"i": row_id}).scalar_one()
    engine.dispose()
    return json.loads(text)


def test_a_run_stores_every_field_of_its_config_and_reads_it_back_unchanged(sqlite_url):
    config = RunConfig(n=2, size=8, attack="random", planner="optimal", shard_size=2)
    summary = run(config, db=sqlite_url)
    stored = raw_json(sqlite_url, "config", "runs", summary.run_id)
    assert stored == {**dataclasses.asdict(config), "planner_spec": stored["planner_spec"], VERSION_KEY: 1}
    with Store.open(sqlite_url) as store:
        assert store.run_info(summary.run_id)["config"] == stored


def test_a_robustness_benchmark_stores_every_setting_and_reads_back_unchanged(sqlite_url):
    from vinadv.planners.registry import load_planner  # noqa: PLC0415 (the planner registry)

    maps = generate_maps(3, 8, seed=5, n_starts=1)
    result = robustness(load_planner("optimal", 8), maps, ["random"], 1, seed=1)
    provenance = ("moves", "maps", "maps_sha256", "edit", "planner", "name", "effort_tolerance")
    assert set(result.settings) == {*ROBUSTNESS_SETTINGS_V0, *provenance, VERSION_KEY}
    assert result.to_dict()[VERSION_KEY] == 2 and result.to_dict()["strategies"]["random"]["ranked_as"] is None
    row_id = save_robustness(result, sqlite_url)
    assert raw_json(sqlite_url, "settings", "robustness", row_id) == result.settings
    with Store.open(sqlite_url) as store:
        (row,) = store.read_robustness([row_id])
    assert row["settings"] == result.settings and row["result"] == json.loads(json.dumps(result.to_dict()))
