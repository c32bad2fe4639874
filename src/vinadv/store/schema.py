"""SQL schema of a vinadv database (SQLAlchemy 2 Core), portable to SQLite, MySQL/MariaDB and PostgreSQL.

Tables:
- `vinadv_meta` (key, value): `schema_version`, so a database of another schema is refused, not misread.
- `runs`: one row per job (config, seed, planner weights checksum, versions, timings, status).
- `map_pairs`: the paper's Table 2 (`no, map_o, map_a, path_o, path_a, label, attack`) plus what makes a row
  reproducible and queryable; `(run_id, pair_index)` is unique, so a resumed run never stores a pair twice.
- `annotations`: human labels of stored pairs (the annotation tool writes them).
- `evaluations`: classifier comparisons on a run's FP/DP pairs (`vinadv evaluate` writes them, the report reads
  them). Added after schema version 1 shipped; it is additive (no existing column changes), so `Store.open`
  creates it in an older database instead of refusing it (`ADDITIVE_TABLES`).
- `robustness`: robustness benchmarks of planners (`vinadv robustness` writes them, the report reads them): one row
  per benchmark, its settings and figures as JSON. Additive, as `evaluations`.
- `bench_chunks` (the step to schema version 7): the finished chunks of maps of a benchmark entry (`vinadv bench run
  --db --resume`), one JSON result per (entry, chunk). Additive, as `evaluations`.
- `measurements`: what the evaluation stage measures of a run besides the classifier comparison
  (`vinadv.vocabulary.MEASUREMENTS`: the planner's quality, the processing time), one JSON result per row; the
  newest row of a run and kind is the one the report shows.

Version 2 adds the harm columns of `map_pairs` (`HARM_COLUMNS`, all nullable: DESIGN.md "Harm"). Version 3 adds
`added_more` (nullable): the obstacles a pair adds after the first (`added_obstacle`), for pairs of several added
obstacles (DESIGN.md "Several obstacles"); NULL for a one-obstacle pair (its one cell is `added_obstacle`).
Version 4 adds the table `measurements` (`UPGRADE_TABLES`). Version 5 compares run names exactly on every backend:
on MySQL/MariaDB `runs.name` gets a binary collation without padding (`exact_collation`), so names differing in
case, accents, emoji or trailing spaces are different runs there too (SQLite and PostgreSQL compare bytes
already); an older MariaDB database has the column changed in place, its rows kept. Version 6 adds `runs.moves`
(nullable, `RUN_UPGRADE_COLUMNS`): the run's movement model (`vinadv.grid.moves`); NULL (every run of a version 5
database) reads as `octile`. Version 7 adds `map_pairs.edit` (nullable): each pair's
edit, `add` or `remove` (DESIGN.md "Obstacle removal"; NULL, in the rows of an older database, reads as `add`)
and the table `bench_chunks`. Version 8 adds the search effort of a pair (`EFFORT_COLUMNS`, nullable; DESIGN.md
"Search effort"): `map_pairs.expanded_o` and `expanded_a`, the cells the planner's search expanded on each map as
path text (`"r,c;r,c"`), and `astar_expansions_o`, `astar_expansions_a`, the exact A*'s counts on the same maps
(NULL: a planner that reports no expansions, and every row of an older database); and the provenance of a robustness
benchmark (`ROBUSTNESS_UPGRADE_COLUMNS`): `robustness.run_name` (`vinadv robustness --name`, NULL: none) while its
`planner` column holds the full planner spec (`wastar:w=3`; a bare name in older rows). A database of an older
version (`UPGRADABLE_VERSIONS`) gains the columns (`TABLE_UPGRADE_COLUMNS`, `ALTER TABLE ... ADD COLUMN`), tables
and collation it lacks on open (see `connection.upgrade`); opened read-only it reads the columns as NULL and the
tables as empty; any other version is refused untouched.

Maps and paths are `Text` (MEDIUMTEXT on MySQL): an N=28 map is 811 characters, paths are unbounded, and a
VARCHAR would cap both.
"""

from __future__ import annotations

import sqlalchemy as sa
from sqlalchemy.dialects import mysql

from vinadv.vocabulary import HARM_FIELDS, HARM_FLOAT_FIELDS
from vinadv.vocabulary import HARMS as HARMS  # the harm column's values; re-exported for the store's users
from vinadv.vocabulary import LABELS as LABELS  # the label column's values; re-exported for the store's users

#: bump when a table or column changes; a database with another version is refused with a clear error.
SCHEMA_VERSION = "8"
#: the versions before: upgraded on open by adding what they lack (`UPGRADE_COLUMNS`, `UPGRADE_TABLES`, the run
#: name's collation; nothing existing is lost)
UPGRADABLE_VERSIONS = ("1", "2", "3", "4", "5", "6", "7")

metadata = sa.MetaData()


def exact_collation(dialect: sa.Dialect) -> str | None:
    """The collation under which MySQL/MariaDB compares two strings equal only when they are the same characters:
    binary (case, accents and every emoji count) and without padding (a trailing space counts), where the server
    has one (MariaDB 10.2 on: `utf8mb4_nopad_bin`; MySQL 8.0.17 on: `utf8mb4_0900_bin`; older servers have only
    the padding `utf8mb4_bin`). None on the other backends, which compare bytes already."""
    if dialect.name not in ("mysql", "mariadb"):
        return None
    version = dialect.server_version_info or ()
    if getattr(dialect, "is_mariadb", False):
        return "utf8mb4_nopad_bin" if version >= (10, 2) else "utf8mb4_bin"
    return "utf8mb4_0900_bin" if version >= (8, 0, 17) else "utf8mb4_bin"


class ExactString(sa.types.TypeDecorator):
    """A `String(length)` compared exactly on every backend: on MySQL/MariaDB a utf8mb4 VARCHAR of the
    `exact_collation` (schema version 5: their default collations ignore case and accents and treat all emoji as
    one), elsewhere a plain VARCHAR."""

    impl = sa.String
    cache_ok = True

    def load_dialect_impl(self, dialect: sa.Dialect) -> sa.types.TypeEngine:
        collation = exact_collation(dialect)
        if collation is None:
            return dialect.type_descriptor(sa.String(self.impl.length))
        return dialect.type_descriptor(mysql.VARCHAR(self.impl.length, charset="utf8mb4", collation=collation))


# MySQL TEXT stops at 64 KiB (a 256x256 map, or a ~10,000-cell path); MEDIUMTEXT holds 16 MiB.
_LongText = sa.Text().with_variant(mysql.MEDIUMTEXT(), "mysql", "mariadb")

# BIGINT autoincrement everywhere except SQLite, where only INTEGER PRIMARY KEY is the rowid alias.
_BigId = sa.BigInteger().with_variant(sa.Integer(), "sqlite")

meta_table = sa.Table(
    "vinadv_meta",
    metadata,
    sa.Column("key", sa.String(64), primary_key=True),
    sa.Column("value", sa.String(255), nullable=False),
)

runs = sa.Table(
    "runs",
    metadata,
    sa.Column("id", _BigId, primary_key=True, autoincrement=True),
    sa.Column("name", ExactString(255), nullable=True),  # compared exactly (schema version 5)
    sa.Column("created", sa.DateTime(), nullable=False),  # UTC, naive (MySQL DATETIME has no zone)
    sa.Column("config", sa.JSON(), nullable=True),
    sa.Column("seed", sa.BigInteger(), nullable=True),
    sa.Column("weights_checksum", sa.String(128), nullable=True),
    sa.Column("attack", sa.String(64), nullable=True),
    sa.Column("classifier", sa.String(255), nullable=True),
    sa.Column("version", sa.String(64), nullable=False),
    sa.Column("timings", sa.JSON(), nullable=True),
    sa.Column("status", sa.String(32), nullable=False),
    # the movement model of the run's maps (schema version 6, `vinadv.grid.moves`); NULL = octile (older runs)
    sa.Column("moves", sa.String(16), nullable=True),
    sa.Index("ix_runs_name", "name"),
)

map_pairs = sa.Table(
    "map_pairs",
    metadata,
    sa.Column("no", _BigId, primary_key=True, autoincrement=True),  # the paper's incremented sequence number
    sa.Column("run_id", _BigId, sa.ForeignKey("runs.id"), nullable=False),
    sa.Column("pair_index", sa.BigInteger(), nullable=False),
    sa.Column("map_o", _LongText, nullable=False),
    sa.Column("map_a", _LongText, nullable=False),
    sa.Column("path_o", _LongText, nullable=False),
    sa.Column("path_a", _LongText, nullable=False),
    sa.Column("label", sa.String(16), nullable=False),
    sa.Column("attack", sa.Boolean(create_constraint=False), nullable=False),
    sa.Column("start", sa.String(16), nullable=False),
    sa.Column("goal", sa.String(16), nullable=False),
    sa.Column("added_obstacle", sa.String(16), nullable=False),
    sa.Column("label_source", sa.String(255), nullable=False),
    sa.Column("score", sa.Double(), nullable=True),
    sa.Column("term_o", sa.String(16), nullable=False),
    sa.Column("term_a", sa.String(16), nullable=False),
    sa.Column("dh", sa.Integer(), nullable=True),
    sa.Column("dv", sa.Integer(), nullable=True),
    # harm (schema version 2): costs in move units (orthogonal 1, diagonal sqrt 2); NULL = none / not computed
    sa.Column("opt_cost_o", sa.Double(), nullable=True),
    sa.Column("opt_cost_a", sa.Double(), nullable=True),
    sa.Column("cost_o", sa.Double(), nullable=True),
    sa.Column("cost_a", sa.Double(), nullable=True),
    sa.Column("regret_o", sa.Double(), nullable=True),
    sa.Column("regret_a", sa.Double(), nullable=True),
    sa.Column("expert_label", sa.String(16), nullable=True),
    sa.Column("harm", sa.String(16), nullable=True),
    # several obstacles (schema version 3): the cells added after `added_obstacle`, in order, "r,c;r,c" (as a path);
    # NULL for a one-obstacle pair
    sa.Column("added_more", _LongText, nullable=True),
    # obstacle removal (the step to schema version 7): 'add' or 'remove' (`vocabulary.EDITS`); NULL reads as 'add'
    sa.Column("edit", sa.String(8), nullable=True),
    # search effort (the step to schema version 8): the planner's expanded cells on each map, "r,c;r,c" (as a
    # path), and the exact A*'s expansion counts on the same maps; NULL = not reported (a planner without them)
    sa.Column("expanded_o", _LongText, nullable=True),
    sa.Column("expanded_a", _LongText, nullable=True),
    sa.Column("astar_expansions_o", sa.Integer(), nullable=True),
    sa.Column("astar_expansions_a", sa.Integer(), nullable=True),
    sa.UniqueConstraint("run_id", "pair_index", name="uq_map_pairs_run_pair"),
    # pair_index last: a filtered page of a run (`Store.page_pairs`, the viewer's grid) is one ordered index range
    sa.Index("ix_map_pairs_run_label", "run_id", "label", "pair_index"),
    sa.Index("ix_map_pairs_run_attack", "run_id", "attack", "pair_index"),
    sa.Index("ix_map_pairs_run_source", "run_id", "label_source", "pair_index"),
    # the viewer's harm filter, the report's harm examples; made by `Store.ensure_indexes` in an older database
    sa.Index("ix_map_pairs_run_harm", "run_id", "harm", "pair_index"),
    sa.Index("ix_map_pairs_label", "label"),
)

annotations = sa.Table(
    "annotations",
    metadata,
    sa.Column("id", _BigId, primary_key=True, autoincrement=True),
    sa.Column("run_id", _BigId, sa.ForeignKey("runs.id"), nullable=False),
    sa.Column("pair_index", sa.BigInteger(), nullable=False),
    sa.Column("label", sa.String(16), nullable=False),
    sa.Column("annotator", sa.String(255), nullable=False),
    sa.Column("created", sa.DateTime(), nullable=False),
    sa.Index("ix_annotations_run_pair", "run_id", "pair_index"),
)

evaluations = sa.Table(
    "evaluations",
    metadata,
    sa.Column("id", _BigId, primary_key=True, autoincrement=True),
    sa.Column("run_id", _BigId, sa.ForeignKey("runs.id"), nullable=False),
    sa.Column("created", sa.DateTime(), nullable=False),  # UTC, naive
    sa.Column("batch", sa.String(64), nullable=False),  # one `vinadv evaluate` call: its rows share this id
    sa.Column("classifier", sa.String(32), nullable=False),  # svm|cnn|mlp|hausdorff|frechet|dtw|hybrid|rule
    sa.Column("setting", sa.String(16), nullable=False),  # baseline|tuned
    sa.Column("training", sa.String(16), nullable=False),  # balanced|imbalanced (the training set)
    sa.Column("train_fraction", sa.Double(), nullable=False),  # of the 70% training split (fig. 8)
    sa.Column("train_size", sa.Integer(), nullable=False),  # training pairs, augmented copies included
    sa.Column("test_size", sa.Integer(), nullable=False),
    sa.Column("seed", sa.BigInteger(), nullable=True),
    sa.Column("metrics", sa.JSON(), nullable=False),  # accuracy, per-class P/R/F1, AUC, AP, confusion, timings
    sa.Column("curves", sa.JSON(), nullable=True),  # {"roc": {"fpr", "tpr"}, "pr": {"precision", "recall"}}
    sa.Index("ix_evaluations_run", "run_id", "id"),
)

robustness = sa.Table(
    "robustness",
    metadata,
    sa.Column("id", _BigId, primary_key=True, autoincrement=True),
    sa.Column("created", sa.DateTime(), nullable=False),  # UTC, naive
    # the full planner spec with its parameters (`wastar:w=3`, `vinadv.planners.registry.spec_label`); older rows:
    # the bare name (`Planner.name`)
    sa.Column("planner", sa.String(255), nullable=False),
    sa.Column("weights_checksum", sa.String(128), nullable=True),  # its weights' SHA-256 (None: no weights)
    sa.Column("settings", sa.JSON(), nullable=False),  # maps, strategies, obstacles, objective, ...
    sa.Column("result", sa.JSON(), nullable=False),  # `RobustnessResult.to_dict()`: every figure
    sa.Column("version", sa.String(64), nullable=False),
    sa.Column("run_name", ExactString(255), nullable=True),  # `vinadv robustness --name` (schema version 8)
    sa.Index("ix_robustness_planner", "planner", "id"),
)

bench_chunks = sa.Table(
    "bench_chunks",
    metadata,
    sa.Column("id", _BigId, primary_key=True, autoincrement=True),
    sa.Column("created", sa.DateTime(), nullable=False),  # UTC, naive
    sa.Column("entry", sa.String(64), nullable=False),  # sha256 of (suite checksum, planner spec): one bench entry
    sa.Column("chunk", sa.Integer(), nullable=False),  # maps chunk * suite.chunk .. of the suite
    sa.Column("result", sa.JSON(), nullable=False),  # the chunk's per-map outcomes (`vinadv.bench.scoring`)
    sa.Column("version", sa.String(64), nullable=False),
    sa.UniqueConstraint("entry", "chunk", name="uq_bench_chunks_entry_chunk"),
)

measurements = sa.Table(
    "measurements",
    metadata,
    sa.Column("id", _BigId, primary_key=True, autoincrement=True),
    sa.Column("run_id", _BigId, sa.ForeignKey("runs.id"), nullable=False),
    sa.Column("created", sa.DateTime(), nullable=False),  # UTC, naive
    sa.Column("kind", sa.String(32), nullable=False),  # `vinadv.vocabulary.MEASUREMENTS`
    sa.Column("result", sa.JSON(), nullable=False),  # what the evaluation stage measured, as it stored it
    sa.Column("version", sa.String(64), nullable=False),  # the vinadv that measured it
    sa.Index("ix_measurements_run_kind", "run_id", "kind", "id"),
)

#: `map_pairs` columns added by schema version 2 (numbers first, then the two labels)
HARM_FLOAT_COLUMNS = HARM_FLOAT_FIELDS
HARM_COLUMNS = HARM_FIELDS
#: `map_pairs` column added by schema version 3
MORE_ADDED_COLUMN = "added_more"
#: `map_pairs` column added by the step to schema version 7
EDIT_COLUMN = "edit"
#: `map_pairs` columns added by the step to schema version 8: the search effort (`vinadv.classify.effort`)
EFFORT_COLUMNS = ("expanded_o", "expanded_a", "astar_expansions_o", "astar_expansions_a")
#: `map_pairs` columns added after version 1: an older database gains those it lacks on open
UPGRADE_COLUMNS = (*HARM_COLUMNS, MORE_ADDED_COLUMN, EDIT_COLUMN, *EFFORT_COLUMNS)
#: `runs` column added by schema version 6: an older database gains it on open (NULL reads as octile)
RUN_UPGRADE_COLUMNS = ("moves",)
#: `robustness` column added by the step to schema version 8: an older database's table gains it on open
ROBUSTNESS_UPGRADE_COLUMNS = ("run_name",)
#: tables added by schema version 4: an older database gains them on open
UPGRADE_TABLES = (measurements,)
#: the version that added the `UPGRADE_TABLES`: a database of that version or later without them is refused
UPGRADE_TABLES_SINCE = 4

TABLES = (meta_table, runs, map_pairs, annotations, evaluations, robustness, measurements, bench_chunks)
#: tables added to the schema later: created when missing, never a reason to refuse a database (`bench_chunks`: the
#: step to 7, the resumable units of `vinadv bench run --db`)
ADDITIVE_TABLES = (evaluations, robustness, bench_chunks)
#: the columns each table gained after it first shipped, added on open to an older database's table (names unique
#: across the tables: a read-only reader of an older database reads them as NULL by name, `Database.absent_columns`)
TABLE_UPGRADE_COLUMNS = {map_pairs: UPGRADE_COLUMNS, runs: RUN_UPGRADE_COLUMNS, robustness: ROBUSTNESS_UPGRADE_COLUMNS}
