"""How `pytest -n 2` shares the tests between its workers (tests/scheduling.py): a module whole, a package of
`ONE_WORKER` whole, and `make test` / `make test-fast` run with two workers unless `TEST_WORKERS` says otherwise."""

from pathlib import Path

import pytest

from tests.scheduling import ONE_WORKER, scope

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize(
    ("node_id", "unit"),
    [
        ("tests/test_cli.py::test_help", "tests/test_cli.py"),
        ("tests/store/test_store_db.py::test_killed_writer[mysql]", "tests/store/test_store_db.py"),
        ("tests/store/test_store_db.py::TestRows::test_round_trip", "tests/store/test_store_db.py"),
        ("tests/grid/test_paths.py::test_concat[a::b]", "tests/grid/test_paths.py"),
        ("tests/report/test_report.py::test_bad_input_exits_2_with_a_message", "tests/report"),
        ("tests/report/test_report_sections.py::test_each_section[harm]", "tests/report"),
        ("tests/reporting_tools/test_x.py::test_y", "tests/reporting_tools/test_x.py"),
    ],
)
def test_a_worker_takes_a_module_or_a_one_worker_package_whole(node_id, unit):
    assert scope(node_id) == unit


def test_one_worker_packages_exist():
    assert ONE_WORKER and all((ROOT / "tests" / name / "conftest.py").is_file() for name in ONE_WORKER)


def test_make_runs_the_tests_with_workers_when_asked():
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    for target in ("test", "test-fast"):
        recipe = makefile.split(f"\n{target}:", 1)[1].split("\n\n", 1)[0]
        assert "-m pytest $(WORKERS_FLAG)" in recipe, target
    assert "\nWORKERS_FLAG := $(if $(TEST_WORKERS),-n $(TEST_WORKERS))\n" in makefile
    assert "\nTEST_WORKERS ?= 2\n" in makefile  # two workers by default: measured faster (docs/development.md)
