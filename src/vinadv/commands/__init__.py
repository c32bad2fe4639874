"""Subcommands of `vinadv`; each module has `register(subparsers)`.

Building the parser must stay light (`vinadv --help` and `--version` import no PyTorch, Numba, scikit-learn or
SQLAlchemy): a command module imports what its command needs inside the command's function, and reads names
that live in heavy modules through `LazyChoices`.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator


class LazyChoices:
    """argparse `choices` taken from `module.attribute` (any iterable of names) only when argparse needs them: to
    check a value given on the command line, or for the command's own `--help`."""

    def __init__(self, module: str, attribute: str) -> None:
        self.module, self.attribute = module, attribute
        self._names: tuple[str, ...] | None = None

    def _load(self) -> tuple[str, ...]:
        if self._names is None:
            self._names = tuple(getattr(importlib.import_module(self.module), self.attribute))
        return self._names

    def __contains__(self, value: object) -> bool:
        return value in self._load()

    def __iter__(self) -> Iterator[str]:
        return iter(self._load())
