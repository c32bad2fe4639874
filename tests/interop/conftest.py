"""Shared helpers for the interop tests: the real avivt files, and small maps of our own."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.needs import public_data
from vinadv.grid import generate_maps


def real_file(name: str) -> Path:
    """The real avivt file `name` (`../shared/data/avivt/<name>`); `skip_or_fail` without it."""
    return public_data(f"avivt/{name}")


def mpd_file(family: str) -> Path:
    """The MP dataset file of `family` (`../shared/data/mpd/<family>_032_moore_c8.npz`); `skip_or_fail` without
    it."""
    return public_data(f"mpd/{family}_032_moore_c8.npz")


@pytest.fixture(scope="module")
def small_maps():
    return generate_maps(12, 10, seed=5, n_starts=3)


def borderless(maps, seed: int = 0):
    """`maps` with a random border: about 60% of the edge cells free (goals and starts stay free)."""
    rng = np.random.default_rng(seed)
    obstacles = maps.obstacles.copy()
    edge = np.zeros(obstacles.shape[1:], dtype=bool)
    edge[0, :] = edge[-1, :] = edge[:, 0] = edge[:, -1] = True
    obstacles[:, edge] = rng.random((len(obstacles), int(edge.sum()))) < 0.4
    return obstacles
