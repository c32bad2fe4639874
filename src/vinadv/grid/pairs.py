"""`PathPairs`: n (original map, adversarial map) pairs with the path planned on each, the core of every pair type.

The pairs file (`vinadv.attacks.pairs.PairSet`), the classifier view (`vinadv.classify.batch.PathPairBatch`) and
the store's rows (`vinadv.store.records.PairRecords`) all build on it, so its checks, `take` and `concat` are
written once. It lives in `grid` although pairs are made by the attacks: every stage that handles pairs (attacks,
classify, identify, store, report) may import `grid`, and `grid` is the only such package that imports neither
PyTorch nor a planner; the type itself needs nothing but NumPy and `PackedPaths`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.columns import Columns
from vinadv.grid.paths import PackedPaths
from vinadv.vocabulary import ADD, EDITS, GOAL, TERMINATIONS


@dataclass(kw_only=True, eq=False)
class PathPairs(Columns):
    """n map pairs of N x N cells, one start and goal each, and both planned paths.

    Attributes (cells are `(row, col)`):
        obstacles_o, obstacles_a: `(n, N, N)` bool, True = obstacle; `obstacles_a` is `obstacles_o` plus `added`
            (edit `add`), or minus them (edit `remove`).
        starts, goals: `(n, 2)` int64: start and goal of each pair.
        added: `(n, K, 2)` int64, K >= 1: the K edited cells of each pair, in the order they were edited: added
            obstacles, or freed obstacle cells for a pair of edit `remove` (K = 1, the paper's setting, for
            one-obstacle pairs; every pair of one object has the same K). An `(n, 2)` array given here is read as
            K = 1.
        path_o, path_a: `PackedPaths` of n paths each, the planned paths on the original and adversarial map.
        term_o, term_a: `(n,)` str, why each path ended: one of `vocabulary.TERMINATIONS`.
        edit: `(n,)` str, each pair's edit, one of `vocabulary.EDITS` (`add`: obstacles added, the paper's
            setting; `remove`: obstacle cells freed); a single str is broadcast (default `add`).
        expanded_o, expanded_a: `PackedPaths` of n cell lists, the cells the planner's search expanded on each map
            (a planner that reports expansions, `Capabilities.expansions`; an empty list: none reported for that
            pair), or None (no pair has them).
        astar_expansions_o, astar_expansions_a: `(n,)` int64, the cells the exact A* of the pairs' movement model
            expands on each map, the reference of the effort figures (`vinadv.classify.effort`; -1: none), or None.
    """

    obstacles_o: np.ndarray
    obstacles_a: np.ndarray
    starts: np.ndarray
    goals: np.ndarray
    added: np.ndarray
    path_o: PackedPaths
    path_a: PackedPaths
    term_o: np.ndarray
    term_a: np.ndarray
    edit: np.ndarray | str = ADD
    expanded_o: PackedPaths | None = None
    expanded_a: PackedPaths | None = None
    astar_expansions_o: np.ndarray | None = None
    astar_expansions_a: np.ndarray | None = None

    def __post_init__(self) -> None:
        name = type(self).__name__
        self.obstacles_o = np.asarray(self.obstacles_o, dtype=bool)
        self.obstacles_a = np.asarray(self.obstacles_a, dtype=bool)
        shape = self.obstacles_o.shape
        if len(shape) != 3 or shape[1] != shape[2]:
            raise InputError(f"{name}.obstacles_o: expected shape (n, N, N), got {shape}")
        n = shape[0]
        if self.obstacles_a.shape != shape:
            raise InputError(f"{name}.obstacles_a: expected shape {shape}, got {self.obstacles_a.shape}")
        for field in ("starts", "goals"):
            setattr(self, field, int_column(getattr(self, field), f"{name}.{field}", (n, 2)))
        self.added = added_column(self.added, f"{name}.added", n)
        for field in ("path_o", "path_a"):
            paths = getattr(self, field)
            if not isinstance(paths, PackedPaths) or len(paths) != n:
                raise InputError(f"{name}.{field}: expected PackedPaths of {n} paths, got {paths!r}")
        for field in ("term_o", "term_a"):
            term = np.asarray(getattr(self, field))
            if term.shape != (n,):
                raise InputError(f"{name}.{field}: expected shape ({n},), got {term.shape}")
            setattr(self, field, term)
        self.edit = edit_column(self.edit, f"{name}.edit", n)
        for field in EXPANSION_FIELDS:
            value = getattr(self, field)
            if value is None:
                continue
            if field.startswith("astar"):
                setattr(self, field, int_column(value, f"{name}.{field}", (n,)))
            elif not isinstance(value, PackedPaths) or len(value) != n:
                raise InputError(f"{name}.{field}: expected PackedPaths of {n} cell lists or None, got {value!r}")

    @property
    def expansions_o(self) -> np.ndarray | None:
        """`(n,)` int64, the cells the planner expanded on the original maps (0: none reported), or None."""
        return None if self.expanded_o is None else self.expanded_o.lengths

    @property
    def expansions_a(self) -> np.ndarray | None:
        """`(n,)` int64, the cells the planner expanded on the adversarial maps (0: none reported), or None."""
        return None if self.expanded_a is None else self.expanded_a.lengths

    @classmethod
    def concat(cls, parts, size: int | None = None, n_added: int | None = None, **settings):
        """The pairs of `parts` in order (`Columns.concat`); `size`, the map side, and `n_added`, K (default 1),
        make an empty result possible (no parts) and are checked against the parts."""
        parts = list(parts)
        if not parts:
            return cls.empty(size, n_added=1 if n_added is None else n_added, **settings)
        sizes = {p.size for p in parts} | ({size} if size is not None else set())
        if len(sizes) > 1:
            raise InputError(f"{cls.__name__}.concat: pairs of different map sizes {sorted(sizes)}", "size")
        # an empty part says nothing about K: it joins parts of any K
        counts = {p.n_added for p in parts if len(p)} | ({n_added} if n_added is not None else set())
        if len(counts) > 1:
            raise InputError(
                f"{cls.__name__}.concat: pairs with different numbers of added obstacles {sorted(counts)}", "obstacles"
            )
        if len(parts) > 1:
            parts = [p for p in parts if len(p)] or parts[:1]
        return super().concat(parts, **settings)

    @classmethod
    def empty(cls, size: int | None = None, n_added: int = 1, **settings):
        """No pairs, on `size x size` maps, of `n_added` added obstacles; `settings`: the other fields of a
        subclass."""
        if size is None:
            raise InputError(f"{cls.__name__}.concat: no parts; pass size= (the map side) for an empty result", "size")
        return cls(
            obstacles_o=np.zeros((0, size, size), bool),
            obstacles_a=np.zeros((0, size, size), bool),
            starts=np.zeros((0, 2), np.int64),
            goals=np.zeros((0, 2), np.int64),
            added=np.zeros((0, n_added, 2), np.int64),
            path_o=PackedPaths.empty(),
            path_a=PackedPaths.empty(),
            term_o=np.zeros(0, "<U10"),
            term_a=np.zeros(0, "<U10"),
            **settings,
        )

    @property
    def size(self) -> int:
        """Map side N."""
        return int(self.obstacles_o.shape[-1])

    @property
    def n_added(self) -> int:
        """K, the number of obstacles each pair adds (1: the paper's setting)."""
        return int(self.added.shape[1])

    @property
    def removes(self) -> np.ndarray:
        """`(n,)` bool: the pair frees obstacle cells (edit `remove`) rather than adding them."""
        return self.edit == EDITS[1]

    @property
    def reached_o(self) -> np.ndarray:
        """`(n,)` bool: the original path ends at the goal."""
        return np.asarray(self.term_o) == TERMINATIONS[GOAL]

    @property
    def reached_a(self) -> np.ndarray:
        """`(n,)` bool: the adversarial path ends at the goal."""
        return np.asarray(self.term_a) == TERMINATIONS[GOAL]


#: the optional search-effort fields of `PathPairs` (the planner's expanded cells and A*'s counts on both maps)
EXPANSION_FIELDS = ("expanded_o", "expanded_a", "astar_expansions_o", "astar_expansions_a")


def added_column(value, name: str, n: int) -> np.ndarray:
    """The added cells `value` as int64 `(n, K, 2)`, K >= 1; `(n, 2)` is K = 1. InputError naming `name` else."""
    arr = np.asarray(value)
    if arr.ndim == 2:
        arr = arr.reshape(len(arr), 1, *arr.shape[1:])
    if arr.ndim != 3 or arr.shape[0] != n or arr.shape[2] != 2 or arr.shape[1] < 1:
        raise InputError(
            f"{name}: expected shape ({n}, K, 2) with K >= 1 (or ({n}, 2) for one obstacle), got {np.shape(value)}"
        )
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        raise InputError(f"{name}: expected integers, got {arr.dtype}")
    return arr.astype(np.int64, copy=False)


def edit_column(value, name: str, n: int) -> np.ndarray:
    """The edits `value` (one str, broadcast, or n of them) as a `(n,)` str array of `vocabulary.EDITS`; InputError
    naming `name` else."""
    arr = np.asarray(value)
    if arr.ndim == 0:
        arr = np.full(n, arr.item() if arr.dtype != object else str(arr.item()))
    if arr.shape != (n,):
        raise InputError(f"{name}: expected shape ({n},), got {arr.shape}")
    arr = arr.astype(str) if arr.size else np.zeros(0, "<U6")
    bad = ~np.isin(arr, EDITS)
    if bad.any():
        raise InputError(f"{name}: {arr[bad][0]!r} is not one of {'|'.join(EDITS)}")
    return arr.astype("<U6")


def int_column(value, name: str, shape: tuple) -> np.ndarray:
    """`value` as int64 of exactly `shape`, or InputError naming `name` (an empty array may be of any dtype)."""
    arr = np.asarray(value)
    if arr.shape != shape:
        raise InputError(f"{name}: expected shape {shape}, got {arr.shape}")
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        raise InputError(f"{name}: expected integers, got {arr.dtype}")
    return arr.astype(np.int64, copy=False)
