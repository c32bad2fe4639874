"""Scale out on a Dask cluster: `DaskExecutor`, an executor (`vinadv.executor`) that maps a task over chunks on the
workers of a Dask scheduler and knows no job. The commands open it (`open_executor`) for `--cluster tcp://HOST:PORT`
(an existing scheduler) or `--workers N` (a LocalCluster of N single-threaded worker processes, at most
`MAX_WORKERS_PER_CORE` = 4 per core of the machine: a cluster is for more); the jobs cut their
work in chunks and write their tasks (`vinadv.pipeline`, `vinadv.jobs.attack`, `vinadv.identify`,
`vinadv.bench.scoring`).

What the executor guarantees, whatever the job:
- Results come back to the client (`distributed.as_completed`); with `ordered` they are released in the order of
  the chunks (those that finish early wait in a bounded buffer), else as they complete. At most `window` tasks
  (4 per worker thread by default, re-read as workers come and go) are submitted or waiting at any time, which also
  bounds the client's memory. Workers never touch a database: the client writes.
- A lost worker's task is recomputed by Dask (the scheduler reschedules the tasks of a dead worker; tasks that raise
  are retried `retries` times); a task's future yields its result once, but the executor is `remote`: a job's
  writer keyed by the chunk skips what it has stored.
- Tasks get their models by reference (`vinadv.executor.shipped`), loaded once per worker process and checked
  against the client's checksums: workers need the same files at the same paths (shared file system, or the
  shipped default weights of the installed package).
- Each worker process uses one thread for torch, Numba and the planner's pool (`worker.single_threaded`, before
  every task); start external workers with `dask worker tcp://HOST:PORT --nworkers <cores> --nthreads 1`.

Dask is the optional extra `vinadv[cluster]`; nothing here imports it until a cluster is asked for, and the command
options that ask for one are the commands' (`vinadv.commands.add_cluster_arguments`).
"""

from __future__ import annotations

import contextlib
import os
import socket
import uuid
from collections.abc import Callable, Iterable, Iterator
from typing import Any
from urllib.parse import urlsplit

from vinadv.cluster.worker import SINGLE_THREAD_ENV, plugin_class, run_task
from vinadv.errors import InputError
from vinadv.executor import LOCAL, chunk_bounds

INSTALL_HINT = "pip install 'vinadv[cluster]'"
#: how often a task that raised is run again (worker deaths are handled by the scheduler's allowed-failures)
RETRIES = 3
#: tasks submitted or waiting per worker thread
WINDOW_PER_THREAD = 4
#: a local cluster's worker processes per core of this machine, at most (more only oversubscribe it: a cluster of
#: several machines, `--cluster`, is for more)
MAX_WORKERS_PER_CORE = 4

__all__ = ["INSTALL_HINT", "DaskExecutor", "open_cluster", "open_executor", "require_dask", "start_local_cluster"]


def require_dask():
    """`distributed`, or InputError saying how to install it."""
    try:
        import distributed
    except ImportError as exc:
        raise InputError(
            f"workers and cluster need Dask's distributed scheduler ({exc}); install it with {INSTALL_HINT}",
            "workers",
            "cluster",
        ) from None
    return distributed


def start_local_cluster(workers: int, **kwargs):
    """A LocalCluster of `workers` processes, one thread each, numeric libraries single-threaded."""
    check_local_workers(workers)
    require_dask()
    from distributed import LocalCluster

    options = dict(
        n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None, env=dict(SINGLE_THREAD_ENV)
    )
    return LocalCluster(**{**options, **kwargs})


def check_local_workers(workers: int) -> None:
    """Refuse (InputError naming `workers`) fewer than 1 worker process or more than `MAX_WORKERS_PER_CORE` per core of
    this machine, before any process is started."""
    if workers < 1:
        raise InputError(f"workers must be >= 1, got {workers}", "workers")
    cores = os.cpu_count() or 1
    if workers > MAX_WORKERS_PER_CORE * cores:
        raise InputError(
            f"workers {workers}: at most {MAX_WORKERS_PER_CORE} local worker processes per core, "
            f"{MAX_WORKERS_PER_CORE * cores} on this machine's {cores} cores; for more, give the scheduler of "
            "Dask workers on several machines (cluster tcp://HOST:PORT)",
            "workers",
            "cluster",
        )


@contextlib.contextmanager
def open_cluster(address: str | None = None, workers: int | None = None) -> Iterator:
    """A connected `distributed.Client` (None when neither `address` nor `workers` is given); closes what it
    started. Call it from the command (under `main()`), never at import: a LocalCluster spawns processes."""
    if address is None and workers is None:
        yield None
        return
    if address is not None and workers is not None:
        raise InputError("give either cluster or workers, not both", "cluster", "workers")
    require_dask()
    from distributed import Client

    with contextlib.ExitStack() as stack:
        if workers is not None:
            cluster = stack.enter_context(start_local_cluster(workers))
            client = stack.enter_context(Client(cluster))
        else:
            _check_reachable(address)
            try:
                client = stack.enter_context(Client(address, timeout="15s"))
            except (OSError, TimeoutError, ValueError) as exc:
                raise InputError(f"cluster {address}: cannot connect to a Dask scheduler ({exc})", "cluster") from None
        client.register_plugin(plugin_class()())
        yield client


@contextlib.contextmanager
def open_executor(address: str | None = None, workers: int | None = None) -> Iterator:
    """The executor of `--cluster`/`--workers`: a `DaskExecutor` on the cluster `open_cluster` opens, or
    `vinadv.executor.LOCAL` when neither is given."""
    with open_cluster(address, workers) as client:
        yield LOCAL if client is None else DaskExecutor(client)


def _check_reachable(address: str) -> None:
    """Fail fast (Dask's client keeps retrying a refused connection until its timeout)."""
    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    if parts.scheme not in ("tcp", "tls"):
        return  # other transports (inproc, ucx): let Dask judge
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if not host or not port:
        raise InputError(f"cluster {address}: expected tcp://HOST:PORT", "cluster")
    try:
        socket.create_connection((host, port), timeout=10).close()
    except OSError as exc:
        raise InputError(f"cluster {address}: cannot connect to a Dask scheduler ({exc})", "cluster") from None


class DaskExecutor:
    """Maps a task over chunks on a Dask cluster (module doc).

    Args:
        client: a connected `distributed.Client`.
        retries: how often a task that raised is run again.
        window: tasks submitted or waiting at any time (default: 4 per worker thread).
        on_result: called with each result as it arrives, before it is released (a test hook).
    """

    remote = True

    def __init__(self, client, retries: int = RETRIES, window: int | None = None, on_result=None):
        self.client = client
        self.retries = retries
        self.window = window
        self.on_result = on_result

    def __repr__(self) -> str:
        return f"DaskExecutor({self.client.scheduler.address if self.client.scheduler else None})"

    def bounds(self, n: int, size: int) -> list[tuple[int, int]]:
        return chunk_bounds(n, size)

    def map(self, task: Callable[[Any], Any], chunks: Iterable, *, ordered: bool = True) -> Iterator:
        from distributed import as_completed

        pending = list(enumerate(chunks))[::-1]  # pop() from the end = the first chunk first
        total = len(pending)
        prefix = f"vinadv-{uuid.uuid4().hex}"
        position: dict = {}
        arrived: dict = {}
        in_flight = 0
        futures = as_completed()

        def submit():
            nonlocal in_flight
            window = self.window or WINDOW_PER_THREAD * max(1, sum(self.client.nthreads().values()))
            while pending and in_flight + len(arrived) < window:
                i, chunk = pending.pop()
                future = self.client.submit(
                    run_task, task, chunk, key=f"{prefix}-{i}", retries=self.retries, pure=False
                )
                position[future.key] = i
                futures.add(future)
                in_flight += 1

        submit()
        next_pos = 0
        for future in futures:
            result = future.result()  # a task that failed for good raises here (InputError included)
            i = position.pop(future.key)
            future.release()
            in_flight -= 1
            if self.on_result is not None:
                self.on_result(result)
            if not ordered:
                next_pos += 1
                yield result
            else:
                arrived[i] = result
                while next_pos in arrived:
                    yield arrived.pop(next_pos)
                    next_pos += 1
            submit()
        if next_pos != total:  # pragma: no cover - as_completed ends only when every future is done
            raise RuntimeError(f"cluster returned {next_pos} of {total} chunks")
