"""The small suites the benchmark tests score: held-out maps, their checksum computed (two 28x28 maps, one random
attack, one chunk per map: `two_map_suite`)."""

from __future__ import annotations

from vinadv.bench import suites
from vinadv.bench.suites import AttackGroup, Suite, maps_sha256
from vinadv.robustness import heldout_maps


def heldout_suite(name: str, n: int, size: int, attacks: tuple, description: str = "a test suite", **fields) -> Suite:
    """A suite named `name` on the first `n` held-out maps of seed 1000 at `size` x `size` (their checksum computed)
    with the groups `attacks`; `fields`: the Suite's other fields."""
    maps = heldout_maps(n, size, seed=1000)
    return Suite(
        name=name,
        description=description,
        n=n,
        size=size,
        maps_seed=1000,
        maps_sha256=maps_sha256(maps.obstacles, maps.starts[:, 0], maps.goals),
        attacks=attacks,
        **fields,
    )


def two_map_suite(name: str) -> Suite:
    """A suite named `name`: the first two held-out maps of seed 1000 at 28x28, adding one obstacle by the random
    strategy (budget 2), one chunk per map."""
    return heldout_suite(name, 2, 28, (AttackGroup(("random",), "add", 1),), budget=2, chunk=1)


def register(monkeypatch, suite: Suite) -> Suite:
    """`suite`, registered for the test only (`monkeypatch`): `bench verify` and `bench run --suite` find it."""
    monkeypatch.setitem(suites.SUITES, suite.name, suite)
    return suite
