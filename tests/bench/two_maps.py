"""The small suite the benchmark tests score: two held-out 28x28 maps, one random attack, one chunk per map."""

from __future__ import annotations

from vinadv.bench.suites import AttackGroup, Suite, maps_sha256
from vinadv.robustness import heldout_maps


def two_map_suite(name: str) -> Suite:
    """A suite named `name`: the first two held-out maps of seed 1000 at 28x28, adding one obstacle by the random
    strategy (budget 2), one chunk per map."""
    maps = heldout_maps(2, 28, seed=1000)
    return Suite(
        name=name,
        description="a test suite",
        n=2,
        size=28,
        maps_seed=1000,
        maps_sha256=maps_sha256(maps.obstacles, maps.starts[:, 0], maps.goals),
        attacks=(AttackGroup(("random",), "add", 1),),
        budget=2,
        chunk=1,
    )
