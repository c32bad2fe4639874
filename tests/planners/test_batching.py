"""`over_maps`: every map exactly once, in pieces, never more threads at once than asked for."""

import threading
import time

import numpy as np
import pytest

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
