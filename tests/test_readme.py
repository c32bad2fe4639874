"""The README's Python API example, run exactly as written there (extracted from README.md, so the two never drift)."""

import contextlib
import io
import re
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

README = Path(__file__).resolve().parents[1] / "README.md"


def python_api_block() -> str:
    text = README.read_text()
    section = text.split("## Python API", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert len(blocks) == 1, "the Python API section holds one python block"
    return blocks[0]


def test_python_api_example_runs():
    code = python_api_block()
    assert len(code.strip().splitlines()) <= 20
    out = io.StringIO()
    namespace: dict = {}
    with contextlib.redirect_stdout(out):
        exec(compile(code, str(README), "exec"), namespace)
    ident = namespace["ident"]
    # what it printed and stored agrees with the identification itself
    assert str(ident.counts()) in out.getvalue()
    assert len(ident) == 40 and set(ident.labels) <= {"invalid", "UrP", "UcP", "DP", "FP"}
    assert ident.attack.tolist() == [label in ("UrP", "FP") for label in ident.labels]
