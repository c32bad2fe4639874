"""`Columns`: the one implementation of subsetting (`take`) and concatenation (`concat`) for vinadv's row types.

A row type is a dataclass whose fields hold one entry per row (a plan, a map pair, a stored record): NumPy arrays
with the rows on axis 0, `PackedPaths` (one path per row), or another `Columns` (say, the pairs of an
identification). Writing `take`/`concat` once here keeps the row types from each growing their own copy.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import fields
from typing import ClassVar

import numpy as np

from vinadv.errors import InputError


class Columns:
    """Base for dataclasses whose fields are columns of n rows.

    Fields, told apart by value:
      - a NumPy array, rows on axis 0: indexed, `np.concatenate`d;
      - an object with `take` and a classmethod `concat` (`PackedPaths`, another `Columns`): delegated to it;
      - None: an absent optional column; it stays None (and is None after `concat` if any part lacks it);
      - a field named in `META` (class attribute): not per row (a strategy name, a map side); `take` keeps it,
        `concat` keeps the parts' common value and refuses parts that disagree, unless the caller gives it.
    Construction goes through the class's own `__init__` (so its checks run on every result).
    """

    META: ClassVar[tuple[str, ...]] = ()

    def __len__(self) -> int:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name not in self.META and value is not None:
                return len(value)
        return 0

    def take(self, index):
        """The rows at `index` (int array, bool mask or slice), in that order, as a new object of this type."""
        idx = np.arange(len(self))[index]
        values = {}
        for f in fields(self):
            if not f.init:
                continue
            value = getattr(self, f.name)
            if f.name in self.META:
                values[f.name] = copy.copy(value)
            elif value is None:
                values[f.name] = None
            elif isinstance(value, np.ndarray):
                values[f.name] = value[idx]
            else:
                values[f.name] = value.take(idx)
        return type(self)(**values)

    #: the old name of `take`, still called by the report and viewer code (owned elsewhere); new code uses `take`
    subset = take

    @classmethod
    def concat(cls, parts: Sequence, **meta):
        """The rows of `parts` (objects of this type), in order. `meta`: values for `META` fields, which then
        need not agree across parts. With no parts: `cls.empty(**meta)` (where a type needs more to be empty, a map
        side say, the caller passes it here)."""
        parts = list(parts)
        if not parts:
            return cls.empty(**meta)
        unknown = set(meta) - set(cls.META)
        if unknown:
            raise InputError(f"{cls.__name__}.concat: {sorted(unknown)} are not among its settings {list(cls.META)}")
        values = {}
        for f in fields(cls):
            if not f.init:
                continue
            column = [getattr(p, f.name) for p in parts]
            if f.name in cls.META:
                if f.name not in meta and any(c != column[0] for c in column[1:]):
                    raise InputError(f"{cls.__name__}.concat: the parts differ in {f.name}")
                values[f.name] = meta.get(f.name, column[0])
            elif any(c is None for c in column):
                values[f.name] = None
            elif isinstance(column[0], np.ndarray):
                values[f.name] = np.concatenate(column)
            else:
                values[f.name] = type(column[0]).concat(column)
        return cls(**values)

    @classmethod
    def empty(cls, **meta):
        """No rows. Types whose empty form needs more (a map side) override this with the arguments they need."""
        raise InputError(f"{cls.__name__}.concat: nothing to concatenate")
