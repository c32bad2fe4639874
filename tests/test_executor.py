"""`vinadv.executor`: the local executor maps a task over chunks in order and runs what may be cut as one chunk;
models go to tasks as themselves locally, by reference to a remote executor, loaded once per process."""

import pytest

from vinadv.errors import InputError
from vinadv.executor import LOCAL, ByReference, Executor, chunk_bounds, process_cached, resolve, shipped


def test_the_local_executor_maps_in_order_lazily():
    seen = []

    def task(chunk):
        seen.append(chunk)
        return chunk * 2

    results = LOCAL.map(task, [3, 1, 2])
    assert seen == []  # nothing runs before the results are asked for
    assert list(results) == [6, 2, 4] and seen == [3, 1, 2]
    assert isinstance(LOCAL, Executor) and not LOCAL.remote


def test_bounds_cut_remote_work_and_keep_local_work_whole():
    assert chunk_bounds(7, 3) == [(0, 3), (3, 6), (6, 7)]
    assert LOCAL.bounds(7, 3) == [(0, 7)] and LOCAL.bounds(0, 3) == []
    with pytest.raises(InputError, match="shard_size must be >= 1, got 0") as info:
        LOCAL.bounds(7, 0)  # refused whatever the executor: the setting must not depend on it
    assert info.value.parameters == ("shard_size",)


class Ref:
    loads = 0

    def __init__(self, name):
        self.name = name

    def __hash__(self):
        return hash(self.name)

    def __eq__(self, other):
        return isinstance(other, Ref) and other.name == self.name

    def load(self):
        Ref.loads += 1
        return f"model {self.name}"


class Remote:
    remote = True


def test_models_are_shipped_by_reference_and_loaded_once_per_process():
    model = object()
    assert shipped(LOCAL, model, lambda: Ref("a")) is model
    assert shipped(Remote(), None, lambda: Ref("a")) is None
    by_ref = shipped(Remote(), model, lambda: Ref("once"))
    assert by_ref == ByReference(Ref("once"))
    before = Ref.loads
    assert resolve(by_ref) == resolve(ByReference(Ref("once"))) == "model once"
    assert Ref.loads == before + 1
    assert resolve(model) is model
    assert process_cached(("k", 1), lambda: [1]) is process_cached(("k", 1), lambda: [2])
