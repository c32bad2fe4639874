"""What runs on a Dask worker around every task: single-threaded numerics (`single_threaded`, `run_task`) and the
worker plugin that sets them up on every worker, those that join later included.

Nothing here imports Dask at module level except the plugin class (made on first use), so `run_task` also runs (and
is tested) in plain Python. The tasks themselves are the jobs' (`vinadv.executor`); the models they need are
loaded once per worker process by `vinadv.executor.resolve`.
"""

from __future__ import annotations

import os
import threading

from vinadv.planners.batching import set_threads, set_torch_threads

#: environment of a worker process: one thread for each numeric library (a worker process is one core)
SINGLE_THREAD_ENV = {
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "NUMBA_NUM_THREADS": "1",
}

_THREAD_STATE = threading.local()


def single_threaded() -> None:
    """Make this process and thread use one core: torch intra-op threads, Numba's thread layer, the engine's pool.

    Torch's setting is per process; Numba's is per calling thread, so every task calls this (cheap after the first
    time in a thread)."""
    if getattr(_THREAD_STATE, "done", False):
        return
    for name, value in SINGLE_THREAD_ENV.items():
        os.environ.setdefault(name, value)  # before numba/torch first import in this process
    set_torch_threads(1)
    set_threads(1)  # the planners' own thread pool over maps (sized from the CPU affinity)
    _THREAD_STATE.done = True


def run_task(task, chunk):
    """`task(chunk)` on a worker, single-threaded."""
    single_threaded()
    return task(chunk)


def plugin_class():
    """The worker plugin class (made on first use: it subclasses Dask's `WorkerPlugin`, imported late)."""
    from distributed.diagnostics.plugin import WorkerPlugin

    class SingleThreadWorker(WorkerPlugin):
        """Run on every worker (and every worker that joins later): one thread per numeric library."""

        name = "vinadv-single-thread"

        def setup(self, worker):
            for name, value in SINGLE_THREAD_ENV.items():
                os.environ.setdefault(name, value)
            import torch

            torch.set_num_threads(1)

    return SingleThreadWorker
