"""`PairRecords`: a batch of identified map pairs as columnar NumPy arrays — what the store writes and reads."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from vinadv.errors import InputError
from vinadv.store.schema import HARM_COLUMNS, HARM_FLOAT_COLUMNS, HARMS, LABELS

TERMINATIONS = ("goal", "collision", "loop", "step_limit")


@dataclass
class PairRecords:
    """n identified map pairs, one row each of the `map_pairs` table.

    Shapes (n pairs, N x N maps; cells are (row, col)):
      pair_index (n,) int64 — position of the pair in its run, unique per run (the resume key)
      obstacles_o, obstacles_a (n, N, N) bool — original and adversarial map, True = obstacle
      starts, goals, added (n, 2) int64 — start, goal, the added obstacle cell
      path_o_cells, path_a_cells (total, 2) int16 and path_o_offsets, path_a_offsets (n + 1,) int64 —
        planned paths packed as in `vinadv.grid.paths`
      label (n,) str in 'invalid|UrP|UcP|DP|FP'; attack (n,) bool (success: UrP or FP)
      term_o, term_a (n,) str — why each path ended: 'goal|collision|loop|step_limit'
      label_source (n,) str — who labelled it ('rule', a classifier name, ...); a single str is broadcast
      score (n,) float64 — classifier score, NaN = none (NULL)
      dh, dv (n,) int64 — horizontal / vertical path distance, -1 = not applicable (NULL)
      opt_cost_o, opt_cost_a, cost_o, cost_a, regret_o, regret_a (n,) float64 — harm costs in move units
        (DESIGN.md "Harm"), NaN = none (NULL)
      expert_label (n,) object, 'invalid|UrP|UcP|DP|FP' or None; harm (n,) object, 'harmful|harmless|invalid' or
        None (None = not computed, NULL)
      no (n,) int64 or None — the table's global sequence number; filled when read back, ignored on write
    """

    pair_index: np.ndarray
    obstacles_o: np.ndarray
    obstacles_a: np.ndarray
    starts: np.ndarray
    goals: np.ndarray
    added: np.ndarray
    path_o_cells: np.ndarray
    path_o_offsets: np.ndarray
    path_a_cells: np.ndarray
    path_a_offsets: np.ndarray
    label: np.ndarray
    attack: np.ndarray
    term_o: np.ndarray
    term_a: np.ndarray
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
        n = len(np.asarray(self.pair_index).reshape(-1))
        self.pair_index = _ints(self.pair_index, "pair_index", (n,))
        self.obstacles_o = np.asarray(self.obstacles_o, dtype=bool)
        self.obstacles_a = np.asarray(self.obstacles_a, dtype=bool)
        size = self.obstacles_o.shape[-1] if self.obstacles_o.ndim == 3 else -1
        for name in ("obstacles_o", "obstacles_a"):
            arr = getattr(self, name)
            if arr.shape != (n, size, size):
                raise InputError(f"PairRecords.{name}: expected shape ({n}, N, N), got {arr.shape}")
        for name in ("starts", "goals", "added"):
            setattr(self, name, _ints(getattr(self, name), name, (n, 2)))
        for side in ("o", "a"):
            cells = np.asarray(getattr(self, f"path_{side}_cells")).reshape(-1, 2).astype(np.int16)
            offsets = _ints(getattr(self, f"path_{side}_offsets"), f"path_{side}_offsets", (n + 1,))
            if offsets[0] != 0 or offsets[-1] != len(cells) or (np.diff(offsets) < 0).any():
                raise InputError(f"PairRecords.path_{side}_offsets: must run from 0 to {len(cells)} without decreasing")
            setattr(self, f"path_{side}_cells", cells)
            setattr(self, f"path_{side}_offsets", offsets)
        self.label = _strings(self.label, "label", n)
        bad = ~np.isin(self.label, LABELS)
        if bad.any():
            raise InputError(f"PairRecords.label: {self.label[bad][0]!r} is not one of {'|'.join(LABELS)}")
        attack = np.asarray(self.attack)
        if attack.shape != (n,):
            raise InputError(f"PairRecords.attack: expected shape ({n},), got {attack.shape}")
        self.attack = attack.astype(bool)
        for name in ("term_o", "term_a"):
            setattr(self, name, _strings(getattr(self, name), name, n))
        self.label_source = _strings(self.label_source, "label_source", n)
        self.score = np.full(n, np.nan) if self.score is None else np.asarray(self.score, dtype=np.float64)
        if self.score.shape != (n,):
            raise InputError(f"PairRecords.score: expected shape ({n},), got {self.score.shape}")
        for name in ("dh", "dv"):
            value = getattr(self, name)
            setattr(self, name, np.full(n, -1, np.int64) if value is None else _ints(value, name, (n,)))
        for name in HARM_FLOAT_COLUMNS:
            value = np.full(n, np.nan) if getattr(self, name) is None else np.asarray(getattr(self, name), np.float64)
            if value.shape != (n,):
                raise InputError(f"PairRecords.{name}: expected shape ({n},), got {value.shape}")
            setattr(self, name, value)
        self.expert_label = _optional_strings(self.expert_label, "expert_label", n, LABELS)
        self.harm = _optional_strings(self.harm, "harm", n, HARMS)
        if self.no is not None:
            self.no = _ints(self.no, "no", (n,))

    def __len__(self) -> int:
        return len(self.pair_index)

    @property
    def size(self) -> int:
        """Map side N."""
        return self.obstacles_o.shape[-1]

    def subset(self, indices: np.ndarray) -> PairRecords:
        """The records at `indices` (positions in this batch, or a boolean mask), in that order."""
        idx = np.arange(len(self))[np.asarray(indices)]
        return PairRecords(
            **{f.name: getattr(self, f.name)[idx] for f in fields(self) if _is_row_field(f.name, self)},
            **_subset_paths(self, idx),
        )

    @classmethod
    def concatenate(cls, parts: list[PairRecords]) -> PairRecords:
        """Rows of all `parts`, in order."""
        if not parts:
            raise InputError("PairRecords.concatenate: nothing to concatenate")
        kwargs = {}
        for f in fields(cls):
            if f.name.startswith("path_"):
                continue
            values = [getattr(p, f.name) for p in parts]
            kwargs[f.name] = None if any(v is None for v in values) else np.concatenate(values)
        for side in ("o", "a"):
            cells = np.concatenate([getattr(p, f"path_{side}_cells") for p in parts])
            lengths = np.concatenate([np.diff(getattr(p, f"path_{side}_offsets")) for p in parts])
            kwargs[f"path_{side}_cells"] = cells
            kwargs[f"path_{side}_offsets"] = np.concatenate([[0], np.cumsum(lengths)])
        return cls(**kwargs)

    @classmethod
    def from_pairs(cls, pairs, *, label, attack, label_source="rule", score=None, dh=None, dv=None,
                   pair_index=None, harm=None) -> PairRecords:
        """Records from a `vinadv.attacks.pairs.PairSet`-like object (read by field name) plus its labels.

        `pair_index` defaults to `0..n-1`. `harm`: a `vinadv.classify.harm.PairHarm`-like object (read by field
        name), or None (the harm columns stay NULL).
        """
        n = len(pairs.starts)
        return cls(
            pair_index=np.arange(n) if pair_index is None else pair_index,
            obstacles_o=pairs.obstacles_o, obstacles_a=pairs.obstacles_a,
            starts=pairs.starts, goals=pairs.goals, added=pairs.added,
            path_o_cells=pairs.path_o_cells, path_o_offsets=pairs.path_o_offsets,
            path_a_cells=pairs.path_a_cells, path_a_offsets=pairs.path_a_offsets,
            label=label, attack=attack, term_o=pairs.term_o, term_a=pairs.term_a,
            label_source=label_source, score=score, dh=dh, dv=dv,
            **({} if harm is None else {name: getattr(harm, name) for name in HARM_COLUMNS}),
        )

    def equals(self, other: PairRecords) -> bool:
        """Same rows, field by field (NaN scores compare equal; `no` is ignored)."""
        for f in fields(self):
            if f.name == "no":
                continue
            a, b = getattr(self, f.name), getattr(other, f.name)
            if a.shape != b.shape:
                return False
            if a.dtype.kind == "f":
                if not np.array_equal(a, b, equal_nan=True):
                    return False
            elif not np.array_equal(a, b):
                return False
        return True


def _is_row_field(name: str, records: PairRecords) -> bool:
    return not name.startswith("path_") and getattr(records, name) is not None


def _subset_paths(records: PairRecords, idx: np.ndarray) -> dict:
    out = {}
    for side in ("o", "a"):
        cells = getattr(records, f"path_{side}_cells")
        offsets = getattr(records, f"path_{side}_offsets")
        lengths = np.diff(offsets)[idx]
        new_offsets = np.zeros(len(idx) + 1, dtype=np.int64)
        np.cumsum(lengths, out=new_offsets[1:])
        # gather cell positions of the chosen paths without a loop over pairs
        take = np.repeat(offsets[:-1][idx] - new_offsets[:-1], lengths) + np.arange(new_offsets[-1])
        out[f"path_{side}_cells"] = cells[take]
        out[f"path_{side}_offsets"] = new_offsets
    return out


def _ints(value, name: str, shape: tuple) -> np.ndarray:
    arr = np.asarray(value)
    if arr.shape != shape:
        raise InputError(f"PairRecords.{name}: expected shape {shape}, got {arr.shape}")
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        raise InputError(f"PairRecords.{name}: expected integers, got {arr.dtype}")
    return arr.astype(np.int64)


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


def _strings(value, name: str, n: int) -> np.ndarray:
    if isinstance(value, str):
        return np.full(n, value, dtype=object)
    arr = np.asarray(value, dtype=object)
    if arr.shape != (n,):
        raise InputError(f"PairRecords.{name}: expected shape ({n},), got {arr.shape}")
    return arr.astype(str).astype(object)
