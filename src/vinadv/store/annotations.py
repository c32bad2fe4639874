"""Human labels of stored pairs (`annotations`; the annotation tool writes them)."""

from __future__ import annotations

import numpy as np
import sqlalchemy as sa

from vinadv.errors import InputError
from vinadv.store.connection import Database, utcnow
from vinadv.store.schema import LABELS, annotations


class AnnotationQueries(Database):
    """Add and read annotations (a part of `Store`)."""

    def add_annotations(self, run_id: int, pair_indices, labels, annotator: str) -> int:
        """Store human labels for stored pairs (one row per (pair, label) given); return how many."""
        pair_indices = np.asarray(pair_indices, dtype=np.int64).reshape(-1)
        labels = np.broadcast_to(np.asarray(labels, dtype=object), pair_indices.shape)
        bad = ~np.isin(labels, LABELS)
        if bad.any():
            raise InputError(f"annotation label {labels[bad][0]!r} is not one of {'|'.join(LABELS)}")
        if not annotator:
            raise InputError("annotator: must be a non-empty name")
        if len(pair_indices) == 0:
            return 0
        now = utcnow()
        rows = [
            {"run_id": int(run_id), "pair_index": int(i), "label": str(lab), "annotator": annotator, "created": now}
            for i, lab in zip(pair_indices.tolist(), labels.tolist())
        ]
        with self.engine.begin() as conn:
            conn.execute(annotations.insert(), rows)
        return len(rows)

    def read_annotations(self, run_id: int, pair_indices=None) -> list[dict]:
        """The run's annotations (of `pair_indices` only, if given), oldest first: dicts with id, pair_index,
        label, annotator, created."""
        query = (
            sa.select(
                annotations.c.id,
                annotations.c.pair_index,
                annotations.c.label,
                annotations.c.annotator,
                annotations.c.created,
            )
            .where(annotations.c.run_id == int(run_id))
            .order_by(annotations.c.id)
        )
        if pair_indices is not None:
            query = query.where(annotations.c.pair_index.in_([int(i) for i in np.asarray(pair_indices).ravel()]))
        with self.engine.connect() as conn:
            rows = conn.execute(query).mappings().all()
        return [dict(r) for r in rows]
