"""Small valid vinadv files (maps, paths, pairs, weights, classifier model, database) and ways to rewrite them, for
the bad-input tests (tests/grid/test_checks.py, tests/test_fuzz_loaders.py); a small file system for the full-disk
tests (`tmpfs`) and a child process to crash (`killed_at_exit`) for the resume tests."""

from __future__ import annotations

import contextlib
import functools
import io
import sqlite3
import subprocess
import zipfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from vinadv.attacks.strategies import make_attack
from vinadv.classify import SVMImageClassifier, label_batch
from vinadv.grid import generate_maps
from vinadv.planners.pathset import PathSet
from vinadv.planners.vin.engine import plan_maps
from vinadv.planners.vin.weights import save_vin
from vinadv.store import Store
from vinadv.testing.classify import synthetic_pairs
from vinadv.testing.planners import planning_vin
from vinadv.testing.store import random_records

SIZE = 10


@functools.cache
def _maps(n_starts: int):
    return generate_maps(12, SIZE, seed=3, n_starts=n_starts)


@functools.cache
def _model():
    return planning_vin(SIZE, seed=1, noise=0.1)


def write_maps(path: Path) -> Path:
    _maps(3).save(path)
    return path


def write_paths(path: Path) -> Path:
    maps = _maps(3)
    result = plan_maps(maps.obstacles, maps.goals, maps.starts, _model(), maps.corner_cutting)
    PathSet.from_result(result, maps.n_starts, maps.size, maps.corner_cutting, model="test").save(path)
    return path


def write_pairs(path: Path) -> Path:
    maps = _maps(1)
    result = make_attack("random", per_map=2, seed=0).attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, _model(), maps.corner_cutting
    )
    result.pairs.save(path)
    return path


def write_weights(path: Path) -> Path:
    save_vin(_model(), path)
    return path


def write_classifier(path: Path) -> Path:
    batch = synthetic_pairs(60, size=8, seed=2, mix=True)
    labels = label_batch(batch).labels
    keep = np.flatnonzero(np.isin(labels, ("DP", "FP")))
    SVMImageClassifier().fit(batch.take(keep), labels[keep]).save(path)
    return path


def write_database(path: Path) -> Path:
    with Store.open(str(path)) as store:
        store.write_pairs(store.create_run("fuzz"), random_records(6, size=5, seed=1))
    conn = sqlite3.connect(path)  # one self-contained file (no -wal) so byte mutations reach every page
    conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    conn.execute("PRAGMA journal_mode=DELETE")
    conn.close()
    return path


def read_npz(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as data:
        return {k: data[k] for k in data.files}


def rewrite_npz(src: Path, dst: Path, **changes) -> Path:
    """`src`'s arrays with `changes` (name=array, or name=None to drop it) written to `dst`."""
    arrays = read_npz(src)
    for name, value in changes.items():
        if value is None:
            arrays.pop(name, None)
        else:
            arrays[name] = np.asarray(value)
    with open(dst, "wb") as fh:
        np.savez(fh, **arrays)
    return dst


def forge_npy_header(src: Path, dst: Path, name: str, shape: tuple[int, ...], dtype: str | None = None) -> Path:
    """`src` (an `.npz`) written to `dst` with array `name`'s `.npy` header claiming `shape` (and `dtype`), its data
    bytes unchanged: a forged header, as a hostile file would carry."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for info in zin.infolist():
            data = zin.read(info)
            if info.filename == f"{name}.npy":
                fh = io.BytesIO(data)
                np.lib.format.read_magic(fh)
                _, fortran, found = np.lib.format.read_array_header_1_0(fh)
                header = io.BytesIO()
                descr = np.lib.format.dtype_to_descr(np.dtype(dtype or found))
                np.lib.format.write_array_header_1_0(
                    header, {"shape": tuple(shape), "fortran_order": fortran, "descr": descr}
                )
                data = header.getvalue() + data[fh.tell() :]
            zout.writestr(info.filename, data)
    return dst


@contextlib.contextmanager
def tmpfs(path: Path, size: str = "4M", options: str = ""):
    """A small tmpfs mounted at `path` (`options` like ",ro"): a full or read-only file system for a test. Root
    only; the test is skipped where mounting is not allowed."""
    path.mkdir(parents=True, exist_ok=True)
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size}{options}", "tmpfs", str(path)], check=False, capture_output=True
    )
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=False)


@contextlib.contextmanager
def killed_at_exit(argv: list[str], **popen) -> Iterator[subprocess.Popen]:
    """`argv` started as a child process (`popen`: more of `subprocess.Popen`'s arguments), then killed with SIGKILL
    when the block ends, however it ends, and reaped: a crash, in which none of the child's own cleanup runs. The
    block waits for the moment to crash it and asserts that the child is still running then."""
    child = subprocess.Popen(argv, **popen)
    try:
        yield child
    finally:
        child.kill()  # SIGKILL on POSIX
        child.wait()
