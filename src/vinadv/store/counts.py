"""Counts and light reads of a `Store`'s pairs, without maps and paths: one GROUP BY or one column each (the
report's tables and the viewer's run list)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import sqlalchemy as sa

from vinadv.errors import InputError
from vinadv.store.connection import Database
from vinadv.store.schema import LABELS, map_pairs
from vinadv.vocabulary import FORK_OR_DETOUR

#: cost units per grouping step of `CountQueries.regret_changes` (1e-6: far below the gap between two distinct costs)
_MICRO = 1_000_000


class CountQueries(Database):
    """Count a run's stored pairs by label, outcome, termination and harm (a part of `Store`)."""

    def _group_counts(self, run_id: int, *keys: sa.ColumnElement) -> list[sa.Row]:
        """The run's stored pairs counted per value of the `map_pairs` columns `keys`, in one GROUP BY: rows
        `(*values, count)`, one per combination present."""
        with self.engine.connect() as conn:
            return conn.execute(
                sa.select(*keys, sa.func.count()).where(map_pairs.c.run_id == int(run_id)).group_by(*keys)
            ).all()

    def label_counts(self, run_id: int) -> dict[str, int]:
        """Stored pairs per label, every label present (0 where none), in DESIGN.md order."""
        counts = {label: 0 for label in LABELS}
        counts.update({label: int(k) for label, k in self._group_counts(run_id, map_pairs.c.label)})
        return counts

    def attack_counts(self, run_id: int) -> dict[bool, int]:
        """Stored pairs per attack outcome: {True: successful, False: not}."""
        counts = {True: 0, False: 0}
        counts.update({bool(a): int(k) for a, k in self._group_counts(run_id, map_pairs.c.attack)})
        return counts

    def label_counts_by_run(self) -> dict[int, dict[str, int]]:
        """Stored pairs per label of every run, in one query: {run_id: {label: n}} (every label present)."""
        with self.engine.connect() as conn:
            rows = conn.execute(
                sa.select(map_pairs.c.run_id, map_pairs.c.label, sa.func.count()).group_by(
                    map_pairs.c.run_id, map_pairs.c.label
                )
            ).all()
        counts: dict[int, dict[str, int]] = {}
        for run_id, label, k in rows:
            counts.setdefault(int(run_id), {lab: 0 for lab in LABELS})[label] = int(k)
        return counts

    def harm_counts_by_run(self) -> dict[int, dict[str | None, int]]:
        """Stored pairs per harm of every run, in one GROUP BY: {run_id: {harm: n}}, only the values present (None:
        not computed; every pair of a version-1 database opened read-only)."""
        c = map_pairs.c
        keys = (c.run_id,) if "harm" in self.absent_columns else (c.run_id, c.harm)
        with self.engine.connect() as conn:
            rows = conn.execute(sa.select(*keys, sa.func.count()).group_by(*keys)).all()
        counts: dict[int, dict[str | None, int]] = {}
        for row in rows:
            counts.setdefault(int(row[0]), {})[row[1] if len(keys) == 2 else None] = int(row[-1])
        return counts

    def label_sources(self, run_id: int) -> list[str]:
        """The distinct label sources of the run's pairs, sorted."""
        with self.engine.connect() as conn:
            rows = (
                conn.execute(sa.select(map_pairs.c.label_source).where(map_pairs.c.run_id == int(run_id)).distinct())
                .scalars()
                .all()
            )
        return sorted(rows)

    def pair_labels(self, run_id: int) -> tuple[np.ndarray, np.ndarray]:
        """Every stored pair of the run without maps and paths: `(pair_index int64 (n,), label object (n,))`,
        ordered by pair index (the report's and the evaluation's pair selection)."""
        with self.engine.connect() as conn:
            rows = conn.execute(
                sa.select(map_pairs.c.pair_index, map_pairs.c.label)
                .where(map_pairs.c.run_id == int(run_id))
                .order_by(map_pairs.c.pair_index)
            ).all()
        index = np.fromiter((r[0] for r in rows), dtype=np.int64, count=len(rows))
        labels = np.empty(len(rows), dtype=object)
        labels[:] = [r[1] for r in rows]
        return index, labels

    def termination_counts(self, run_id: int, side: str = "o") -> dict[str, int]:
        """Stored pairs per termination of the original (`side='o'`) or adversarial (`'a'`) path:
        {termination: n}, only those present, sorted by name."""
        if side not in ("o", "a"):
            raise InputError(f"side: {side!r} is not 'o' or 'a'")
        rows = self._group_counts(run_id, map_pairs.c[f"term_{side}"])
        return {str(term): int(k) for term, k in sorted(rows)}

    def harm_counts(self, run_id: int) -> dict[str, dict[str | None, int]]:
        """Stored pairs per (paper label, harm), in one GROUP BY: `{label: {harm: n}}`, only the combinations
        present. Harm None: not computed (NULL: a pair stored without harm, or every pair of a
        version-1 database opened read-only)."""
        c = map_pairs.c
        keys = (c.label,) if "harm" in self.absent_columns else (c.label, c.harm)
        counts: dict[str, dict[str | None, int]] = {}
        for row in self._group_counts(run_id, *keys):
            harm = row[1] if len(keys) == 2 else None
            counts.setdefault(str(row[0]), {})[harm] = int(row[-1])
        return counts

    def regret_changes(
        self, run_id: int, labels: Sequence[str] = FORK_OR_DETOUR
    ) -> dict[tuple[str, str], tuple[np.ndarray, np.ndarray]]:
        """What the attack added to the planner's regret, `regret_a - regret_o` (cost units), over the run's pairs
        with a label of `labels` whose two regrets are stored, as one GROUP BY (the report's histogram):
        `{(label, harm): (changes (k,) float64 ascending, pairs (k,) int64)}`, only the groups present.

        Changes are grouped after rounding to 1e-6 cost units: costs are sums of 1 and sqrt 2, so a run of any size
        has few distinct changes, and rounding merges the float noise of one value's different sums."""
        c = map_pairs.c
        if self.absent_columns & {"harm", "regret_o", "regret_a"}:
            return {}
        change = sa.func.round((c.regret_a - c.regret_o) * _MICRO).label("change")
        query = (
            sa.select(c.label, c.harm, change, sa.func.count())
            .where(
                c.run_id == int(run_id),
                c.label.in_(list(labels)),
                c.harm.is_not(None),
                c.regret_o.is_not(None),
                c.regret_a.is_not(None),
            )
            .group_by(c.label, c.harm, change)
        )
        with self.engine.connect() as conn:
            rows = conn.execute(query).all()
        groups: dict[tuple[str, str], list] = {}
        for label, harm, value, k in rows:
            groups.setdefault((str(label), str(harm)), []).append((float(value) / _MICRO, int(k)))
        return {
            key: (np.array([v for v, _ in part], dtype=np.float64), np.array([k for _, k in part], np.int64))
            for key, part in ((key, sorted(part)) for key, part in sorted(groups.items()))
        }
