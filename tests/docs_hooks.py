"""The scripts of docs/ as the tests load them: `docs/hooks.py` and the module it imports, as MkDocs runs a hook."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
WEIGHTS = ROOT / "src" / "vinadv" / "weights"


def docs_module(name: str) -> ModuleType:
    """A script of docs/ (not a package) loaded from its file, with docs/ on the path while it loads, as MkDocs loads
    a hook: `hooks.py` imports its sibling `measured.py`."""
    spec = importlib.util.spec_from_file_location(f"docs_{name}", DOCS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(DOCS))
    try:
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(DOCS))
    return module


def filled_page(page: str) -> str:
    """docs/PAGE as the site shows it: the hook's text in place of every marker, none left unfilled."""
    filled = docs_module("hooks").on_page_markdown((DOCS / page).read_text(), page=None, config=None, files=None)
    assert "<!-- vinadv:" not in filled, f"docs/{page}: a marker the hook does not know"
    return filled
