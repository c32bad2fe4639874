"""Where a job's work runs: an executor maps a task function over chunks and knows no job.

Every job (`vinadv.jobs.JOBS`: `vinadv.pipeline.run`, `vinadv.jobs.attack.run`, `vinadv.identify.run`,
`vinadv.robustness.run`, `vinadv.bench.job.run`, `vinadv.evaluation.job.run`) cuts its work in chunks (shards of
maps, slices of pairs, chunks of a suite, or one chunk: the whole job), writes the task that computes one chunk as
a plain function of picklable arguments, and hands both to an executor:

- `LocalExecutor` (`LOCAL`): in this process, one chunk after the other, in order; the planners' own thread pool
  splits each chunk's maps over the cores. It runs what would be cut in pieces for other processes as one chunk
  (`bounds`): planners batch whole arrays best.
- `vinadv.cluster.DaskExecutor`: on the workers of a Dask cluster (only the commands import it). It is `remote`:
  a task's arguments are pickled, and a result may arrive twice (a lost worker's task is run again).

Models (planners, classifiers) are not pickled for a remote executor: a job hands them as `shipped(executor, model,
reference)`, the model itself in this process or a `ByReference` to a small, hashable reference whose `load()`
rebuilds it; in the task, `resolve(x)` gives the model, loaded once per process.

This module imports nothing heavy: the commands build their parsers beside it.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from vinadv.errors import InputError


@runtime_checkable
class Executor(Protocol):
    """Maps a task over chunks.

    Attributes:
        remote: tasks run in other processes (arguments pickled, models by reference) and a result may be delivered
            more than once (a writer keyed by the chunk skips what it has stored).
    """

    remote: bool

    def map(self, task: Callable[[Any], Any], chunks: Iterable, *, ordered: bool = True) -> Iterator:
        """`task(chunk)` of every chunk: in the order of `chunks` (`ordered`), or as they complete."""
        ...

    def bounds(self, n: int, size: int) -> list[tuple[int, int]]:
        """How this executor cuts `n` items that may be computed in pieces of `size`: `(lo, hi)` slices."""
        ...


def chunk_bounds(n: int, size: int, name: str = "shard_size") -> list[tuple[int, int]]:
    """`(lo, hi)` slices of `n` items, `size` each (the last one shorter); InputError naming `name` for size < 1."""
    if size < 1:
        raise InputError(f"{name} must be >= 1, got {size}", name)
    return [(lo, min(n, lo + size)) for lo in range(0, n, size)]


class LocalExecutor:
    """In this process, chunk after chunk, in order; what may be cut in pieces runs as one chunk."""

    remote = False

    def map(self, task: Callable[[Any], Any], chunks: Iterable, *, ordered: bool = True) -> Iterator:
        for chunk in chunks:
            yield task(chunk)

    def bounds(self, n: int, size: int) -> list[tuple[int, int]]:
        chunk_bounds(n, size)  # the size is checked all the same: it must not depend on the executor
        return [(0, n)] if n else []

    def __repr__(self) -> str:
        return "LocalExecutor()"


#: the executor of a job given none
LOCAL = LocalExecutor()


@dataclass(frozen=True)
class ByReference:
    """A model handed to a remote task by reference: `ref.load()` rebuilds it there (`ref` hashable and picklable;
    the planners' `PlannerRef`, say), once per process (`resolve`)."""

    ref: Any


def shipped(executor: Executor, model, reference: Callable[[], Any]):
    """`model` as a task's argument on `executor`: itself in this process, else `ByReference(reference())`."""
    if model is None or not executor.remote:
        return model
    return ByReference(reference())


_LOADED: dict = {}
_LOADED_LOCK = threading.Lock()


def process_cached(key, load: Callable[[], Any]):
    """`load()`, called once per process for `key` (hashable) and kept."""
    with _LOADED_LOCK:
        if key not in _LOADED:
            _LOADED[key] = load()
        return _LOADED[key]


def resolve(value):
    """In a task: the model of a `ByReference` (loaded once per process), or `value` itself."""
    if isinstance(value, ByReference):
        return process_cached(("ref", value.ref), value.ref.load)
    return value


__all__ = [
    "LOCAL",
    "ByReference",
    "Executor",
    "LocalExecutor",
    "chunk_bounds",
    "process_cached",
    "resolve",
    "shipped",
]
