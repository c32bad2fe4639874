"""SQL storage of runs and identified map pairs (SQLAlchemy 2 Core; SQLite, MySQL/MariaDB, PostgreSQL).

`Store.open(url)` opens a database, `PairRecords` is the columnar batch it writes and reads, `codec` holds
the paper's text formats for maps and paths and the row codec.
"""

from vinadv.store.connection import resolve_url, safe_url
from vinadv.store.records import PairRecords
from vinadv.store.schema import LABELS, SCHEMA_VERSION
from vinadv.store.store import Store

__all__ = ["LABELS", "SCHEMA_VERSION", "PairRecords", "Store", "resolve_url", "safe_url"]
