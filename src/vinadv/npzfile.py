"""Reading and writing vinadv's NPZ files: a `format` entry names kind and version, every field is checked.

Every error names the file and the field, so a user knows what to fix.
"""

from __future__ import annotations

import json
import os
import zipfile
from collections.abc import Mapping
from typing import Any

import numpy as np

from vinadv.errors import InputError, first_line
from vinadv.outfile import atomic_output


def save_npz(path: str | os.PathLike, fmt: str, arrays: Mapping[str, Any]) -> None:
    """Write `arrays` plus `format=fmt` to `path`, atomically (a crash never leaves half a file)."""
    with atomic_output(path, "wb", mkdir=True) as fh:
        np.savez(fh, format=np.array(fmt), **{k: np.asarray(v) for k, v in arrays.items()})


class NpzReader:
    """Checked access to the fields of one vinadv NPZ file of format `fmt` or one of the `older` versions it still
    reads; `format` is the one found."""

    def __init__(self, path: str | os.PathLike, fmt: str, older: tuple[str, ...] = ()):
        self.path = str(path)
        if not os.path.exists(self.path):
            raise InputError(f"{self.path}: no such file")
        if not zipfile.is_zipfile(self.path):
            raise InputError(f"{self.path}: not an .npz file (not a zip archive)")
        try:
            self._data = dict(np.load(self.path, allow_pickle=False))
        except Exception as exc:  # noqa: BLE001 - zipfile and numpy raise a dozen types for a damaged archive
            raise InputError(f"{self.path}: not a readable .npz file ({first_line(exc)})") from None
        found = self._data.get("format")
        found = str(found) if found is not None and found.ndim == 0 else None
        self.format = found
        if found != fmt and found not in older:
            kind = fmt.split("/")[0]
            if found is None:
                raise InputError(f"{self.path}: field 'format' missing; not a {kind} file")
            if found.split("/")[0] == kind:
                raise InputError(f"{self.path}: format '{found}' is not supported (expected '{fmt}')")
            raise InputError(f"{self.path}: format '{found}' is not a {kind} file (expected '{fmt}')")

    def has(self, name: str) -> bool:
        return name in self._data

    def ndim(self, name: str) -> int | None:
        """The number of dimensions of field `name` (None when it is missing), for fields of several layouts."""
        return self._data[name].ndim if name in self._data else None

    def fail(self, name: str, problem: str) -> InputError:
        return InputError(f"{self.path}: field '{name}' {problem}")

    def array(self, name: str, kind: str, ndim: int, shape: tuple[int | None, ...] | None = None) -> np.ndarray:
        """Field `name`, of dtype kind `kind` ('b' bool, 'i' integer, 'f' float, 'U' string), `ndim` dims.

        `shape` entries that are not None must match.
        """
        if name not in self._data:
            raise self.fail(name, "is missing")
        arr = self._data[name]
        ok_kind = (
            arr.dtype.kind == kind
            or (kind == "i" and arr.dtype.kind == "u")
            or (kind == "f" and arr.dtype.kind in "iu")
        )
        if not ok_kind:
            raise self.fail(name, f"has dtype {arr.dtype}, expected {_KIND_NAMES[kind]}")
        if arr.ndim != ndim:
            raise self.fail(name, f"has shape {arr.shape}, expected {ndim} dimensions")
        if shape is not None:
            for axis, (got, want) in enumerate(zip(arr.shape, shape)):
                if want is not None and got != want:
                    raise self.fail(name, f"has shape {arr.shape}, expected size {want} on axis {axis}")
        return arr

    def scalar(self, name: str, kind: str, default: Any = None) -> Any:
        if name not in self._data:
            if default is not None:
                return default
            raise self.fail(name, "is missing")
        return self.array(name, kind, 0).item()

    def json(self, name: str) -> Any:
        text = self.scalar(name, "U")
        try:
            return json.loads(text)
        except json.JSONDecodeError as exc:
            raise self.fail(name, f"is not valid JSON ({exc})") from None


_KIND_NAMES = {"b": "bool", "i": "integer", "f": "float", "U": "string"}


def check_cells_in_grid(reader: NpzReader, name: str, cells: np.ndarray, size: int) -> None:
    if cells.size and (cells.min() < 0 or cells.max() >= size):
        raise reader.fail(name, f"has a cell outside the {size}x{size} grid")


def check_offsets(reader: NpzReader, name: str, offsets: np.ndarray, n: int, total: int) -> None:
    if len(offsets) != n + 1:
        raise reader.fail(name, f"has {len(offsets)} entries, expected {n + 1}")
    if offsets[0] != 0 or offsets[-1] != total or np.any(np.diff(offsets) < 1):
        raise reader.fail(name, f"is not increasing from 0 to {total} (every path needs at least one cell)")
