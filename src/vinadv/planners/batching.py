"""How the planners split a batch of maps: chunks (bound memory) and threads (`over_maps`).

Light on purpose (standard library only): `vinadv plan --help` reads `DEFAULT_CHUNK` from here without loading
Numba or PyTorch.
"""

from __future__ import annotations

import contextlib
import functools
import os
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor

#: maps per chunk of the planning engine: bounds the memory of its path buffers (N * N cells per rollout, touched
#: only as far as used).
DEFAULT_CHUNK = 4096
#: threads of `over_maps`: the cores this process may use, at most 8. A Dask worker sets it to 1
#: (`set_threads`).
N_THREADS = max(1, min(len(os.sched_getaffinity(0)), 8))


def chunk_slices(total: int, chunk_size: int, progress: bool = False, desc: str = "planning") -> Iterable[slice]:
    """`range(total)` as slices of `chunk_size` (at least 1) items, under a tqdm bar named `desc` when `progress`."""
    chunk_size = max(1, int(chunk_size))
    slices = [slice(i, i + chunk_size) for i in range(0, total, chunk_size)]
    if not progress:
        return slices
    from tqdm import tqdm  # noqa: PLC0415 (tqdm: planning without a bar does not load it)

    return tqdm(slices, unit="chunk", desc=desc)


def set_threads(threads: int) -> None:
    """Use at most `threads` threads in `over_maps` from now on."""
    global N_THREADS
    N_THREADS = max(1, int(threads))


@functools.cache
def _pool(threads: int) -> ThreadPoolExecutor:
    """A pool of `threads` workers (one per thread count asked for: a pool's size bounds how many pieces run at
    once)."""
    return ThreadPoolExecutor(threads, thread_name_prefix="vinadv-plan")


#: pieces per thread in `over_maps`, and the fewest maps in a piece
PIECES_PER_THREAD = 4
MIN_PIECE = 16


#: the most work (in units of the caller's `cost`: multiply-adds for the VIN's value iteration) one round of
#: `over_maps` hands to its threads: about a second of compiled kernel, after which Ctrl-C and SIGTERM are seen
ROUND_COST = 2 * 10**9


def over_maps(b: int, work: Callable[[int, int], None], threads: int | None = None, cost: float = 0.0) -> None:
    """`work(lo, hi)` over `range(b)` split between `threads` threads (default and at most `N_THREADS`), for
    kernels that release the GIL (Numba `nogil=True`).

    `cost`: the work of one map (say k * l_q * N * N multiply-adds); the maps are then run in rounds of at most
    `ROUND_COST` work between them, one after the other, so that a signal (Ctrl-C, SIGTERM), which Python handles only
    between two calls of a compiled kernel, stops the command within a round, however large k or the batch.

    Plain threads rather than Numba's OpenMP layer: OpenMP workers left spinning slow down PyTorch's own OpenMP
    pool, which callers use right after. Several pieces per thread, taken as threads come free: on a machine where
    another process holds a core, the thread sharing that core does less of the work instead of holding up the
    rest (one piece per thread made the job as slow as its slowest thread, about 2x).
    """
    threads = N_THREADS if threads is None else max(1, min(threads, N_THREADS))
    per_round = b if cost <= 0 else max(1, int(ROUND_COST * threads // cost))
    if per_round < b:
        for lo in range(0, b, per_round):
            hi = min(b, lo + per_round)
            over_maps(hi - lo, lambda a, z, lo=lo: work(lo + a, lo + z), threads)
        return
    pieces = min(threads * PIECES_PER_THREAD, b // MIN_PIECE)
    if threads == 1 or pieces < 2:
        work(0, b)
        return
    bounds = [b * i // pieces for i in range(pieces + 1)]
    list(_pool(threads).map(lambda lh: work(*lh), zip(bounds[:-1], bounds[1:])))


#: the fewest maps in one CPU forward of a torch planner (`forward_batches`): oneDNN convolves a batch of fewer than 16
#: images with other kernels, whose float32 sums differ in the last bits (measured on the shipped GPPN: every batch
#: of 16 or more gives each map the same logits bit for bit, every smaller one does not)
CPU_MIN_BATCH = 16


def forward_batches(lo: int, hi: int, on_cpu: bool, batch_size: int) -> list[slice]:
    """`range(lo, hi)` as the batches of a torch planner's forwards: `batch_size` maps at a time on a GPU; on the
    CPU as many batches as make each at least `CPU_MIN_BATCH` maps (all in one where there are fewer), their sizes
    differing by at most one.

    Small CPU batches keep a forward's activations in the caches: the shipped GPPN's forward on 28x28 maps and the
    Neural A* encoder's on 32x32 maps each take about 0.6 of the time in batches of 16 as of 64
    (`perf/torch_batch.py`). Never
    below `CPU_MIN_BATCH`, so a map's logits are the same bits in whatever batch it lands.
    """
    if not on_cpu:
        return [slice(i, min(hi, i + batch_size)) for i in range(lo, hi, batch_size)]
    count = max(1, (hi - lo) // CPU_MIN_BATCH)
    bounds = [lo + (hi - lo) * i // count for i in range(count + 1)]
    return [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]


def forward_maps(b: int, device, batch_size: int, forward: Callable[[slice], None]) -> None:
    """Call `forward(sl)` over the slices of `b` maps, without gradients: on the CPU split between threads of one
    torch thread each (`over_maps`), on another device `batch_size` maps at a time, one after another; the slices are
    `forward_batches`'."""
    import torch

    on_cpu = device.type == "cpu"

    def work(lo: int, hi: int) -> None:
        with torch.no_grad():  # per thread: grad mode is thread-local
            for sl in forward_batches(lo, hi, on_cpu, batch_size):
                forward(sl)

    if not on_cpu:
        work(0, b)
    else:
        with torch_threads(1):
            over_maps(b, work)


def set_torch_threads(threads: int) -> None:
    """PyTorch's intra-op threads set to `threads` for good, and Numba's parallel kernels to as many (at most its
    pool).

    Both matter: a Numba parallel kernel (its OpenMP layer runs on the libgomp PyTorch loads) sets the calling
    thread's OpenMP thread count to Numba's own at every launch, and PyTorch reads its thread count from there.
    Measured: after `torch.set_num_threads(1)`, one `shortest_distances` call put PyTorch back on 2 threads."""
    import numba
    import torch

    torch.set_num_threads(threads)
    numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))


@contextlib.contextmanager
def torch_threads(threads: int) -> Iterator[None]:
    """PyTorch's intra-op threads set to `threads` inside the block, restored after (a process-wide setting).

    The torch planners run their forward on one torch thread per `over_maps` thread: on small maps a multi-threaded
    op spends its time synchronising, and on a machine where another process holds a core it waits for that core
    (measured: 40x slower with 2 threads than with 1 for a small GPPN on 10x10 maps, one busy core)."""
    import torch

    before = torch.get_num_threads()
    if before != threads:
        torch.set_num_threads(threads)
    try:
        yield
    finally:
        if before != threads:
            torch.set_num_threads(before)
