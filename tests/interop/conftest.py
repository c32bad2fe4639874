"""Shared helpers for the interop tests: the real avivt files, and small maps of our own."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vinadv.grid import generate_maps


def shared_data(name: str, folder: str = "avivt") -> Path | None:
    """`../shared/data/<folder>/<name>` relative to the repository root (CI), else /work/shared; None if absent."""
    for base in (Path(__file__).resolve().parents[2] / ".." / "shared", Path("/work/shared")):
        path = base / "data" / folder / name
        if path.exists():
            return path
    return None


def real_file(name: str) -> Path:
    path = shared_data(name)
    if path is None:
        pytest.skip(f"the real avivt file {name} is not present (../shared/data/avivt/)")
    return path


def mpd_file(family: str) -> Path:
    """The MP dataset file of `family` (`../shared/data/mpd/<family>_032_moore_c8.npz`); the test is skipped
    without it."""
    path = shared_data(f"{family}_032_moore_c8.npz", "mpd")
    if path is None:
        pytest.skip(f"the MP dataset file of {family} is not present (../shared/data/mpd/)")
    return path


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
