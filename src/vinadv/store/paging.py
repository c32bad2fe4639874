"""Keyset paging through a run's stored pairs (the viewer), sorted by pair index or by a pair's label, harm, regret
added or search effort, and the indexes that make every page by pair index one range read.

A page is asked for by the pair it follows (`after`) or precedes (`before`), whatever the sort: the sort key of that
pair is read back (one row by the unique `(run_id, pair_index)`) and the page is the pairs whose `(key, pair_index)`
comes after (before) it. Every key is two non-NULL parts, `(missing, value)`, so a pair without the value (harm not
computed, no expansions reported) sorts last and the comparison stays a plain tuple comparison on every backend.

The search effort (DESIGN.md "Search effort") is read where the database holds the planner's expanded cells
(`map_pairs.expanded_o`, `expanded_a`: path text, one comma per cell): the number of cells and their ratio are
computed in SQL, so no page decodes a cell list. A database without those columns pages as before, with no effort.
"""

from __future__ import annotations

import functools

import sqlalchemy as sa

from vinadv.errors import InputError
from vinadv.store.connection import Database
from vinadv.store.schema import map_pairs
from vinadv.vocabulary import HARMS, LABELS

#: the sort orders of `page_pairs`: pair index; label in DESIGN.md order; harm (harmful first); regret added by the
#: attack (`regret_a - regret_o`, largest first); search effort (`expansions_a / expansions_o`, largest first)
SORTS = ("pair", "label", "harm", "regret", "effort")
#: the columns of a planner's expanded cells (schema version 8; absent from older databases)
EXPANDED_COLUMNS = ("expanded_o", "expanded_a")


def _column(name: str) -> sa.ColumnElement:
    """`map_pairs.<name>`, also where this version of the schema does not declare it (the expanded cells)."""
    return map_pairs.c[name] if name in map_pairs.c else sa.column(name, sa.Text())


def _cell_count(name: str) -> sa.ColumnElement:
    """The number of cells in the path text column `name` (one comma each), NULL where it holds none."""
    text = _column(name)
    count = sa.func.length(text) - sa.func.length(sa.func.replace(text, ",", ""))
    return sa.case((sa.func.coalesce(sa.func.length(text), 0) == 0, sa.null()), else_=count)


def _constant(value) -> sa.ColumnElement:
    """`value` for every row as an expression of the row: a bare constant in ORDER BY is a column position on MySQL."""
    return sa.case((map_pairs.c.pair_index.is_(None), value), else_=value)


def _order(values: tuple[str, ...], column: sa.ColumnElement) -> sa.ColumnElement:
    """The position of `column`'s value in `values` (len(values) for any other)."""
    return sa.case({v: i for i, v in enumerate(values)}, value=column, else_=len(values))


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

    @functools.cached_property
    def has_expansions(self) -> bool:
        """Whether the database's pairs can hold a planner's expanded cells (`EXPANDED_COLUMNS`)."""
        with self.engine.connect() as conn:
            have = {c["name"] for c in sa.inspect(conn).get_columns(map_pairs.name)}
        return set(EXPANDED_COLUMNS) <= have

    def sort_keys(self) -> tuple[str, ...]:
        """The sorts `page_pairs` takes on this database (`SORTS`; `effort` only where pairs can hold expansions)."""
        return SORTS if self.has_expansions else tuple(s for s in SORTS if s != "effort")

    def run_has_expansions(self, run_id: int) -> bool:
        """Whether some stored pair of the run holds its planner's expanded cells (a search planner's run)."""
        if not self.has_expansions:
            return False
        c = map_pairs.c
        with self.engine.connect() as conn:
            found = conn.execute(
                sa.select(c.pair_index).where(c.run_id == int(run_id), _column("expanded_o").is_not(None)).limit(1)
            ).first()
        return found is not None

    def _sort_key(self, sort: str) -> tuple[sa.ColumnElement, sa.ColumnElement, bool]:
        """`(missing, value, descending)` of a sort: `missing` 1 for a pair without the value, else 0."""
        c = map_pairs.c
        absent = self.absent_columns
        if sort == "label":
            return _constant(0), _order(LABELS, c.label), False
        if sort == "harm":
            if "harm" in absent:
                return _constant(1), _constant(0), False
            return sa.case((c.harm.is_(None), 1), else_=0), _order(HARMS, c.harm), False
        if sort == "regret":
            if absent & {"regret_o", "regret_a"}:
                return _constant(1), _constant(0.0), True
            change = c.regret_a - c.regret_o
            return sa.case((change.is_(None), 1), else_=0), sa.func.coalesce(change, 0.0), True
        if sort == "effort":
            ratio = sa.cast(_cell_count("expanded_a"), sa.Double()) / _cell_count("expanded_o")
            return sa.case((ratio.is_(None), 1), else_=0), sa.func.coalesce(ratio, 0.0), True
        raise InputError(f"sort: {sort!r} is not one of {'|'.join(self.sort_keys())}", "sort")

    def page_pairs(
        self,
        run_id: int,
        *,
        label: str | None = None,
        attack: bool | None = None,
        label_source: str | None = None,
        harm: str | None = None,
        min_regret: float | None = None,
        min_effort: float | None = None,
        sort: str = "pair",
        after: int | None = None,
        before: int | None = None,
        limit: int = 50,
    ) -> list[dict]:
        """One page of the run's pairs, without maps and paths, in the order of `sort` (`SORTS`), ties by pair index
        (keyset paging).

        `after`/`before`: only pairs after/before that pair in this order (`before` returns the `limit` pairs just
        before it, still in order); a pair that is not stored is refused (InputError) unless the order is by pair
        index. Filters are exact matches, but for `min_regret` (regret added, `regret_a - regret_o`, at least this)
        and `min_effort` (effort ratio at least this). Each dict: pair_index, label, attack, label_source, score, dh,
        dv, term_o, term_a, added_obstacle, harm, regret_o, regret_a, expansions_o, expansions_a (None where not
        stored). Ordered by pair index, with the (run_id, <filter>, pair_index) indexes every page is one index range
        read, however deep; another order reads and sorts the run's (filtered) pairs, a few ms per 5,000.
        """
        if sort not in self.sort_keys():
            raise InputError(f"sort: {sort!r} is not one of {'|'.join(self.sort_keys())}", "sort")
        if min_effort is not None and not self.has_expansions:
            raise InputError(f"min_effort: database {self.url} holds no search effort", "min_effort")
        c = map_pairs.c
        harm_columns = [
            sa.null().label(name) if name in self.absent_columns else c[name]
            for name in ("harm", "regret_o", "regret_a")
        ]
        effort_columns = [
            _cell_count(f"expanded_{side}").label(f"expansions_{side}")
            if self.has_expansions
            else sa.null().label(f"expansions_{side}")
            for side in ("o", "a")
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
            *effort_columns,
        ).where(*self._filters(run_id, label, attack, label_source, harm, min_regret, min_effort))
        if sort == "pair":
            if after is not None:
                query = query.where(c.pair_index > int(after))
            if before is not None:
                query = query.where(c.pair_index < int(before))
            order = [c.pair_index.desc() if before is not None else c.pair_index]
        else:
            missing, value, descending = self._sort_key(sort)
            cursor = after if after is not None else before
            if cursor is not None:
                query = query.where(self._beyond(run_id, sort, int(cursor), forward=after is not None))
            # `before` reads backwards from the cursor: every part's direction flips
            backwards = before is not None
            value_order = value.desc() if descending != backwards else value.asc()
            order = [
                missing.desc() if backwards else missing.asc(),
                value_order,
                c.pair_index.desc() if backwards else c.pair_index.asc(),
            ]
        with self.engine.connect() as conn:
            rows = [dict(r) for r in conn.execute(query.order_by(*order).limit(int(limit))).mappings()]
        for row in rows:
            row["attack"] = bool(row["attack"])
        return rows[::-1] if before is not None else rows

    def _filters(self, run_id, label, attack, label_source, harm, min_regret, min_effort) -> list:
        c = map_pairs.c
        where = [c.run_id == int(run_id)]
        if label is not None:
            where.append(c.label == label)
        if attack is not None:
            where.append(c.attack == (sa.true() if attack else sa.false()))
        if label_source is not None:
            where.append(c.label_source == label_source)
        if harm is not None:
            where.append(sa.false() if "harm" in self.absent_columns else c.harm == harm)
        if min_regret is not None:
            if self.absent_columns & {"regret_o", "regret_a"}:
                where.append(sa.false())
            else:
                where.append(c.regret_a - c.regret_o >= float(min_regret))
        if min_effort is not None:
            ratio = sa.cast(_cell_count("expanded_a"), sa.Double()) / _cell_count("expanded_o")
            where.append(ratio >= float(min_effort))
        return where

    def _beyond(self, run_id: int, sort: str, cursor: int, *, forward: bool) -> sa.ColumnElement:
        """The pairs after (`forward`) or before the pair `cursor` in the order of `sort`."""
        c = map_pairs.c
        missing, value, descending = self._sort_key(sort)
        with self.engine.connect() as conn:
            row = conn.execute(sa.select(missing, value).where(c.run_id == int(run_id), c.pair_index == cursor)).first()
        if row is None:
            raise InputError(f"{'after' if forward else 'before'}: run {run_id} has no pair {cursor}", "cursor")
        m, v = row

        def later(expr, bound, desc):  # comes after `bound` in the order (of a part sorted `desc`)
            return expr < bound if desc != (not forward) else expr > bound

        return sa.or_(
            later(missing, m, False),
            sa.and_(missing == m, later(value, v, descending)),
            sa.and_(missing == m, value == v, later(c.pair_index, cursor, False)),
        )

    def pair_expansions(self, run_id: int, pair_indices) -> dict[int, tuple[str | None, str | None]]:
        """The planner's expanded cells of the run's pairs `pair_indices` on the original and the adversarial map as
        stored (path text, `vinadv.store.codec.decode_paths`), in one read: `{pair_index: (text_o, text_a)}`, None
        for each that holds none; empty for a database without expansions (and for pairs not stored)."""
        if not self.has_expansions:
            return {}
        c = map_pairs.c
        query = sa.select(c.pair_index, _column("expanded_o"), _column("expanded_a")).where(
            c.run_id == int(run_id), c.pair_index.in_([int(i) for i in pair_indices])
        )
        with self.engine.connect() as conn:
            rows = conn.execute(query).all()
        return {int(i): (o or None, a or None) for i, o, a in rows}
