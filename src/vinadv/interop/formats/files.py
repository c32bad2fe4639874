"""The arrays of a foreign maps file (`.npz` or MATLAB `.mat`), read with checks whose errors name the file and
the array."""

from __future__ import annotations

import os
import zipfile
from typing import Any

import numpy as np

from vinadv.errors import InputError


class ForeignArrays:
    """The arrays of one foreign file, with checks whose errors name the file and the array."""

    def __init__(self, path: str | os.PathLike, data: dict[str, Any]):
        self.path, self.data = str(path), data

    def fail(self, name: str, problem: str) -> InputError:
        return InputError(f"{self.path}: array '{name}' {problem}")

    def has(self, name: str) -> bool:
        return name in self.data

    def get(self, name: str, ndim: int, shape: tuple[int | None, ...] = ()) -> np.ndarray:
        if name not in self.data:
            raise InputError(f"{self.path}: array '{name}' is missing (has {sorted(self.data)[:12]})")
        arr = np.asarray(self.data[name])
        if arr.dtype.kind not in "biuf":
            raise self.fail(name, f"has dtype {arr.dtype}, expected numbers")
        if arr.ndim != ndim:
            raise self.fail(name, f"has shape {arr.shape}, expected {ndim} dimensions")
        for axis, want in enumerate(shape):
            if want is not None and arr.shape[axis] != want:
                raise self.fail(name, f"has shape {arr.shape}, expected size {want} on axis {axis}")
        return arr

    def integers(self, name: str, arr: np.ndarray, lo: int, hi: int) -> np.ndarray:
        """`arr` as int64, every value an integer in `lo..hi`."""
        if arr.size and (np.any(arr != np.round(arr)) or arr.min() < lo or arr.max() > hi):
            raise self.fail(name, f"has values outside the integers {lo}..{hi}")
        return arr.astype(np.int64)


def load_npz(path: str, names: tuple[str, ...] | None = None) -> ForeignArrays:
    """The arrays of the `.npz` file at `path` (only `names` where given, those it has: a split of a large file)."""
    if not os.path.exists(path):
        raise InputError(f"{path}: no such file")
    if not zipfile.is_zipfile(path):
        raise InputError(f"{path}: not an .npz file (not a zip archive)")
    try:
        with np.load(path, allow_pickle=False) as npz:
            return ForeignArrays(path, {k: npz[k] for k in npz.files if names is None or k in names})
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise InputError(f"{path}: not a readable .npz file ({exc})") from None


def load_mat(path: str) -> ForeignArrays:
    import scipy.io
    import scipy.io.matlab

    if not os.path.exists(path):
        raise InputError(f"{path}: no such file")
    try:
        data = scipy.io.loadmat(path)
    except (ValueError, OSError, TypeError, NotImplementedError, scipy.io.matlab.MatReadError) as exc:
        raise InputError(f"{path}: not a readable MATLAB .mat file ({exc})") from None
    return ForeignArrays(path, {k: v for k, v in data.items() if not k.startswith("__")})
