"""The six jobs have one shape (`vinadv.jobs.JOBS`): a frozen dataclass config that refuses a bad value naming the
field and gives `to_dict()` (its fields, which rebuild it), the planner by its spec and weights where the job has
one, one `run(config, executor=LOCAL, *, ...)` and a result with `to_dict()`; each is a command."""

import dataclasses
import importlib
import inspect

import pytest

from vinadv.bench.suites import SUITES
from vinadv.cli import build_parser
from vinadv.errors import InputError
from vinadv.executor import LOCAL
from vinadv.jobs import JOBS

#: per job: the arguments of a valid config, and a field with a value it refuses
CASES = {
    "run": ({}, ("n", 0)),
    "attack": ({"maps": "maps.npz", "strategy": "random"}, ("seed", -1)),
    "identify": ({"pairs": "pairs.npz"}, ("shard_size", 0)),
    "robustness": ({}, ("max_obstacles", 0)),
    "bench run": ({"suite": next(iter(SUITES))}, ("suite", "no-such-suite")),
    "evaluate": ({}, ("setting", "fast")),
}
#: the jobs without a planner of their own (evaluate reads the stored run's)
NO_PLANNER = {"evaluate"}


def job(name: str):
    module, config, result = JOBS[name]
    module = importlib.import_module(module)
    return getattr(module, config), module.run, getattr(module, result)


def test_the_table_names_six_jobs_with_a_case_each():
    assert set(JOBS) == set(CASES) and len(JOBS) == 6


@pytest.mark.parametrize("name", list(CASES))
def test_a_job_has_the_shape(name):
    config_type, run, result_type = job(name)
    valid, (field, bad) = CASES[name]
    assert dataclasses.is_dataclass(config_type) and config_type.__dataclass_params__.frozen
    assert "__post_init__" in vars(config_type)  # it checks itself
    config = config_type(**valid)
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(config, field, bad)
    with pytest.raises(InputError) as refused:
        config_type(**{**valid, field: bad})
    assert field in refused.value.parameters and "\n" not in str(refused.value)
    fields = {f.name for f in dataclasses.fields(config_type)}
    out = config.to_dict()
    assert isinstance(out, dict) and set(out) - {"version"} <= fields  # a record may carry its version
    assert config_type(**{k: v for k, v in out.items() if k in fields}) == config
    if name not in NO_PLANNER:
        assert {"planner", "weights"} <= fields
    parameters = list(inspect.signature(run).parameters.values())
    assert [p.name for p in parameters[:2]] == ["config", "executor"] and parameters[1].default is LOCAL
    assert all(p.kind is p.KEYWORD_ONLY for p in parameters[2:])
    assert inspect.signature(run).return_annotation in (result_type, result_type.__name__)
    assert callable(getattr(result_type, "to_dict", None))


def test_every_job_is_a_command():
    def words(parser, prefix=()):
        for action in parser._actions:
            if action.__class__.__name__ == "_SubParsersAction":
                for name, sub in action.choices.items():
                    yield " ".join((*prefix, name))
                    yield from words(sub, (*prefix, name))

    assert set(JOBS) <= set(words(build_parser()))
