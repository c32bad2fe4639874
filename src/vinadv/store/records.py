"""`PairRecords`: a batch of identified map pairs as columnar NumPy arrays — what the store writes and reads."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.pairs import PathPairs, int_column
from vinadv.grid.paths import PackedPaths
from vinadv.store.schema import HARM_COLUMNS, HARM_FLOAT_COLUMNS
from vinadv.vocabulary import HARMS, LABELS


@dataclass(kw_only=True, eq=False)
class PairRecords(PathPairs):
    """n identified map pairs, one row each of the `map_pairs` table: `PathPairs` plus the identification.

    Shapes (n pairs, N x N maps; cells are (row, col)), besides those of `PathPairs` (obstacles_o/obstacles_a
    `(n, N, N)` bool, starts/goals `(n, 2)` int64, added `(n, K, 2)` int64 (stored as `added_obstacle`, the first,
    and `added_more`, the rest), path_o/path_a `PackedPaths`, term_o/term_a `(n,)` str, edit `(n,)` str):
      pair_index (n,) int64 — position of the pair in its run, unique per run (the resume key)
      label (n,) str in 'invalid|UrP|UcP|DP|FP'; attack (n,) bool (success: UrP or FP)
      label_source (n,) str — who labelled it ('rule', a classifier name, ...); a single str is broadcast
      score (n,) float64 — classifier score, NaN = none (NULL)
      dh, dv (n,) int64 — horizontal / vertical path distance, -1 = not applicable (NULL)
      opt_cost_o, opt_cost_a, cost_o, cost_a, regret_o, regret_a (n,) float64 — harm costs in move units
        (DESIGN.md "Harm"), NaN = none (NULL)
      expert_label (n,) object, 'invalid|UrP|UcP|DP|FP' or None; harm (n,) object, 'harmful|harmless|invalid' or
        None (None = not computed, NULL)
      expanded_o, expanded_a, astar_expansions_o, astar_expansions_a — the search effort (`PathPairs`; stored as
        `expanded_*` path text and A*'s counts, NULL where not reported)
      no (n,) int64 or None — the table's global sequence number; filled when read back, ignored on write
    String columns are object arrays.
    """

    pair_index: np.ndarray
    label: np.ndarray
    attack: np.ndarray
    label_source: np.ndarray | str = "rule"
    score: np.ndarray | None = None
    dh: np.ndarray | None = None
    dv: np.ndarray | None = None
    opt_cost_o: np.ndarray | None = None
    opt_cost_a: np.ndarray | None = None
    cost_o: np.ndarray | None = None
    cost_a: np.ndarray | None = None
    regret_o: np.ndarray | None = None
    regret_a: np.ndarray | None = None
    expert_label: np.ndarray | None = None
    harm: np.ndarray | None = None
    no: np.ndarray | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        n = len(self.starts)
        self.pair_index = int_column(self.pair_index, "PairRecords.pair_index", (n,))
        for name in ("term_o", "term_a"):
            setattr(self, name, _strings(getattr(self, name), name, n))
        self.label = _strings(self.label, "label", n)
        bad = ~np.isin(self.label, LABELS)
        if bad.any():
            raise InputError(f"PairRecords.label: {self.label[bad][0]!r} is not one of {'|'.join(LABELS)}")
        attack = np.asarray(self.attack)
        if attack.shape != (n,):
            raise InputError(f"PairRecords.attack: expected shape ({n},), got {attack.shape}")
        self.attack = attack.astype(bool)
        self.label_source = _strings(self.label_source, "label_source", n)
        self.score = np.full(n, np.nan) if self.score is None else np.asarray(self.score, dtype=np.float64)
        if self.score.shape != (n,):
            raise InputError(f"PairRecords.score: expected shape ({n},), got {self.score.shape}")
        for name in ("dh", "dv"):
            value = getattr(self, name)
            column = np.full(n, -1, np.int64) if value is None else int_column(value, f"PairRecords.{name}", (n,))
            setattr(self, name, column)
        for name in HARM_FLOAT_COLUMNS:
            value = np.full(n, np.nan) if getattr(self, name) is None else np.asarray(getattr(self, name), np.float64)
            if value.shape != (n,):
                raise InputError(f"PairRecords.{name}: expected shape ({n},), got {value.shape}")
            setattr(self, name, value)
        self.expert_label = _optional_strings(self.expert_label, "expert_label", n, LABELS)
        self.harm = _optional_strings(self.harm, "harm", n, HARMS)
        if self.no is not None:
            self.no = int_column(self.no, "PairRecords.no", (n,))

    @classmethod
    def from_pairs(
        cls,
        pairs: PathPairs,
        *,
        label,
        attack,
        label_source="rule",
        score=None,
        dh=None,
        dv=None,
        pair_index=None,
        harm=None,
    ) -> PairRecords:
        """Records of `pairs` (a `PairSet`, any `PathPairs`) plus their labels; `pair_index` defaults to `0..n-1`.

        `harm`: a `vinadv.classify.harm.PairHarm`-like object (read by field name), or None (the harm columns stay
        NULL).
        """
        return cls(
            pair_index=np.arange(len(pairs)) if pair_index is None else pair_index,
            label=label,
            attack=attack,
            label_source=label_source,
            score=score,
            dh=dh,
            dv=dv,
            **{f.name: getattr(pairs, f.name) for f in fields(PathPairs)},  # the pairs as they are
            **({} if harm is None else {name: getattr(harm, name) for name in HARM_COLUMNS}),
        )

    def equals(self, other: PairRecords) -> bool:
        """Same rows, field by field (NaN floats compare equal; `no` is ignored)."""
        for f in fields(self):
            if f.name == "no":
                continue
            a, b = getattr(self, f.name), getattr(other, f.name)
            if a is None or b is None:
                if a is not b:
                    return False
            elif isinstance(a, PackedPaths):
                if a != b:
                    return False
            elif a.shape != b.shape or not np.array_equal(a, b, equal_nan=a.dtype.kind == "f"):
                return False
        return True


def _strings(value, name: str, n: int) -> np.ndarray:
    if isinstance(value, str):
        return np.full(n, value, dtype=object)
    arr = np.asarray(value, dtype=object)
    if arr.shape != (n,):
        raise InputError(f"PairRecords.{name}: expected shape ({n},), got {arr.shape}")
    return arr.astype(str).astype(object)


def _optional_strings(value, name: str, n: int, allowed: tuple[str, ...]) -> np.ndarray:
    """`(n,)` object array of str or None (NULL); None for the whole column when `value` is None."""
    if value is None:
        return np.full(n, None, dtype=object)
    arr = np.asarray(value, dtype=object)
    if arr.shape != (n,):
        raise InputError(f"PairRecords.{name}: expected shape ({n},), got {arr.shape}")
    null = np.equal(arr, None)
    values = arr[~null].astype(str)
    bad = ~np.isin(values, allowed)
    if bad.any():
        raise InputError(f"PairRecords.{name}: '{values[bad][0]}' is not one of {'|'.join(allowed)}")
    arr[~null] = values.astype(object)
    return arr
