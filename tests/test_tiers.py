"""The suite's two tiers: `make test-fast` runs `pytest -m "not slow"`, `make test` everything.

A test is slow by a marker in its own module (`pytestmark = pytest.mark.slow` or `@pytest.mark.slow`), or, for the
database servers' variants of a backend test, by its `db_url` parameter (tests/conftest.py); never by a list of node
ids, which a renamed test would silently leave.
"""

import ast
import re
import tomllib
from pathlib import Path

import pytest

from tests.conftest import COLLECTED

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"


def test_make_test_fast_leaves_out_the_slow_marker_and_markers_are_checked():
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    fast_recipe = makefile.split("\ntest-fast:", 1)[1].split("\n\n", 1)[0]
    assert '-m "not slow"' in fast_recipe
    options = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["pytest"]["ini_options"]
    assert any(m.startswith("slow:") for m in options["markers"])
    # the GPU tests' marker: perf/device_check.sh selects them with `-m cuda` on a lent GPU machine
    assert any(m.startswith("cuda:") for m in options["markers"])
    assert "-m cuda" in (ROOT / "perf" / "device_check.sh").read_text(encoding="utf-8")
    # a misspelt marker (`@pytest.mark.slwo`) would leave its test in the fast tier without a word: refuse it
    assert "--strict-markers" in options["addopts"].split()
    assert options["timeout"] == 300


def test_conftests_name_no_tests():
    """No string in a conftest (docstrings and comments aside) is a test's node id or path."""
    node_id = re.compile(r"(^|/)test_\w+\.py|::|^tests/")
    found = []
    for conftest in sorted(TESTS.rglob("conftest.py")):
        tree = ast.parse(conftest.read_text(encoding="utf-8"))
        docstrings = {
            id(node.body[0].value)
            for node in ast.walk(tree)
            if isinstance(node, ast.Module | ast.FunctionDef | ast.ClassDef)
            and node.body
            and isinstance(node.body[0], ast.Expr)
            and isinstance(node.body[0].value, ast.Constant)
        }
        found += [
            f"{conftest.relative_to(ROOT)}:{node.lineno}: {node.value!r}"
            for node in ast.walk(tree)
            if isinstance(node, ast.Constant)
            and isinstance(node.value, str)
            and id(node) not in docstrings
            and node_id.search(node.value)
        ]
    assert not found, found


#: test packages with no quick test (none since the report's header and paper-setting tests, which render no report)
ALL_SLOW: set[str] = set()


def test_every_test_has_one_tier_and_every_package_keeps_quick_tests(request):
    """Reads what this session collected (tests/conftest.py keeps it, before `-m` selects), so it costs nothing and
    runs in both tiers; it needs the whole suite collected (`pytest`, `make test`, `make test-fast`)."""
    collected = request.config.stash[COLLECTED]
    files = {node_id.split("::")[0] for node_id, _ in collected}
    on_disk = {str(p.relative_to(ROOT)) for p in TESTS.rglob("test_*.py")}
    whole_suite = {(ROOT / arg).resolve() for arg in request.config.args} in ({TESTS}, {ROOT})
    if not whole_suite:
        pytest.skip("only part of the suite was collected")
    assert on_disk <= files, sorted(on_disk - files)  # every test file's tests, before `-m` selected
    node_ids = [node_id for node_id, _ in collected]
    assert len(set(node_ids)) == len(node_ids)
    slow = {node_id for node_id, is_slow in collected if is_slow}
    fast = set(node_ids) - slow
    # the quick tier is a real part of the suite, not a token one
    assert len(fast) > len(slow) > 0
    # `-m` selected from the tier it names only (the server variants' marks were set before it selected)
    selected = {item.nodeid for item in request.session.items}
    tier = {"not slow": fast, "slow": slow}.get(request.config.option.markexpr, set(node_ids))
    assert selected <= tier

    # every test package (one per vinadv package) and the top-level tests keep some tests in the quick tier
    def package(node_id: str) -> str:
        parts = node_id.split("::")[0].split("/")
        return parts[1] if len(parts) > 2 else "tests"

    assert {package(n) for n in fast} == {package(n) for n in node_ids} - ALL_SLOW
