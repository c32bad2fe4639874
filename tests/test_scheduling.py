"""How `pytest -n 2` shares the tests between its workers (tests/scheduling.py): a module whole, a package of
`ONE_WORKER` whole (but its `OWN_FIXTURES` modules), and `make test` / `make test-fast` run with two workers unless
`TEST_WORKERS` says otherwise."""

import ast
import re
from pathlib import Path

import pytest

from tests.scheduling import ONE_WORKER, OWN_FIXTURES, scope

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
        ("tests/report/test_report_planners.py::test_header", "tests/report/test_report_planners.py"),
        ("tests/reporting_tools/test_x.py::test_y", "tests/reporting_tools/test_x.py"),
    ],
)
def test_a_worker_takes_a_module_or_a_one_worker_package_whole(node_id, unit):
    assert scope(node_id) == unit


def test_one_worker_packages_exist():
    assert ONE_WORKER and all((ROOT / "tests" / name / "conftest.py").is_file() for name in ONE_WORKER)


def _fixtures(conftest: Path) -> set[str]:
    """The names of the fixtures that `conftest` defines."""
    tree = ast.parse(conftest.read_text(encoding="utf-8"))
    return {
        node.name
        for node in tree.body
        if isinstance(node, ast.FunctionDef) and any("fixture" in ast.unparse(d) for d in node.decorator_list)
    }


def test_own_fixture_modules_use_none_of_their_packages_fixtures():
    """A module taken out of its `ONE_WORKER` package's unit must not need the package's session fixtures (else both
    workers would make them)."""
    assert OWN_FIXTURES
    for module in sorted(OWN_FIXTURES):
        package = module.split("/")[1]
        assert package in ONE_WORKER, module
        shared = _fixtures(ROOT / "tests" / package / "conftest.py")
        assert shared, package
        text = (ROOT / module).read_text(encoding="utf-8")
        used = {name for name in shared if re.search(rf"\b{name}\b", text)}
        assert not used, (module, used)


def test_make_runs_the_tests_with_workers_when_asked():
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    for target in ("test", "test-fast"):
        recipe = makefile.split(f"\n{target}:", 1)[1].split("\n\n", 1)[0]
        assert "-m pytest $(WORKERS_FLAG)" in recipe, target
    assert "\nWORKERS_FLAG := $(if $(TEST_WORKERS),-n $(TEST_WORKERS))\n" in makefile
    assert "\nTEST_WORKERS ?= 2\n" in makefile  # two workers by default: measured faster (docs/development.md)
