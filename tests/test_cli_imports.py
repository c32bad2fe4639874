"""`vinadv --help`, `--version` and the help of commands that need no heavy library import none of them: the parser
is built from light modules (behaviour, not timing: which modules a fresh interpreter loaded)."""

import ast
import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tests.needs import MODELLED_CPU, cpu_vendor

HEAVY = ("torch", "numba", "sklearn", "sqlalchemy", "scipy", "matplotlib", "distributed", "flask", "pandas", "pyarrow")


def imported_modules(*argv: str) -> set[str]:
    """Top-level packages a fresh `python -X importtime -m vinadv.cli ARGV` imported (it exits 0)."""
    done = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "vinadv.cli", *argv], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-2000:]
    lines = [line.split("|")[-1] for line in done.stderr.splitlines() if line.startswith("import time:")]
    names = {line.strip().split(".")[0] for line in lines}
    assert "vinadv" in names  # the importtime report was read
    return names


@pytest.mark.parametrize(
    "argv",
    [
        ["--help"],
        ["--version"],
        ["maps", "generate", "--help"],
        ["plan", "--help"],
        ["export", "--help"],
        ["report", "--help"],
        ["serve", "--help"],
    ],
    ids=" ".join,
)
def test_parser_imports_no_heavy_library(argv):
    assert not imported_modules(*argv) & set(HEAVY)


@pytest.mark.parametrize("argv", [["--help"], ["--version"]], ids=" ".join)
def test_top_level_help_imports_no_numpy_either(argv):
    # NumPy alone is a third of a second to import: the bare parser does without it
    assert "numpy" not in imported_modules(*argv)


@pytest.mark.slow
def test_a_command_still_checks_its_choices():
    done = subprocess.run(
        [sys.executable, "-m", "vinadv.cli", "run", "--attack", "nope", "--n", "1"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 2 and "near-path" in done.stderr and "nope" in done.stderr


@pytest.mark.slow
def test_a_run_with_the_rule_labeller_does_without_scikit_learn(tmp_path):
    # every command imports only what it uses: the rule labeller is plain Numba, the classifiers bring scikit-learn
    names = imported_modules("run", "--n", "20", "--db", str(tmp_path / "r.db"), "--quiet")
    assert "sqlalchemy" in names and "numba" in names  # the run did happen
    assert "sklearn" not in names and "matplotlib" not in names and "flask" not in names


@pytest.mark.slow
def test_a_vin_run_needs_no_pytorch_once_the_replay_settings_are_kept(tmp_path, monkeypatch):
    # the first run measures PyTorch's arithmetic for the near-tie replay and keeps it; the next loads no PyTorch
    monkeypatch.setenv("VINADV_CACHE_DIR", str(tmp_path / "cache"))
    first = imported_modules("run", "--n", "2000", "--db", str(tmp_path / "a.db"), "--quiet")
    assert "torch" in first
    kept = json.loads((tmp_path / "cache" / "torch_replay.json").read_text())["machines"]
    (entries,) = kept.values()
    assert {"conv_modes", "sum_order", "fc_order", "default_threads"} <= set(entries)
    # where this CPU's BLAS order is not modelled (an Intel Xeon's MKL), nothing is verified and PyTorch stays in use
    replayed = {"q_verified", "fc_verified"} <= set(entries)
    assert replayed or not MODELLED_CPU, f"the replay was not verified on a modelled CPU ({cpu_vendor()})"
    # the kept settings hold whatever the run's size: a short second run shows it (the first needs its near ties)
    second = imported_modules("run", "--n", "100", "--seed", "1", "--db", str(tmp_path / "b.db"), "--quiet")
    assert "sqlalchemy" in second
    # replayed: no PyTorch at all; else PyTorch decides the near ties the short run meets, if it meets any
    assert "torch" not in second or not replayed


# --- the lint rule that keeps the commands light ----------------------------------------------------------------------
# Ruff's banned-module-level-imports (TID253) for src/vinadv/commands/ (its ruff.toml; vinadv.cluster extends it) names
# the heavy libraries of pyproject.toml, NumPy, and every vinadv module that imports one of them at module level; these
# tests keep that list exact as modules change.

SRC = Path(__file__).resolve().parent.parent / "src"


def module_level_imports(path: Path, name: str) -> set[str]:
    """The modules a module's import statements name outside functions (`if TYPE_CHECKING:` blocks aside); for
    `from A import b`, both `A` and `A.b` (b may be a module)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()

    def visit(body) -> None:
        for node in body:
            if isinstance(node, ast.Import):
                found.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = package.split(".")[: len(package.split(".")) - node.level + 1] if node.level else []
                module = ".".join([*base, *([node.module] if node.module else [])])
                found.add(module)
                found.update(f"{module}.{alias.name}" for alias in node.names)
            elif isinstance(node, ast.If):
                if "TYPE_CHECKING" not in ast.unparse(node.test):
                    visit(node.body)
                visit(node.orelse)
            elif isinstance(node, ast.Try):
                for block in (node.body, node.orelse, node.finalbody, *(h.body for h in node.handlers)):
                    visit(block)
            elif isinstance(node, ast.With | ast.ClassDef):
                visit(node.body)

    visit(ast.parse(path.read_text()).body)
    return found


def heavy_vinadv_modules(libraries: set[str]) -> set[str]:
    """The vinadv modules whose import loads one of `libraries`: those importing one at module level, through any
    chain of vinadv imports (importing `a.b.c` runs `a` and `a.b` first). A package whose names load lazily (a module
    `__getattr__`) counts as importing each of its modules wherever a name is imported from it."""
    imports, lazy = {}, set()
    for path in sorted((SRC / "vinadv").rglob("*.py")):
        name = ".".join(path.relative_to(SRC).with_suffix("").parts).removesuffix(".__init__")
        imports[name] = module_level_imports(path, name)
        if path.name == "__init__.py" and re.search(r"^def __getattr__", path.read_text(), re.M):
            lazy.add(name)
    for found in imports.values():
        found.update(m for m in imports if any(m.startswith(f"{p}.") for p in found & lazy))

    def loads(module: str) -> set[str]:
        """`module` and its packages, as far as they are vinadv modules."""
        parts = module.split(".")
        return {".".join(parts[:i]) for i in range(1, len(parts) + 1)} & imports.keys()

    heavy = {name for name, found in imports.items() if {m.split(".")[0] for m in found} & libraries}
    while True:
        more = {
            name
            for name, found in imports.items()
            if name not in heavy and (loads(name) - {name} | set().union(*map(loads, found))) & heavy
        }
        if not more:
            return heavy
        heavy |= more


def heavy_libraries() -> set[str]:
    """What the commands' start-up does without: pyproject.toml's banned-module-level-imports, and NumPy."""
    lint = tomllib.loads((SRC.parent / "pyproject.toml").read_text())["tool"]["ruff"]["lint"]
    return set(lint["flake8-tidy-imports"]["banned-module-level-imports"]) | {"numpy"}


def test_the_commands_lint_bans_exactly_the_heavy_libraries_and_vinadv_modules():
    libraries = heavy_libraries()
    commands = tomllib.loads((SRC / "vinadv" / "commands" / "ruff.toml").read_text())["lint"]
    banned = commands["flake8-tidy-imports"]["banned-module-level-imports"]
    heavy = heavy_vinadv_modules(libraries)
    # a heavy package's modules are all heavy (importing one runs the package): the package's name covers them
    expected = libraries | {m for m in heavy if m.rpartition(".")[0] not in heavy}
    assert len(banned) == len(set(banned))
    assert not set(banned) - expected, f"light (or gone): remove from commands/ruff.toml {set(banned) - expected}"
    assert not expected - set(banned), f"heavy: add to commands/ruff.toml {expected - set(banned)}"


def test_the_command_line_layer_imports_nothing_heavy_at_module_level():
    heavy = heavy_vinadv_modules(heavy_libraries())
    layer = {"vinadv.cli", "vinadv.commands", "vinadv.cluster"}
    assert not {m for m in heavy if m in layer or m.rpartition(".")[0] in layer}, "the CLI imports a heavy module"
    cluster = tomllib.loads((SRC / "vinadv" / "cluster" / "ruff.toml").read_text())
    assert cluster["extend"] == "../commands/ruff.toml"  # vinadv.cluster builds the run and attack parsers
