"""DESIGN.md's layout is the tree: every package and module it names exists, and every package of `src/vinadv/`
(and every top-level module) is named there, so the layout cannot go stale as code moves."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: the checkout's package (not `vinadv.__file__`: the layout is about this tree, whichever vinadv is imported)
SOURCE = ROOT / "src" / "vinadv"
#: an entry of the layout block: indentation, then `name/` (a folder) or `name.py` (a module), then its description
ENTRY = re.compile(r"^(?P<indent> *)(?P<name>[\w./]+/|\w+\.py)(?:\s|$)")


def layout_block(text: str) -> list[str]:
    """The lines of the code block under the `## Layout` heading."""
    section = text.split("\n## Layout", 1)[1]
    return section.split("```", 2)[1].splitlines()[1:]


def layout_paths(lines: list[str]) -> set[str]:
    """Repository-relative paths of the entries, nested by indentation (two spaces a level)."""
    paths, parents = set(), []
    for line in lines:
        match = ENTRY.match(line)
        if not match:
            continue
        depth = len(match["indent"]) // 2
        del parents[depth:]
        path = "/".join([*parents, match["name"].rstrip("/")])
        paths.add(path)
        if match["name"].endswith("/"):
            parents.append(match["name"].rstrip("/"))
    return paths


def test_layout_parser_nests_by_indentation():
    lines = ["src/vinadv/", "  grid/        maps", "    x.py  one", "  cli.py  the command", "tests/   pytest"]
    expected = {"src/vinadv", "src/vinadv/grid", "src/vinadv/grid/x.py", "src/vinadv/cli.py", "tests"}
    assert layout_paths(lines) == expected


def test_every_entry_of_the_layout_exists():
    paths = layout_paths(layout_block((ROOT / "DESIGN.md").read_text(encoding="utf-8")))
    assert "src/vinadv" in paths
    missing = sorted(p for p in paths if not (ROOT / p).exists())
    assert not missing, f"DESIGN.md's layout names what the tree lacks: {missing}"


def test_every_package_and_top_level_module_is_in_the_layout():
    paths = layout_paths(layout_block((ROOT / "DESIGN.md").read_text(encoding="utf-8")))
    packages = {str(p.parent.relative_to(ROOT)) for p in SOURCE.rglob("__init__.py") if "__pycache__" not in p.parts}
    modules = {str(p.relative_to(ROOT)) for p in SOURCE.glob("*.py") if p.name != "__init__.py"}
    unnamed = sorted((packages | modules) - paths)
    assert not unnamed, f"DESIGN.md's layout does not name: {unnamed}"
