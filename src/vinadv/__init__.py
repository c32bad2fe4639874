"""vinadv: adversarial maps for learned path planners (see README.md and the docs).

`vinadv.open(url)` opens a database's results as pandas DataFrames (`vinadv.analysis`); that module is imported on
first use, so `import vinadv` stays light.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from vinadv.analysis import Results

__version__ = "0.1.0"


# named as the builtin it shadows here only (nothing in this module opens a file): `vinadv.open(url)`
def open(url: str | None = None) -> Results:
    """Open the vinadv database at `url` for reading, as `vinadv.analysis.Results` (`vinadv.analysis.open`)."""
    # the package's one upward import (the layering test allows it), made when called: pandas, pyarrow and the store
    # load then, not with `import vinadv`
    from vinadv.analysis import open as open_results  # noqa: PLC0415

    return open_results(url)


def lazy_names(package: str, modules: dict[str, tuple[str, ...]]) -> tuple[list[str], Callable, Callable]:
    """A package's names imported from their modules when first used (PEP 562): `modules` lists the names by the
    submodule of `package` that defines them. Returns the lazy names (the package's `__all__`, or part of it), its
    `__getattr__` and its `__dir__` (the package's own names and the lazy ones); a name, once imported, is kept in the
    package."""
    exports = {name: module for module, names in modules.items() for name in names}
    names = sorted(exports)

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | exports.keys())

    return names, __getattr__, __dir__
