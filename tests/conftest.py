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

from tests.needs import skip_or_fail
from vinadv.planners.batching import set_torch_threads

# One torch thread in the test process: the tests' maps are small, and on a shared 2-core machine a 2-thread op on
# a small map waits for the busy core (the oracles' step-by-step planning ran 50x slower). Numba's parallel kernels
# get one too, or their first launch would put torch back on two (`set_torch_threads`). Commands the tests start in
# subprocesses keep the defaults.
set_torch_threads(1)

# The near-tie replay keeps what it measured of PyTorch on disk (`replay.cache_path`): the tests, and the
# commands they start, keep theirs in a folder of their own, so they neither trust the user's nor leave one behind.
os.environ["VINADV_CACHE_DIR"] = tempfile.mkdtemp(prefix="vinadv-test-cache-")
atexit.register(shutil.rmtree, os.environ["VINADV_CACHE_DIR"], True)

#: Tests left out of `make test-fast` (`pytest -m "not slow"`), by node id prefix: the ones that start Dask
#: clusters or a browser, train networks or classifiers, or run the whole pipeline; together they take most of the
#: suite's time. One list, so the fast selection is decided in one place.
SLOW = (
    "tests/cluster/",
    "tests/report/",
    "tests/viewer/test_browser.py",
    "tests/planners/test_training.py",
    "tests/classify/test_models.py",
    "tests/classify/test_cooccurrence.py",
    "tests/commands/test_classify.py::test_train_and_eval_on_held_out_split",
    "tests/test_pipeline.py::test_killed_run_resumes_with_every_pair_exactly_once",
    "tests/test_pipeline.py::test_stored_labels_agree_with_an_independent_recomputation",
    "tests/test_readme.py",
    # the slowest of the rest (pytest --durations, 2-core machine): subprocesses killed or starved on purpose,
    # the largest float64 gradient check
    "tests/planners/vin/test_value_iteration.py::test_values_and_gradients_equal_torch_float64",
    "tests/planners/vin/test_value_iteration.py::test_float32_close_to_torch_and_batch_split_between_threads",
    "tests/planners/replay/test_replay.py::test_a_process_without_pytorch_plans_what_pytorch_would",
    "tests/planners/vin/test_engine.py::test_identical_to_reference_odd_sizes",
    "tests/test_cli_imports.py::test_a_run_with_the_rule_labeller_does_without_scikit_learn",
    "tests/test_faults.py::test_full_disk_during_a_run_is_one_line_with_the_resume_hint",
    "tests/test_faults.py::test_kill_inside_a_transaction_then_resume_stores_every_pair_once",
    "tests/test_faults.py::test_export_into_a_broken_pipe_ends_quietly",
    "tests/store/test_store_db.py::test_killed_writer_resumes_with_every_pair_exactly_once",
    "tests/test_cli_imports.py::test_a_command_still_checks_its_choices",
    "tests/test_cli_imports.py::test_a_vin_run_needs_no_pytorch_once_the_replay_settings_are_kept",
    "tests/planners/test_gppn_training.py",
    "tests/attacks/test_obstacles.py::test_every_k_obstacle_pair_keeps_the_rules",
    "tests/attacks/test_obstacles.py::test_greedy_steps_pick_the_strongest_cell_of_a_brute_force_search",
    "tests/test_robustness.py::test_exhaustive_harmful_rate_is_the_share_of_maps_some_single_cell_harms",
    # 2-thread PyTorch beside a busy core, and a fresh interpreter
    "tests/planners/replay/test_replay.py::test_replay_kernel_is_q_values_bit_for_bit[2-threads",
    "tests/planners/test_batching.py::test_torch_keeps_its_threads_after_numba_parallel_kernels",
)


def pytest_collection_modifyitems(config, items) -> None:
    for item in items:
        # the database servers' variants too: the quick selection checks every backend test on SQLite
        on_server = getattr(item, "callspec", None) is not None and item.callspec.params.get("db_url") in SERVERS
        if item.nodeid.startswith(SLOW) or on_server:
            item.add_marker(pytest.mark.slow)


MYSQL_DEFAULT = "mysql+pymysql://root@127.0.0.1:3306/test"
POSTGRES_DEFAULT = "postgresql+psycopg://postgres@127.0.0.1:5432/test"
BACKENDS = ("sqlite", "mysql", "postgres")
SERVERS = BACKENDS[1:]


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


@pytest.fixture(scope="session")
def planning_weights(tmp_path_factory):
    """`planning_weights(size)`: the path (str) of a weights file of `planning_vin(size, seed=2, noise=0.1)`, a VIN
    that plans well on small maps; written once per size and session."""
    from vinadv.planners.testing import planning_vin
    from vinadv.planners.vin.weights import save_vin

    made: dict[int, str] = {}

    def path_for(size: int) -> str:
        if size not in made:
            path = tmp_path_factory.mktemp("w") / f"vin{size}.pt"
            save_vin(planning_vin(size, seed=2, noise=0.1), path)
            made[size] = str(path)
        return made[size]

    return path_for
