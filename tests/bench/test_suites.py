"""The suites: a released suite never changes (its checksum is frozen), its maps are the generator's (sha256
checked), an unknown suite is one line, and the registry refuses a name twice."""

from __future__ import annotations

import dataclasses

import pytest

from vinadv.bench.scoring import suite_maps
from vinadv.bench.suites import FROZEN, SUITES, AttackGroup, Suite, get_suite, maps_sha256, register
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.robustness import heldout_maps


def test_released_suites_never_change():
    assert {name: s.checksum for name, s in SUITES.items() if name in FROZEN} == FROZEN
    assert set(FROZEN) <= set(SUITES)


def test_the_checksum_covers_every_field():
    suite = get_suite("vin28-quick-v1")
    for change in ({"n": 99}, {"seed": 1}, {"attacks": (AttackGroup(("random",), "add", 3),)}, {"chunk": 10}):
        assert dataclasses.replace(suite, **change).checksum != suite.checksum


@pytest.mark.slow
def test_the_quick_suites_maps_are_the_frozen_ones():
    suite = get_suite("vin28-quick-v1")
    maps = suite_maps(suite)  # refused if the generator made other maps
    assert len(maps) == 100 and maps.size == 28
    # the digest, by hand: obstacle bytes, then int64 starts and goals
    first = heldout_maps(100, 28, seed=1000)
    assert maps_sha256(first.obstacles, first.starts[:, 0], first.goals) == suite.maps_sha256
    other = dataclasses.replace(suite, maps_sha256="0" * 64)
    with pytest.raises(InputError, match="generator makes other maps"):
        suite_maps(other)


def test_unknown_suite_is_one_line(capsys):
    assert main(["bench", "run", "--suite", "vin28-v9", "--planner", "optimal"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "unknown --suite 'vin28-v9'" in err and "vin28-quick-v1" in err


def test_registry_refuses_a_name_twice():
    with pytest.raises(InputError, match="already registered"):
        register(get_suite("vin28-v1"))
    assert isinstance(SUITES["vin28-v1"], Suite)


def test_the_command_help_names_every_registered_suite(capsys):
    with pytest.raises(SystemExit):
        main(["bench", "run", "--help"])
    text = " ".join(capsys.readouterr().out.split())  # argparse wraps the help
    for name in SUITES:
        assert name in text
