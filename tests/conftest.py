"""Database fixtures: a fresh SQLite file, MariaDB database or PostgreSQL schema per test, dropped afterwards.

Server URLs come from `VINADV_TEST_MYSQL_URL` / `VINADV_TEST_POSTGRES_URL` (defaults: the local servers).
An unreachable server skips its tests, except under `CI=true`, where it fails them.
"""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
import uuid
from collections.abc import Iterator

import pytest
import sqlalchemy as sa
from hypothesis import settings

from tests.needs import skip_or_fail
from tests.scheduling import make_scheduler
from vinadv.planners.batching import set_torch_threads
from vinadv.planners.vin.weights import save_vin
from vinadv.testing.planners import planning_vin

# One torch thread in the test process: the tests' maps are small, and on a shared 2-core machine a 2-thread op on
# a small map waits for the busy core (the oracles' step-by-step planning ran 50x slower). Numba's parallel kernels
# get one too, or their first launch would put torch back on two (`set_torch_threads`). Commands the tests start in
# subprocesses keep the defaults.
set_torch_threads(1)


@pytest.fixture(autouse=True)
def one_torch_thread_after_each_test() -> Iterator[None]:
    """Back to one torch thread after a test that changed it: a command run in the test process applies its
    `--threads` for good (`test_cli_fuzz` gave 12), and every later test of that worker then ran its small ops on 12
    threads over 2 cores; the port-loop oracle of `test_protocols` took 40 s instead of 0.3 s."""
    yield
    import torch  # noqa: PLC0415 (loaded already: `save_vin` imports it)

    if torch.get_num_threads() != 1:
        set_torch_threads(1)


# Hypothesis: every property test reproducible. The "ci" profile (loaded where CI=true, or by HYPOTHESIS_PROFILE=ci)
# draws the same examples on every run (derandomize: seeded by the test itself) and keeps no database, so a CI run
# fails only on a case anyone can rerun; "dev" (the default elsewhere) draws new examples each run and keeps the ones
# that failed in .hypothesis/ to replay them first. Both print a failure's reproduction blob (`@reproduce_failure`);
# a failure found either way is kept in its test as an `@example(...)`, a regression example every profile runs.
# `pytest --hypothesis-seed=N` draws other examples once, to look for hidden assumptions (docs/development.md).
settings.register_profile("ci", derandomize=True, database=None, print_blob=True)
settings.register_profile("dev", print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE") or ("ci" if os.environ.get("CI") == "true" else "dev"))

# Temporary files (tmp_path, the folders below) on a RAM disk where there is a roomy one: SQLite syncs every new
# database to disk (45 ms a database on the 2-core machine's disk, 15 ms in memory) and the suite creates hundreds;
# no test here is about surviving a power cut. pytest still numbers its folders per run, so runs side by side do not
# collide. VINADV_TEST_TMP=disk keeps them in the system's temporary folder.
RAM_DISK = "/dev/shm"
if (
    os.environ.get("VINADV_TEST_TMP") != "disk"
    and os.path.isdir(RAM_DISK)
    and os.access(RAM_DISK, os.W_OK)
    and shutil.disk_usage(RAM_DISK).free > 4 * 2**30
):
    tempfile.tempdir = RAM_DISK

# The near-tie replay keeps what it measured of PyTorch on disk (`replay.cache_path`): the tests, and the
# commands they start, keep theirs in a folder of their own, so they neither trust the user's nor leave one behind.
os.environ["VINADV_CACHE_DIR"] = tempfile.mkdtemp(prefix="vinadv-test-cache-")
atexit.register(shutil.rmtree, os.environ["VINADV_CACHE_DIR"], True)


#: (node id, slow?) of every test the session collected, before `-m` selected some (tests/test_tiers.py reads it)
COLLECTED = pytest.StashKey[list[tuple[str, bool]]]()


@pytest.hookimpl(tryfirst=True)  # before `-m` selects: the marks set here count
def pytest_collection_modifyitems(config, items) -> None:
    """Tests on the database servers are slow, whether a variant of a backend test (`db_url` or `module_db_url` =
    mysql/postgres) or a test that takes a server's fixture (`SERVER_FIXTURES`): the quick selection checks every
    backend test on SQLite and needs no server. So are the GPU tests (marked `cuda`). The rest of the slow tier
    (`make test-fast` is `pytest -m "not slow"`) is marked in the test modules themselves (`pytestmark =
    pytest.mark.slow` or `@pytest.mark.slow`): the ones that start Dask clusters, a browser or subprocesses, train
    networks or classifiers, or run the whole pipeline."""
    for item in items:
        callspec = getattr(item, "callspec", None)
        params = callspec.params if callspec is not None else {}
        on_server = params.get("db_url") in SERVERS or params.get("module_db_url") in SERVERS
        on_gpu = item.get_closest_marker("cuda") is not None  # the GPU tests: never in the quick tier
        if on_server or on_gpu or SERVER_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)
    config.stash[COLLECTED] = [(item.nodeid, item.get_closest_marker("slow") is not None) for item in items]


def pytest_runtest_setup(item) -> None:
    """A test marked `cuda` is skipped where PyTorch sees no CUDA GPU (CI has none: skipped there too, not failed)."""
    if item.get_closest_marker("cuda") is not None:
        import torch  # noqa: PLC0415 (only for the GPU tests)

        if not torch.cuda.is_available():
            pytest.skip("needs a CUDA GPU (PyTorch sees none here); perf/device_check.sh runs it on one")


@pytest.hookimpl(optionalhook=True)  # pytest-xdist's hook, called only under `pytest -n N`
def pytest_xdist_make_scheduler(config, log):
    """Under `pytest -n N` a worker takes a whole module at a time, and the report tests whole (tests/scheduling.py)."""
    return make_scheduler(config, log)


MYSQL_DEFAULT = "mysql+pymysql://root@127.0.0.1:3306/test"
POSTGRES_DEFAULT = "postgresql+psycopg://postgres@127.0.0.1:5432/test"
BACKENDS = ("sqlite", "mysql", "postgres")
SERVERS = BACKENDS[1:]
#: the fixtures that reach a database server
SERVER_FIXTURES = {"mysql_server", "postgres_server", "mysql_url", "postgres_url"}


def _server(env: str, default: str) -> sa.Engine:
    url = os.environ.get(env) or default
    engine = sa.create_engine(url, connect_args={"connect_timeout": 5}, poolclass=sa.pool.NullPool)
    try:
        with engine.connect() as conn:
            conn.execute(sa.text("SELECT 1"))
    except Exception as exc:  # any failure to reach the server
        skip_or_fail(f"{env}: server {sa.make_url(url).render_as_string(hide_password=True)} unreachable: {exc}")
    return engine


@pytest.fixture(scope="session")
def mysql_server() -> sa.Engine:
    return _server("VINADV_TEST_MYSQL_URL", MYSQL_DEFAULT)


@pytest.fixture(scope="session")
def postgres_server() -> sa.Engine:
    return _server("VINADV_TEST_POSTGRES_URL", POSTGRES_DEFAULT)


def _fresh_name() -> str:
    return f"vinadv_test_{uuid.uuid4().hex[:12]}"


def _fresh_database(server: sa.Engine) -> Iterator[str]:
    """A fixture's body: make a fresh, empty database on `server` (a MariaDB database, or a PostgreSQL schema first
    on the search path), yield its URL (password included) and drop it after the test."""
    name = _fresh_name()
    if server.dialect.name == "postgresql":
        create, drop = f'CREATE SCHEMA "{name}"', f'DROP SCHEMA IF EXISTS "{name}" CASCADE'
        url = server.url.update_query_dict({"options": f"-csearch_path={name}"})
    else:
        create, drop = f"CREATE DATABASE `{name}` CHARACTER SET utf8mb4", f"DROP DATABASE IF EXISTS `{name}`"
        url = server.url.set(database=name)
    with server.begin() as conn:
        conn.execute(sa.text(create))
    try:
        yield url.render_as_string(hide_password=False)
    finally:
        with server.begin() as conn:
            conn.execute(sa.text(drop))


@pytest.fixture
def mysql_url(mysql_server):
    """URL of a fresh, empty MariaDB database (dropped after the test)."""
    yield from _fresh_database(mysql_server)


@pytest.fixture
def postgres_url(postgres_server):
    """URL of a fresh, empty PostgreSQL schema (first on the search path; dropped after the test)."""
    yield from _fresh_database(postgres_server)


@pytest.fixture
def sqlite_url(tmp_path):
    return f"sqlite:///{tmp_path / 'vinadv.db'}"


@pytest.fixture(params=BACKENDS)
def db_url(request):
    """A fresh empty database on each backend in turn."""
    return request.getfixturevalue(f"{request.param}_url")


@pytest.fixture(scope="module", params=BACKENDS)
def module_db_url(request, tmp_path_factory):
    """A fresh empty database on each backend in turn, made once per module (and dropped after it), for a module's
    tests that only read what a module-scoped fixture stored there: a MariaDB database costs seconds of the server's
    DDL to create and fill, a test that writes takes `db_url`."""
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path_factory.mktemp('db') / 'vinadv.db'}"
    else:
        yield from _fresh_database(request.getfixturevalue(f"{request.param}_server"))


@pytest.fixture(scope="session")
def planning_weights(tmp_path_factory):
    """`planning_weights(size)`: the path (str) of a weights file of `planning_vin(size, seed=2, noise=0.1)`, a VIN
    that plans well on small maps; written once per size and session."""
    made: dict[int, str] = {}

    def path_for(size: int) -> str:
        if size not in made:
            path = tmp_path_factory.mktemp("w") / f"vin{size}.pt"
            save_vin(planning_vin(size, seed=2, noise=0.1), path)
            made[size] = str(path)
        return made[size]

    return path_for
