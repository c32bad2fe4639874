"""The README's and the documentation's examples, run as written (extracted from the pages, so the two never drift).

Every ```python block of README.md and docs/**/*.md runs, from the repository's root (a `--8<-- "FILE"` line, the
snippet syntax of the docs, stands for FILE's text). Every concrete `vinadv ...` command of their ```sh blocks must
parse with today's parser: a renamed or removed option fails here. Synopsis lines (`[--opt X]`, `a|b`, `...`,
upper-case placeholders) are left out of that check; the CLI reference (docs/reference/cli.md) is generated.
"""

import contextlib
import io
import os
import re
import shlex
from pathlib import Path

import pytest

from vinadv.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PAGES = [README, *sorted((ROOT / "docs").rglob("*.md"))]
SNIPPET = re.compile(r'^--8<-- "([^"]+)"$', flags=re.M)


def fenced_blocks(path: Path, language: str) -> list[str]:
    """The bodies of the page's ```LANGUAGE blocks, snippet lines replaced by the files they name."""
    blocks = re.findall(rf"^```{language}\n(.*?)^```", path.read_text(), flags=re.S | re.M)
    return [SNIPPET.sub(lambda m: (ROOT / m.group(1)).read_text(), block) for block in blocks]


def python_blocks() -> list[tuple[str, str]]:
    """(where, code) of every Python block, each distinct block once (the README repeats the docs' tour)."""
    seen, found = set(), []
    for page in PAGES:
        for i, code in enumerate(fenced_blocks(page, "python")):
            if code not in seen:
                seen.add(code)
                found.append((f"{page.relative_to(ROOT)}:{i}", code))
    return found


def shell_commands() -> list[tuple[str, str]]:
    """(where, command line) of every concrete `vinadv` command in the pages' ```sh blocks."""
    found = []
    for page in PAGES:
        for block in fenced_blocks(page, "sh"):
            for line in block.replace("\\\n", " ").splitlines():
                line = line.split(" #", 1)[0].strip()
                if not line.startswith("vinadv ") or re.search(r"[\[|<]|\.\.\.|\b[A-Z]{2,}\b|--help", line):
                    continue
                found.append((str(page.relative_to(ROOT)), line))
    return found


PYTHON_BLOCKS = python_blocks()
SHELL_COMMANDS = shell_commands()


def test_the_pages_hold_examples():
    with_python = {str(page.relative_to(ROOT)) for page in PAGES if fenced_blocks(page, "python")}
    assert {"README.md", "docs/getting-started.md", "docs/own-planner.md", "docs/guide/robustness.md"} <= with_python
    assert len(SHELL_COMMANDS) >= 20


@pytest.mark.slow  # the examples plan and attack with the shipped VIN (PyTorch, Numba): seconds each
@pytest.mark.parametrize("where, code", PYTHON_BLOCKS, ids=[w for w, _ in PYTHON_BLOCKS])
def test_python_block_runs(where, code, monkeypatch):
    monkeypatch.chdir(ROOT)  # examples name repository files (examples/my_planner.py) and write only to temp dirs
    before = set(os.listdir(ROOT))
    out = io.StringIO()
    namespace: dict = {"__name__": "__main__"}
    with contextlib.redirect_stdout(out):
        exec(compile(code, where, "exec"), namespace)
    assert set(os.listdir(ROOT)) == before, "an example left files in the repository"
    ident = namespace.get("ident")
    if ident is not None:  # the tour: what it printed and stored agrees with the identification itself
        assert str(ident.counts()) in out.getvalue()
        assert set(ident.labels) <= {"invalid", "UrP", "UcP", "DP", "FP"}
        assert ident.attack.tolist() == [label in ("UrP", "FP") for label in ident.labels]
        assert len(ident.adversarial()) > 0, "a tour that finds no successful attack shows nothing"


@pytest.mark.parametrize("where, line", SHELL_COMMANDS, ids=[f"{w}: {line}" for w, line in SHELL_COMMANDS])
def test_shell_command_parses(where, line):
    parser = build_parser()
    try:
        args = parser.parse_args(shlex.split(line)[1:])
    except SystemExit as exc:
        pytest.fail(f"{where}: `{line}` does not parse (exit {exc.code})")
    assert callable(args.func)
