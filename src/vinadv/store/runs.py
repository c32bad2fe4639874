"""The runs of a `Store`: one row per job (`runs`), and how many of its shards are completely stored."""

from __future__ import annotations

import unicodedata

import sqlalchemy as sa

from vinadv import __version__
from vinadv.errors import InputError
from vinadv.grid.moves import DEFAULT_MOVES, move_model
from vinadv.records import upgrade_run_config
from vinadv.store.connection import Database, utcnow
from vinadv.store.schema import exact_collation, map_pairs, meta_table, runs

#: the longest run name, in characters: the `runs.name` column's length, which MariaDB and PostgreSQL enforce
MAX_NAME_LENGTH = runs.c.name.type.length


def check_run_name(name: str) -> str:
    """Refuse (InputError naming `name`) what cannot be a run name, before anything is written: a name is found
    again exactly as given, so it has no leading or trailing whitespace and no control characters (a name that
    shows as another); it needs a letter (`resolve_run` reads a number as a run id) and holds at most
    `MAX_NAME_LENGTH` characters (what every backend stores). Returns `name`."""
    if not isinstance(name, str):
        raise InputError(f"name: a run name is text, got {type(name).__name__}", "name")
    shown = repr(name) if len(name) <= 60 else repr(name[:40]) + f"... ({len(name):,} characters)"
    if len(name) > MAX_NAME_LENGTH:
        raise InputError(f"name: {shown} is longer than {MAX_NAME_LENGTH} characters", "name")
    if not name.strip() or name.strip().isdigit():
        raise InputError(f"name: {shown} cannot be a run name (a name needs a letter; numbers are run ids)", "name")
    if name != name.strip():
        raise InputError(f"name: {shown} starts or ends with whitespace; give the name without it", "name")
    odd = next((c for c in name if unicodedata.category(c) in _UNSHOWN), None)
    if odd is not None:
        what = _UNSHOWN[unicodedata.category(odd)]
        raise InputError(f"name: {shown} holds U+{ord(odd):04X} ({what}), which a run name may not", "name")
    return name


#: Unicode categories a run name may not hold: characters that show as nothing or as another, or cannot be stored
_UNSHOWN = {
    "Cc": "a control character",
    "Cs": "a lone surrogate: bytes that are not UTF-8",
    "Zl": "a line separator",
    "Zp": "a paragraph separator",
}


class RunQueries(Database):
    """Create, find and finish runs (a part of `Store`)."""

    def create_run(
        self,
        name: str | None = None,
        *,
        config: dict | None = None,
        seed: int | None = None,
        weights_checksum: str | None = None,
        attack: str | None = None,
        classifier: str | None = None,
        version: str = __version__,
        status: str = "running",
        moves: str = DEFAULT_MOVES,
    ) -> int:
        """Insert a run and return its id. A `name` is unique in a database (`--resume` finds a run by it) and
        follows `check_run_name`: InputError otherwise. `moves`: the movement model of the run's maps
        (`vinadv.grid.moves`), stored in `runs.moves`."""
        moves = move_model(moves).name
        self.refuse_outdated(["moves"])
        if name is not None:
            check_run_name(name)
            found = self.find_run(name)
            if found is not None:
                raise InputError(
                    f"name: run {found} in database {self.url} is already called {name!r}; "
                    "continue it with resume, or choose another name",
                    "name",
                    "resume",
                    "name",
                )
        return self.insert_row(
            runs,
            name=name,
            created=utcnow(),
            config=config,
            seed=None if seed is None else int(seed),
            weights_checksum=weights_checksum,
            attack=attack,
            classifier=classifier,
            version=version,
            timings=None,
            status=status,
            moves=moves,
        )

    def find_run(self, name: str) -> int | None:
        """The id of the latest run called exactly `name` (for `--resume`), or None: on MySQL/MariaDB compared under
        the `exact_collation` (the column's from schema version 5 on; named here too, so a version 4 database
        opened read-only compares exactly as well)."""
        collation = exact_collation(self.engine.dialect)
        column = runs.c.name if collation is None else runs.c.name.collate(collation)
        with self.engine.connect() as conn:
            found = conn.execute(
                sa.select(runs.c.id).where(column == name).order_by(runs.c.id.desc()).limit(1)
            ).scalar_one_or_none()
        return None if found is None else int(found)

    def resolve_run(self, ref: str | int, param: str = "run_id") -> int:
        """The id of the run `ref` names: the one rule for every run reference. A number is a run id (a run name is
        never a number, see `create_run`), anything else a run name (its latest run), looked up exactly as given,
        then, when no run has that exact name, without the whitespace around it (a stored name with whitespace,
        which `check_run_name` refuses for a new run: 'x ' is found by 'x ', and 'x' by ' x '). InputError (naming the
        parameter `param`) when there is no such run."""
        text = str(ref)
        if text.strip().isascii() and text.strip().isdigit():  # not '²': a digit to isdigit, no number to int
            text = text.strip()
            found = None
            if int(text) < 2**63:  # a larger number is no id (and no SQL integer)
                with self.engine.connect() as conn:
                    found = conn.execute(sa.select(runs.c.id).where(runs.c.id == int(text))).scalar_one_or_none()
            if found is None:
                raise InputError(f"{param}: no run {text} in database {self.url}", param)
            return int(text)
        found = self.find_run(text) if text else None
        if found is None and text.strip() and text.strip() != text:
            found = self.find_run(text.strip())
        if found is None:
            raise InputError(f"{param}: no run named {text!r} in database {self.url} (give a run id or name)", param)
        return found

    def run_info(self, run_id: int) -> dict:
        """The run's row as a dict; `InputError` when there is no such run. Its `moves` is the run's movement
        model: `octile` where it is NULL (a run of schema version 5 or below, or no column in such a database
        opened read-only)."""
        with self.engine.connect() as conn:
            row = conn.execute(sa.select(*self._run_columns()).where(runs.c.id == int(run_id))).mappings().one_or_none()
        if row is None:
            raise InputError(f"run_id: no run {run_id} in database {self.url}", "run_id")
        return _run_row(row)

    def run_moves(self, run_id: int) -> str:
        """The movement model of the run (`run_info`'s `moves`)."""
        return self.run_info(run_id)["moves"]

    def _run_columns(self) -> list:
        """The `runs` columns to select: a column an older database lacks (read-only) reads as NULL."""
        return [sa.null().label(c.name) if c.name in self.absent_columns else c for c in runs.columns]

    def list_runs(self, with_counts: bool = True) -> list[dict]:
        """All runs, oldest first, each with its stored pair count (`n_pairs`) unless `with_counts` is False
        (counting reads every pair's index entry: ~0.1 s per million pairs on SQLite)."""
        if not with_counts:
            with self.engine.connect() as conn:
                query = sa.select(*self._run_columns()).order_by(runs.c.id)
                return [_run_row(r) for r in conn.execute(query).mappings()]
        counts = sa.select(map_pairs.c.run_id, sa.func.count().label("n_pairs")).group_by(map_pairs.c.run_id).subquery()
        query = (
            sa.select(*self._run_columns(), sa.func.coalesce(counts.c.n_pairs, 0).label("n_pairs"))
            .select_from(runs.outerjoin(counts, counts.c.run_id == runs.c.id))
            .order_by(runs.c.id)
        )
        with self.engine.connect() as conn:
            return [_run_row(r) for r in conn.execute(query).mappings()]

    def finish_run(self, run_id: int, timings: dict | None = None, status: str = "done") -> None:
        """Record the run's timings (seconds per stage) and final status."""
        self._update_run(run_id, timings=timings, status=status)

    def set_run_status(self, run_id: int, status: str) -> None:
        """Record the run's status alone: "running" again when resumed, "interrupted" (Ctrl-C, SIGTERM) or
        "failed" (its planner broke the contract) when it stopped part way."""
        self._update_run(run_id, status=status)

    def _update_run(self, run_id: int, **values) -> None:
        with self.engine.begin() as conn:
            updated = conn.execute(runs.update().where(runs.c.id == int(run_id)).values(**values)).rowcount
        if updated != 1:
            raise InputError(f"run_id: no run {run_id} in database {self.url}", "run_id")

    def shards_done(self, run_id: int) -> int:
        """How many shards of the run are completely stored, from shard 0 on (0 when none recorded)."""
        with self.engine.connect() as conn:
            value = conn.execute(
                sa.select(meta_table.c.value).where(meta_table.c.key == _shards_key(run_id))
            ).scalar_one_or_none()
        return int(value) if value is not None else 0

    def set_shards_done(self, run_id: int, shards: int) -> None:
        """Record that shards `0 .. shards-1` of the run are completely stored (`--resume` skips them)."""
        key = _shards_key(run_id)
        for attempt in range(2):  # again only when another writer of the run (a concurrent resume) inserted it
            try:
                with self.engine.begin() as conn:
                    updated = conn.execute(
                        meta_table.update().where(meta_table.c.key == key).values(value=str(int(shards)))
                    ).rowcount
                    if not updated:
                        conn.execute(meta_table.insert().values(key=key, value=str(int(shards))))
                return
            except sa.exc.IntegrityError:
                if attempt:
                    raise


def _run_row(row) -> dict:
    """A `runs` row as a dict: its `config` in today's form (`vinadv.records.upgrade_run_config`), its `moves`
    `octile` where NULL (the column's value in the rows of schema versions 1 to 5)."""
    info = dict(row)
    info["config"] = upgrade_run_config(info["config"])
    info["moves"] = info["moves"] or DEFAULT_MOVES
    return info


def _shards_key(run_id: int) -> str:
    """The `vinadv_meta` key of a run's stored-shard count (in the meta table: no schema change)."""
    return f"run:{int(run_id)}:shards_done"
