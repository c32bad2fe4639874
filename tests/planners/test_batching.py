"""`over_maps`: every map exactly once, in pieces, never more threads at once than asked for; `forward_batches`:
every map once, in batches that never fall under `CPU_MIN_BATCH` on the CPU."""

import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vinadv.grid import generate_maps
from vinadv.planners import batching


@pytest.mark.parametrize("b", [0, 1, 5, 31, 32, 200, 1001])
@pytest.mark.parametrize("threads", [1, 2, 3])
def test_every_map_once_and_threads_bounded(b, threads, monkeypatch):
    monkeypatch.setattr(batching, "N_THREADS", 4)
    seen = np.zeros(b, dtype=int)
    lock = threading.Lock()
    active, most = [0], [0]

    def work(lo, hi):
        with lock:
            active[0] += 1
            most[0] = max(most[0], active[0])
        time.sleep(0.002)  # long enough for pieces to overlap if the pool let them
        seen[lo:hi] += 1
        with lock:
            active[0] -= 1

    batching.over_maps(b, work, threads=threads)
    assert (seen == 1).all()
    assert most[0] <= threads


def test_set_threads_caps_the_threads(monkeypatch):
    monkeypatch.setattr(batching, "N_THREADS", 4)
    batching.set_threads(1)
    assert batching.N_THREADS == 1
    callers = set()
    batching.over_maps(1000, lambda lo, hi: callers.add(threading.get_ident()), threads=4)
    assert callers == {threading.get_ident()}  # one thread: the caller's own


@given(lo=st.integers(0, 50), length=st.integers(0, 300), batch_size=st.integers(1, 100), on_cpu=st.booleans())
def test_forward_batches_cover_the_range_once(lo, length, batch_size, on_cpu):
    hi = lo + length
    batches = batching.forward_batches(lo, hi, on_cpu, batch_size)
    covered = [i for sl in batches for i in range(sl.start, sl.stop)]
    assert covered == list(range(lo, hi))  # in order, each map once
    sizes = [sl.stop - sl.start for sl in batches]
    if not on_cpu:
        assert all(size == batch_size for size in sizes[:-1]) and (not sizes or 0 < sizes[-1] <= batch_size)
    elif length < batching.CPU_MIN_BATCH:
        assert sizes == [length]  # too few to split: one batch, as before batches were small
    else:
        assert min(sizes) >= batching.CPU_MIN_BATCH and max(sizes) < 2 * batching.CPU_MIN_BATCH
        assert max(sizes) - min(sizes) <= 1


@pytest.mark.slow
def test_torch_keeps_its_threads_after_numba_parallel_kernels(tmp_path):
    """Numba's parallel kernels (OpenMP layer) can reset the calling thread's OpenMP thread count to Numba's own,
    which torch then uses; with `set_torch_threads` both agree. In a fresh process, whose defaults (2 threads each on
    a 2-core machine) the bug needs; torch used, then a maps file read and its maps searched, showed it."""
    path = tmp_path / "maps.npz"
    generate_maps(3000, 28, seed=1, n_starts=1).save(path)
    code = (
        "import torch, numba\n"
        "from vinadv.planners.batching import set_torch_threads\n"
        "from vinadv.grid import shortest_distances\n"
        "from vinadv.grid.mapset import MapSet\n"
        "set_torch_threads(1)\n"
        f"maps = MapSet.load({str(path)!r})\n"
        "assert torch.get_num_threads() == 1\n"  # torch asked first (as a training step would), then Numba runs
        "shortest_distances(maps.obstacles, maps.goals)\n"
        "print(torch.get_num_threads(), numba.config.NUMBA_NUM_THREADS)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    torch_threads, numba_pool = map(int, out.stdout.split())
    assert torch_threads == 1, f"torch went back to {torch_threads} threads (Numba's pool: {numba_pool})"
