"""Keyset paging through a run's stored pairs (the viewer), and the indexes that make every page one range read."""

from __future__ import annotations

import sqlalchemy as sa

from vinadv.store.connection import Database
from vinadv.store.schema import map_pairs


class PagingQueries(Database):
    """Pages of a run's pairs without maps and paths (a part of `Store`)."""

    def ensure_indexes(self) -> list[str]:
        """Create the indexes of the current schema that the database lacks (one made with fewer indexes);
        return their names. Paging stays correct without them, only slower. An index on a column the database
        does not have yet (the harm columns of a version-1 database opened without `create`) is left for later."""
        created = []
        with self.engine.begin() as conn:
            present = {ix["name"] for ix in sa.inspect(conn).get_indexes(map_pairs.name)}
            for index in sorted(map_pairs.indexes, key=lambda ix: ix.name):
                if {c.name for c in index.columns} & self.absent_columns:
                    continue
                if index.name not in present:
                    index.create(conn)
                    created.append(index.name)
        return created

    def page_pairs(
        self,
        run_id: int,
        *,
        label: str | None = None,
        attack: bool | None = None,
        label_source: str | None = None,
        harm: str | None = None,
        after: int | None = None,
        before: int | None = None,
        limit: int = 50,
    ) -> list[dict]:
        """One page of the run's pairs, without maps and paths, ordered by pair index (keyset paging).

        `after`/`before`: only pairs with a larger/smaller index (`before` returns the `limit` pairs just before
        it, still in ascending order). Filters are exact matches. Each dict: pair_index, label, attack,
        label_source, score, dh, dv, term_o, term_a, added_obstacle, harm, regret_o, regret_a. With the
        (run_id, <filter>, pair_index) indexes every page is one index range read, however deep.
        """
        c = map_pairs.c
        harm_columns = [
            sa.null().label(name) if name in self.absent_columns else c[name]
            for name in ("harm", "regret_o", "regret_a")
        ]
        query = sa.select(
            c.pair_index,
            c.label,
            c.attack,
            c.label_source,
            c.score,
            c.dh,
            c.dv,
            c.term_o,
            c.term_a,
            c.added_obstacle,
            *harm_columns,
        ).where(c.run_id == int(run_id))
        if label is not None:
            query = query.where(c.label == label)
        if attack is not None:
            query = query.where(c.attack == (sa.true() if attack else sa.false()))
        if label_source is not None:
            query = query.where(c.label_source == label_source)
        if harm is not None:
            query = query.where(sa.false() if "harm" in self.absent_columns else c.harm == harm)
        if after is not None:
            query = query.where(c.pair_index > int(after))
        if before is not None:
            query = query.where(c.pair_index < int(before))
            query = query.order_by(c.pair_index.desc())
        else:
            query = query.order_by(c.pair_index)
        with self.engine.connect() as conn:
            rows = [dict(r) for r in conn.execute(query.limit(int(limit))).mappings()]
        for row in rows:
            row["attack"] = bool(row["attack"])
        return rows[::-1] if before is not None else rows
