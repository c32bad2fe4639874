"""Data flows one way (grid -> planners -> attacks -> classify -> identify -> store/report), and the packages import
each other in one order: no import circle between them and no reaching back upstream, counting the imports inside
functions too (they run all the same). The store is a sink that knows only grids and the vocabulary, so the stages
that hand it their results (identify, robustness, pipeline, evaluation) may import it.

The report only reads: what it shows is stored (the evaluation stage computes it), so besides the layers it may not
import the planners, the evaluation stage or classifier training; of `vinadv.classify` it may use only the exact
rule labeller, the path pair batch, the harm summary, the path features and the path images it draws
(`REPORT_CLASSIFY`)."""

import ast
import functools
from pathlib import Path

import vinadv

SOURCE = Path(vinadv.__file__).parent

#: each top-level module or package of vinadv and its layer: a module may import only lower layers and its own package
LAYERS = {
    "vinadv": 0,
    "errors": 0,
    "vocabulary": 1,
    # the Wilson interval of every rate, from its counts: the bench, the report, robustness and analysis read it
    "intervals": 1,
    "seeds": 1,
    # how a figure is shown (rounded, float noise as 0): every page, table and command's text
    "display": 1,
    "checksums": 1,
    # where a job's chunks run (in this process; the Dask executor is the cluster's): knows no job
    "executor": 2,
    "outfile": 1,
    "jsonfile": 1,
    # the records stored as JSON, their versions and their one upgrade at read: every reader and writer imports it
    "records": 1,
    "npzfile": 2,
    "grid": 3,
    "planners": 4,
    "interop": 5,
    "attacks": 5,
    "classify": 5,
    "identify": 6,
    # drawing maps, pairs, value maps and k curves in one palette: the report, the viewer and the commands draw with it
    "plot": 6,
    # support code for tests and benchmarks: synthetic weights, records and pairs for what lies below it; no
    # production module imports it (test_production_code_never_imports_the_test_support)
    "testing": 6,
    "store": 4,
    "hardening": 7,
    # the jobs without an engine module of their own (vinadv attack), and the one attack call every job makes
    "jobs": 7,
    "robustness": 8,
    "pipeline": 8,
    "evaluation": 8,
    "report": 9,
    "bench": 9,
    # the exact k = 2 diagnostic: the pair search judged by harm, against a robustness run's greedy
    "exact_k2": 9,
    # shows the bench's leaderboard (`vinadv serve --bench`)
    "viewer": 10,
    # runs the stages on workers, the benchmark's chunks included; only the commands import it
    "cluster": 10,
    "analysis": 10,
    "commands": 11,
    "cli": 12,
}

#: the imports that run upward on purpose: the package's `vinadv.open` imports `vinadv.analysis` when called (and
#: for type checkers only), so that `import vinadv` stays light
LAZY_EXPORTS = {("vinadv", "analysis")}


#: what the report may not import though it is a lower layer: computing (planning, evaluating, training) is the
#: evaluation stage's job
REPORT_FORBIDDEN = ("planners", "evaluation", "attacks", "identify", "pipeline", "hardening", "robustness")
#: the modules of `vinadv.classify` the report may import (none trains a classifier; the package itself is refused,
#: its lazy names reach the trained models)
REPORT_CLASSIFY = ("rule", "batch", "harm", "features", "images")


def imported_vinadv_modules(path: Path) -> set[str]:
    """Full `vinadv.X.Y` module names imported anywhere in the file (`from vinadv.X import Y` counts as `vinadv.X`
    unless `vinadv.X.Y` is a module of `SOURCE`)."""
    modules = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            for alias in node.names:
                candidate = f"{node.module}.{alias.name}"
                parts = candidate.split(".")[1:]
                is_module = (SOURCE.joinpath(*parts).with_suffix(".py")).exists() or SOURCE.joinpath(*parts).is_dir()
                modules.add(candidate if is_module else node.module)
        elif isinstance(node, ast.Import):
            modules.update(a.name for a in node.names)
    return {m for m in modules if m.split(".")[0] == "vinadv"}


@functools.cache
def parsed(path: Path) -> ast.Module:
    """The file's syntax tree, parsed once for all the checks here (walking every module is the checks' cost)."""
    return ast.parse(path.read_text(encoding="utf-8"))


@functools.cache
def imported_vinadv_names(path: Path) -> frozenset[str]:
    """`vinadv.X` names imported anywhere in the file (module level or inside functions)."""
    names = set()
    for node in ast.walk(parsed(path)):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            modules = [node.module] if node.module != "vinadv" else [f"vinadv.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            modules = [a.name for a in node.names]
        else:
            continue
        for module in modules:
            parts = module.split(".")
            if parts[0] == "vinadv":
                # `from vinadv import __version__` imports the package itself
                names.add(parts[1] if len(parts) > 1 and parts[1] in LAYERS else "vinadv")
    return frozenset(names)


def part_of(path: Path) -> str:
    rel = path.relative_to(SOURCE)
    return rel.parts[0] if len(rel.parts) > 1 else ("vinadv" if rel.stem == "__init__" else rel.stem)


def test_every_module_has_a_layer():
    parts = {part_of(p) for p in SOURCE.rglob("*.py")}
    assert parts == set(LAYERS)


def test_no_module_imports_its_own_layer_or_above():
    upstream_imports = []
    for path in sorted(SOURCE.rglob("*.py")):
        own = part_of(path)
        for name in imported_vinadv_names(path) - {own}:
            if LAYERS[name] >= LAYERS[own] and (own, name) not in LAZY_EXPORTS:
                upstream_imports.append(f"{path.relative_to(SOURCE)} imports vinadv.{name}")
    assert not upstream_imports, upstream_imports


def test_relative_imports_are_not_used():
    # the layer check reads absolute imports only
    for path in SOURCE.rglob("*.py"):
        assert not [n for n in ast.walk(parsed(path)) if isinstance(n, ast.ImportFrom) and n.level], path


def test_the_report_only_reads():
    reaching = []
    for path in sorted((SOURCE / "report").rglob("*.py")):
        for module in imported_vinadv_modules(path):
            parts = module.split(".")
            if len(parts) > 1 and parts[1] in REPORT_FORBIDDEN:
                reaching.append(f"{path.relative_to(SOURCE)} imports {module}")
            if len(parts) > 1 and parts[1] == "classify" and (len(parts) < 3 or parts[2] not in REPORT_CLASSIFY):
                reaching.append(f"{path.relative_to(SOURCE)} imports {module}")
    assert not reaching, reaching


def test_the_report_check_sees_a_forbidden_import(tmp_path):
    # the check's own oracle: each line below is one import the report may not make
    source = tmp_path / "x.py"
    source.write_text(
        "from vinadv.classify import label_batch\nimport vinadv.classify.models\n"
        "from vinadv.planners.registry import load_planner\nfrom vinadv.classify.rule import label_batch\n"
    )
    assert imported_vinadv_modules(source) == {
        "vinadv.classify",
        "vinadv.classify.models",
        "vinadv.planners.registry",
        "vinadv.classify.rule",
    }


def test_production_code_never_imports_the_test_support():
    importers = [
        str(path.relative_to(SOURCE))
        for path in sorted(SOURCE.rglob("*.py"))
        if part_of(path) != "testing" and "testing" in imported_vinadv_names(path)
    ]
    assert not importers, importers


#: the planner families: a package each under `vinadv.planners`
PLANNER_FAMILIES = ("vin", "gppn", "neural_astar", "transpath", "classical")
#: the contract and the mechanics every planner shares (`vinadv.planners` outside the families and the registry)
PLANNER_CONTRACT = (
    "interface",
    "search",
    "checks",
    "result",
    "rollout",
    "batching",
    "device",
    "spec",
    "records",
    "harness",
)


def test_the_planner_contract_imports_no_family():
    # a family builds on the contract, never the other way; only the registry (and the families) name families
    reaching = []
    for name in PLANNER_CONTRACT:
        path = SOURCE / "planners" / f"{name}.py"
        for module in imported_vinadv_modules(path):
            parts = module.split(".")
            if parts[1:2] == ["planners"] and len(parts) > 2 and parts[2] in PLANNER_FAMILIES:
                reaching.append(f"planners/{name}.py imports {module}")
    assert not reaching, reaching
    packages = {p.name for p in (SOURCE / "planners").iterdir() if (p / "__init__.py").exists()}
    assert packages == {*PLANNER_FAMILIES, "registry"}
