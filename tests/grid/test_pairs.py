from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vinadv.errors import InputError
from vinadv.grid.pairs import PathPairs
from vinadv.grid.paths import PackedPaths
from vinadv.vocabulary import TERMINATIONS

SIZE = 6


def random_pairs(n: int, seed: int) -> PathPairs:
    rng = np.random.default_rng(seed)
    obstacles = rng.random((n, SIZE, SIZE)) < 0.3
    added = rng.integers(0, SIZE, (n, 2))
    obstacles_a = obstacles.copy()
    obstacles_a[np.arange(n), added[:, 0], added[:, 1]] = True

    def paths():
        return PackedPaths.pack([rng.integers(0, SIZE, (rng.integers(1, 6), 2)) for _ in range(n)])

    return PathPairs(
        obstacles_o=obstacles,
        obstacles_a=obstacles_a,
        starts=rng.integers(0, SIZE, (n, 2)),
        goals=rng.integers(0, SIZE, (n, 2)),
        added=added,
        path_o=paths(),
        path_a=paths(),
        term_o=np.array(TERMINATIONS)[rng.integers(0, 4, n)],
        term_a=np.array(TERMINATIONS)[rng.integers(0, 4, n)],
    )


def rows(pairs: PathPairs) -> list[tuple]:
    """Each pair as plain Python values: the oracle for take/concat."""
    return [
        (
            pairs.obstacles_o[i].tolist(),
            pairs.obstacles_a[i].tolist(),
            pairs.starts[i].tolist(),
            pairs.goals[i].tolist(),
            pairs.added[i].tolist(),
            pairs.path_o[i].tolist(),
            pairs.path_a[i].tolist(),
            str(pairs.term_o[i]),
            str(pairs.term_a[i]),
        )
        for i in range(len(pairs))
    ]


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 8), st.integers(0, 10**6), st.data())
def test_take_is_list_indexing(n, seed, data):
    pairs = random_pairs(n, seed)
    idx = data.draw(st.lists(st.integers(0, n - 1), max_size=12)) if n else []
    assert rows(pairs.take(np.array(idx, dtype=np.int64))) == [rows(pairs)[i] for i in idx]
    mask = np.array(data.draw(st.lists(st.booleans(), min_size=n, max_size=n)), dtype=bool)
    assert rows(pairs.take(mask)) == [r for r, m in zip(rows(pairs), mask) if m]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 5), min_size=1, max_size=4), st.integers(0, 10**6))
def test_concat_is_list_concatenation(sizes, seed):
    parts = [random_pairs(n, seed + i) for i, n in enumerate(sizes)]
    assert rows(PathPairs.concat(parts)) == [r for p in parts for r in rows(p)]


def test_empty_and_concat_of_nothing():
    empty = PathPairs.empty(SIZE)
    assert len(empty) == 0 and empty.size == SIZE and len(empty.path_o) == 0
    assert PathPairs.concat([], size=SIZE).obstacles_o.shape == (0, SIZE, SIZE)
    with pytest.raises(InputError, match="pass size="):
        PathPairs.concat([])  # the empty form needs the map side


def test_reached():
    pairs = random_pairs(5, 1)
    assert pairs.reached_o.tolist() == [t == "goal" for t in pairs.term_o]


@pytest.mark.parametrize(
    "change, match",
    [
        ({"starts": np.zeros((3, 2))}, r"PathPairs.starts: expected shape \(4, 2\)"),
        ({"goals": np.full((4, 2), 0.5)}, "PathPairs.goals: expected integers"),
        ({"obstacles_a": np.zeros((4, 5, 5), bool)}, "PathPairs.obstacles_a: expected shape"),
        ({"path_a": PackedPaths.empty(3)}, "PathPairs.path_a: expected PackedPaths of 4 paths"),
        ({"term_o": np.array(["goal"])}, r"PathPairs.term_o: expected shape \(4,\)"),
    ],
)
def test_bad_fields_are_named(change, match):
    good = random_pairs(4, 2)
    fields = {
        name: getattr(good, name)
        for name in ("obstacles_o", "obstacles_a", "starts", "goals", "added", "path_o", "path_a", "term_o", "term_a")
    }
    with pytest.raises(InputError, match=match):
        PathPairs(**{**fields, **change})


@dataclass(kw_only=True, eq=False)
class Tagged(PathPairs):
    """A subclass with a per-row column, an optional column and a setting, like the pairs file and the store."""

    META = ("tag",)
    score: np.ndarray
    extra: np.ndarray | None = None
    tag: str = "x"

    @classmethod
    def empty(cls, size: int | None = None, **settings):
        return super().empty(size, score=np.zeros(0), **settings)


def test_subclass_columns_settings_and_optional_fields():
    a = Tagged(**{k: v for k, v in vars(random_pairs(3, 3)).items()}, score=np.arange(3.0), extra=np.arange(3))
    b = Tagged(**{k: v for k, v in vars(random_pairs(2, 4)).items()}, score=np.arange(2.0))
    both = Tagged.concat([a, b])
    assert both.score.tolist() == [0, 1, 2, 0, 1] and both.extra is None and both.tag == "x"
    assert a.take([2, 0]).extra.tolist() == [2, 0]
    with pytest.raises(InputError, match="differ in tag"):
        Tagged.concat([a, Tagged.concat([b], tag="y")])
    assert Tagged.concat([a, Tagged.concat([b], tag="y")], tag="z").tag == "z"
    assert Tagged.concat([], size=SIZE, tag="q").tag == "q"
    with pytest.raises(InputError, match="different map sizes"):
        Tagged.concat([a], size=3)
    with pytest.raises(InputError, match="not among its settings"):
        Tagged.concat([a], colour="red")
