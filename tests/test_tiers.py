"""The suite's two tiers: `make test-fast` runs `pytest -m "not slow"`, `make test` everything.

A test is slow by a marker in its own module (`pytestmark = pytest.mark.slow` or `@pytest.mark.slow`), or, for the
database servers' variants of a backend test, by its `db_url` parameter (tests/conftest.py); never by a list of node
ids, which a renamed test would silently leave.
"""

import ast
import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"


def test_make_test_fast_leaves_out_the_slow_marker_and_markers_are_checked():
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    fast_recipe = makefile.split("\ntest-fast:", 1)[1].split("\n\n", 1)[0]
    assert '-m "not slow"' in fast_recipe
    options = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["pytest"]["ini_options"]
    assert any(m.startswith("slow:") for m in options["markers"])
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


#: collects the suite three times in one interpreter (the test modules are imported once): all tests, `-m slow` and
#: `-m "not slow"`; writes the three lists of node ids as JSON to argv[1]
COLLECT = """
import json, sys
import pytest

class NodeIds:
    def pytest_collection_finish(self, session):
        self.ids = [item.nodeid for item in session.items]

lists = {}
for name, select in (("all", []), ("slow", ["-m", "slow"]), ("fast", ["-m", "not slow"])):
    plugin = NodeIds()
    code = pytest.main(["--collect-only", "-qq", "-p", "no:cacheprovider", *select, "tests"], plugins=[plugin])
    assert code == 0, (name, code)
    lists[name] = plugin.ids
with open(sys.argv[1], "w") as f:
    json.dump(lists, f)
"""


#: test packages with no quick test: every report test builds runs and renders a whole report
ALL_SLOW = {"report"}


@pytest.mark.slow  # collecting the suite imports every test module (about 10 s of CPU)
def test_slow_and_fast_tiers_split_the_suite_and_every_package_keeps_fast_tests(tmp_path):
    out = tmp_path / "tiers.json"
    subprocess.run([sys.executable, "-c", COLLECT, str(out)], cwd=ROOT, check=True, capture_output=True, timeout=600)
    lists = json.loads(out.read_text())
    everything, slow, fast = (lists[k] for k in ("all", "slow", "fast"))
    assert len(set(everything)) == len(everything) > 0
    assert len(slow) == len(set(slow)) and len(fast) == len(set(fast))
    assert not set(slow) & set(fast)
    assert sorted(slow + fast) == sorted(everything)
    # the quick tier is a real part of the suite, not a token one
    assert len(fast) > len(slow)

    # every test package (one per vinadv package) and the top-level tests keep some tests in the quick tier
    def package(node_id: str) -> str:
        parts = node_id.split("::")[0].split("/")
        return parts[1] if len(parts) > 2 else "tests"

    assert {package(n) for n in fast} == {package(n) for n in everything} - ALL_SLOW
