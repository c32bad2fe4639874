"""Scale out on a Dask cluster: `--cluster tcp://HOST:PORT` (an existing scheduler) or `--workers N` (a LocalCluster
of N single-threaded worker processes) on `vinadv run`, `vinadv attack`, `vinadv identify` and `vinadv bench run`.

Who computes and who writes:
- `run`: shard `k` is `pipeline.compute_shard(config, k)` on a worker, from its own seed `(seed, k)`, so the stored
  run does not depend on the number of workers or the order shards finish. Results come back to the client as they
  complete (`distributed.as_completed`); the client writes them, in shard order, with the store's batched
  transactional writes. Workers never touch the database: one writer needs no database credentials on the
  workers, works the same for SQLite files and servers, and keeps `--resume` exact (it relies on shards being
  stored in order: shards before the last stored one are complete). Shards that finish early wait in a bounded
  buffer: at most `window` shards (4 per worker thread by default) are submitted or waiting at any time, which
  also bounds the client's memory.
- `attack` / `identify`: the maps (pairs) are split in shards of `--shard-size`, sent to the workers, and the
  results gathered in order: the same pairs/labels as the local command.
- `bench run`: chunk `c` of the suite is `bench.entry.compute_chunk(suite, planner, maps, c)` on a worker (the suite
  sent by value; its maps made, or read from `--data`, once per worker process); results come back as they
  complete and the client stores each (`--db`: one transaction per chunk, keyed by its index, so the order does not
  matter to `--resume`) and builds the entry from all of them: the same entry as the local run, but for its time.
- A lost worker's shard is recomputed by Dask (the scheduler reschedules the tasks of a dead worker; tasks that
  raise are retried `retries` times); a shard's future yields its result once, and the client writes with
  `skip_stored` on the unique `(run_id, pair_index)`, so a shard is never stored twice.
- Workers rebuild the planner (`vinadv.planners.registry.PlannerRef`: spec and weights file) and a classifier model
  from their file paths, checked against the client's checksums, once per worker process; they need the same files
  at the same paths (shared file system, or the shipped default weights of the installed package).
- Each worker process uses one thread for torch, Numba and the planner's pool; start external workers with
  `dask worker tcp://HOST:PORT --nworkers <cores> --nthreads 1`.

Dask is the optional extra `vinadv[cluster]`; nothing here imports it until a cluster is asked for.

NumPy too is imported inside the functions that use it: `vinadv --help` builds its parser from this module.
"""

from __future__ import annotations

import contextlib
import os
import socket
from collections.abc import Iterator
from urllib.parse import urlsplit

from vinadv.cluster.worker import (
    SINGLE_THREAD_ENV,
    attack_shard_task,
    bench_chunk_task,
    identify_shard_task,
    plugin_class,
    run_shard_task,
)
from vinadv.errors import InputError
from vinadv.planners.weights import weights_checksum

INSTALL_HINT = "pip install 'vinadv[cluster]'"
#: how often a task that raised is run again (worker deaths are handled by the scheduler's allowed-failures)
RETRIES = 3
#: shards submitted or waiting per worker thread
WINDOW_PER_THREAD = 4

__all__ = [
    "INSTALL_HINT",
    "add_cluster_arguments",
    "open_cluster",
    "start_local_cluster",
    "ClusterShards",
    "ClusterIdentify",
    "ClusterBenchChunks",
    "attack_on_cluster",
    "identify_on_cluster",
    "require_dask",
]


def require_dask():
    """`distributed`, or InputError saying how to install it."""
    try:
        import distributed
    except ImportError as exc:
        raise InputError(
            f"workers/cluster need Dask's distributed scheduler ({exc}); install it with {INSTALL_HINT}",
            "workers",
            "cluster",
        ) from None
    return distributed


def add_cluster_arguments(parser, shard_size: bool = False) -> None:
    """`--cluster`, `--workers` (and with `shard_size`, `--shard-size` for commands that have none yet)."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--cluster", metavar="tcp://HOST:PORT", help="compute on this Dask scheduler's workers")
    group.add_argument(
        "--workers", type=int, metavar="N", help="compute on a local Dask cluster of N single-threaded worker processes"
    )
    if shard_size:
        parser.add_argument(
            "--shard-size", type=int, default=1000, help="with --cluster/--workers: items per task (default 1000)"
        )


def start_local_cluster(workers: int, **kwargs):
    """A LocalCluster of `workers` processes, one thread each, numeric libraries single-threaded."""
    if workers < 1:
        raise InputError(f"workers must be >= 1, got {workers}", "workers")
    require_dask()
    from distributed import LocalCluster

    options = dict(
        n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None, env=dict(SINGLE_THREAD_ENV)
    )
    return LocalCluster(**{**options, **kwargs})


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


def _absolute(path) -> str:
    """Workers may run in another directory: they get absolute paths (same files at the same paths)."""
    return os.path.abspath(os.fspath(path))


def _total_threads(client) -> int:
    return max(1, sum(client.nthreads().values()))


class ClusterShards:
    """`run_pipeline`'s `shard_results` on a Dask cluster: yields each shard's `ShardResult`, in shard order.

    Tasks are submitted `window` at a time (default 4 per worker thread, re-read as workers come and go), collected
    with `as_completed`, and released to the caller in shard order, so the caller's writes keep `--resume` exact.
    """

    def __init__(self, client, retries: int = RETRIES, window: int | None = None, on_result=None):
        self.client = client
        self.retries = retries
        self.window = window
        self.on_result = on_result  # test hook: called with each ShardResult as it arrives

    def __call__(self, config, shards, planner, classifier, label_source):
        from dask.base import tokenize
        from distributed import as_completed

        from vinadv.planners.registry.loading import PlannerRef

        ref = PlannerRef.of(planner, config.planner, config.weights, config.corner_cutting)
        classifier = config.classifier if config.classifier in (None, "rule") else _absolute(config.classifier)
        classifier_sum = None if classifier in (None, "rule") else weights_checksum(classifier)
        token = tokenize(config.to_dict(), ref, classifier_sum, label_source)
        pending = list(shards)[::-1]  # pop() from the end = lowest shard first
        order = list(shards)
        arrived: dict = {}
        in_flight = 0
        futures = as_completed()

        def submit():
            nonlocal in_flight
            window = self.window or WINDOW_PER_THREAD * _total_threads(self.client)
            while pending and in_flight + len(arrived) < window:
                shard = pending.pop()
                futures.add(
                    self.client.submit(
                        run_shard_task,
                        config,
                        shard,
                        ref,
                        classifier,
                        classifier_sum,
                        label_source,
                        key=f"vinadv-shard-{token}-{shard}",
                        retries=self.retries,
                        pure=False,
                    )
                )
                in_flight += 1

        submit()
        next_pos = 0
        for future in futures:
            result = future.result()  # a task that failed for good raises here (InputError included)
            future.release()
            in_flight -= 1
            arrived[result.shard] = result
            if self.on_result is not None:
                self.on_result(result)
            while next_pos < len(order) and order[next_pos] in arrived:
                yield arrived.pop(order[next_pos])
                next_pos += 1
            submit()
        if next_pos != len(order):  # pragma: no cover - as_completed ends only when every future is done
            raise RuntimeError(f"cluster returned {next_pos} of {len(order)} shards")


def _gather_in_order(client, futures, progress: bool, desc: str, unit_counts):
    """Results of `futures` in submission order, a tqdm bar over items while they complete."""
    from distributed import as_completed

    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=int(sum(unit_counts)), desc=desc, unit="item")
    position = {f.key: i for i, f in enumerate(futures)}
    results = [None] * len(futures)
    for future in as_completed(futures):
        i = position[future.key]
        results[i] = future.result()
        future.release()
        if bar is not None:
            bar.update(unit_counts[i])
    if bar is not None:
        bar.close()
    return results


def _bounds(n: int, shard_size: int) -> list[tuple[int, int]]:
    if shard_size < 1:
        raise InputError(f"shard_size must be >= 1, got {shard_size}", "shard_size")
    return [(lo, min(n, lo + shard_size)) for lo in range(0, n, shard_size)]


def attack_on_cluster(
    client,
    strategy: str,
    options: dict,
    maps,
    planner_ref,
    shard_size: int = 1000,
    progress: bool = False,
    objective: str = "paper",
):
    """`Attack.attack` of every map of `maps` (first start of each) with the planner of `planner_ref` (a
    `vinadv.planners.registry.PlannerRef`), `shard_size` maps per task: the same `AttackResult` as the local
    command. `options`: `make_attack`'s keyword arguments (per_map, seed, ...); `objective`: what the ranking
    strategies keep ('paper' | 'harm', `vinadv.identify.OBJECTIVES`)."""
    import numpy as np

    from vinadv.attacks.strategies import AttackResult, make_attack

    attack = make_attack(strategy, **options)  # validates the options here, before anything is sent
    bounds = _bounds(len(maps), shard_size)
    futures = [
        client.submit(
            attack_shard_task,
            strategy,
            options,
            maps.obstacles[lo:hi],
            maps.starts[lo:hi, 0],
            maps.goals[lo:hi],
            lo,
            maps.corner_cutting,
            planner_ref,
            objective,
            retries=RETRIES,
            pure=False,
        )
        for lo, hi in bounds
    ]
    parts = _gather_in_order(client, futures, progress, f"attack {strategy}", [hi - lo for lo, hi in bounds])
    from vinadv.attacks.pairs import PairSet

    params = parts[0].pairs.params if parts else attack.params()  # the planner's spec included
    steps = []
    for k in range(attack.obstacles):  # each greedy step's pairs, the shards' joined (the last: the result)
        shifted = []
        for (lo, _), part in zip(bounds, parts):
            step = part.steps[k]
            step.map_index = step.map_index + lo
            shifted.append(step)
        steps.append(
            PairSet.concat(
                shifted,
                size=maps.size,
                n_added=k + 1,
                strategy=strategy,
                params=params,
                corner_cutting=maps.corner_cutting,
            )
        )
    no_valid = (
        np.concatenate([p.no_valid_cell + lo for (lo, _), p in zip(bounds, parts)]).astype(np.int64)
        if parts
        else np.zeros(0, np.int64)
    )
    return AttackResult(steps[-1], no_valid, int(sum(p.planner_calls for p in parts)), steps)


class ClusterIdentify:
    """`identify.identify_and_store`'s `remote`: `identify_on_cluster` on the Dask scheduler at `address`, or on a
    local cluster of `workers`, opened when called (after the caller has checked its inputs) and closed after."""

    def __init__(
        self, address: str | None = None, workers: int | None = None, shard_size: int = 1000, progress: bool = False
    ):
        self.address, self.workers, self.shard_size, self.progress = address, workers, shard_size, progress

    def __call__(
        self, pairs, planner_ref, classifier: str | None, label_source: str, *, harm_tol: float, harm_rtol: float
    ):
        with open_cluster(self.address, self.workers) as client:
            return identify_on_cluster(
                client,
                pairs,
                planner_ref,
                classifier,
                label_source,
                shard_size=self.shard_size,
                progress=self.progress,
                harm_tol=harm_tol,
                harm_rtol=harm_rtol,
            )


def identify_on_cluster(
    client,
    pairs,
    planner_ref,
    classifier: str | None,
    label_source: str,
    shard_size: int = 1000,
    progress: bool = False,
    *,
    harm_tol: float,
    harm_rtol: float,
):
    """`identify` (after `replan` with the planner of `planner_ref`, unless None) of `pairs`, `shard_size` pairs
    per task: the same `Identification` as the local command (harm with the tolerances `harm_tol`, `harm_rtol`)."""
    import numpy as np

    from vinadv.identify import Identification

    classifier = classifier if classifier in (None, "rule") else _absolute(classifier)
    classifier_sum = None if classifier in (None, "rule") else weights_checksum(classifier)
    bounds = _bounds(len(pairs), shard_size)
    futures = [
        client.submit(
            identify_shard_task,
            pairs.take(np.arange(lo, hi)),
            planner_ref,
            classifier,
            classifier_sum,
            label_source,
            harm_tol,
            harm_rtol,
            retries=RETRIES,
            pure=False,
        )
        for lo, hi in bounds
    ]
    parts = _gather_in_order(client, futures, progress, "identify", [hi - lo for lo, hi in bounds])
    if not parts:
        from vinadv.identify import identify

        return identify(pairs, None, label_source, harm_tol=harm_tol, harm_rtol=harm_rtol)
    return Identification.concat(parts, label_source=label_source)


class ClusterBenchChunks:
    """`vinadv.bench.entry.run_bench`'s `chunk_results` on a Dask cluster: every chunk to compute is submitted (a
    suite has tens of chunks), and `(chunk, result)` pairs are yielded as they complete, in any order.

    Args:
        client: a connected `distributed.Client`.
        planner_ref: the planner, by reference (`vinadv.planners.registry.PlannerRef`): workers load it once each,
            checked against the client's checksum.
        data: a data suite's folder (`--data`), made absolute for the workers (the same files at the same path).
    """

    def __init__(self, client, planner_ref, data=None, retries: int = RETRIES):
        self.client = client
        self.planner_ref = planner_ref
        self.data = None if data is None else _absolute(data)
        self.retries = retries

    def __call__(self, suite, planner, maps, chunks):
        from dask.base import tokenize
        from distributed import as_completed

        token = tokenize(suite.checksum, self.planner_ref, self.data)
        futures = [
            self.client.submit(
                bench_chunk_task,
                suite,
                chunk,
                self.planner_ref,
                self.data,
                key=f"vinadv-bench-{token}-{chunk}",
                retries=self.retries,
                pure=False,
            )
            for chunk in chunks
        ]
        for future in as_completed(futures):
            chunk, result = future.result()  # a task that failed for good raises here (InputError included)
            future.release()
            yield chunk, result
