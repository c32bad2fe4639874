"""What runs on a Dask worker: single-threaded numerics, planners and classifiers rebuilt from their files, and the
shard tasks of `vinadv run`, `vinadv attack` and `vinadv identify`, and the chunk task of `vinadv bench run`.

Nothing here imports Dask at module level except the plugin class, so the tasks also run (and are tested) in
plain Python. Models are never pickled: a task gets the path of the weights (or classifier) file and its checksum,
loads it once per worker process (`_MODELS`), and refuses a file whose checksum differs from the client's (a
worker on another machine with other weights would otherwise silently make other pairs).
"""

from __future__ import annotations

import os
import threading

from vinadv.errors import InputError
from vinadv.planners.batching import set_threads, set_torch_threads
from vinadv.planners.weights import weights_checksum  # a file's SHA-256, for any model file

#: environment of a worker process: one thread for each numeric library (a worker process is one core)
SINGLE_THREAD_ENV = {
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "NUMBA_NUM_THREADS": "1",
}

_MODELS: dict = {}
_MODELS_LOCK = threading.Lock()
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


def _cached(key, load):
    with _MODELS_LOCK:
        if key not in _MODELS:
            _MODELS[key] = load()
        return _MODELS[key]


def worker_planner(ref):
    """The planner of `ref` (a `vinadv.planners.registry.PlannerRef`), loaded once per worker process;
    `PlannerError` if this worker's planner differs from the client's (another weights file, say)."""
    return _cached(("planner", ref), ref.load)


def worker_classifier(spec: str | None, checksum: str | None):
    """The classifier `spec` ('rule', None or a model file), loaded once per worker process."""
    from vinadv.identify import load_classifier

    def load():
        if checksum is not None:
            found = weights_checksum(spec)
            if found != checksum:
                raise InputError(
                    f"classifier file {spec} on this worker differs from the client's (sha256 {found} != {checksum})"
                )
        return load_classifier(spec)[0]

    return _cached(("classifier", spec, checksum), load)


def run_shard_task(
    config, shard: int, planner_ref, classifier_spec: str | None, classifier_sum: str | None, label_source: str
):
    """`vinadv run`: shard `shard` of the run (`pipeline.compute_shard`), on a worker, with the planner of
    `planner_ref`; `classifier_spec` is the client's file as an absolute path."""
    from vinadv.pipeline import compute_shard

    single_threaded()
    classifier = worker_classifier(classifier_spec, classifier_sum)
    return compute_shard(config, shard, worker_planner(planner_ref), classifier, label_source)


def attack_shard_task(
    strategy: str,
    options: dict,
    obstacles,
    starts,
    goals,
    first_map: int,
    corner_cutting: bool,
    planner_ref,
    objective: str = "paper",
):
    """`vinadv attack` on maps `first_map .. first_map + len(obstacles)` of the file: the same pairs as attacking
    the whole file at once (map indices local to the shard; the client shifts them)."""
    from vinadv.attacks.strategies import make_attack
    from vinadv.identify import objective_strength

    single_threaded()
    attack = make_attack(strategy, **options)
    return attack.attack(
        obstacles,
        starts,
        goals,
        worker_planner(planner_ref),
        corner_cutting,
        strength=objective_strength(objective),
        first_map=first_map,
    )


def identify_shard_task(
    pairs,
    planner_ref,
    classifier_spec: str | None,
    classifier_sum: str | None,
    label_source: str,
    harm_tol: float,
    harm_rtol: float,
):
    """`vinadv identify` on a shard of pairs: plan again (with the planner of `planner_ref`, unless None), label,
    and compute the harm."""
    from vinadv.identify import identify, replan

    single_threaded()
    if planner_ref is not None:
        pairs = replan(pairs, worker_planner(planner_ref))
    return identify(
        pairs, worker_classifier(classifier_spec, classifier_sum), label_source, harm_tol=harm_tol, harm_rtol=harm_rtol
    )


def bench_chunk_task(suite, chunk: int, planner_ref, data: str | None):
    """`vinadv bench run`: chunk `chunk` of `suite` (a `vinadv.bench.suites.Suite`, sent by value) on a worker,
    `(chunk, vinadv.bench.entry.compute_chunk(...))`, with the planner of `planner_ref`. The suite's maps are made
    (or read from the folder `data`, an absolute path, checked by sha256) once per worker process."""
    from vinadv.bench.entry import compute_chunk, suite_maps

    single_threaded()
    maps = _cached(("bench-maps", suite.checksum, data), lambda: suite_maps(suite, data))
    return chunk, compute_chunk(suite, worker_planner(planner_ref), maps, chunk)


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
