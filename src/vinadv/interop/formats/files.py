"""The arrays of a foreign maps file (`.npz` or MATLAB `.mat`), read with checks whose errors name the file and
the array; and the checks of a foreign file that a reader reads whole (`check_file`, `ascii_text`)."""

from __future__ import annotations

import math
import os
import zipfile
from typing import Any

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.generator import available_memory


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


def check_file(path: str, max_bytes: int) -> None:
    """InputError naming `path` unless it is a file of at most `max_bytes` bytes (a reader that reads it whole)."""
    if not os.path.exists(path):
        raise InputError(f"{path}: no such file")
    if os.path.isdir(path):
        raise InputError(f"{path}: is a directory, expected a file")
    if os.path.getsize(path) > max_bytes:
        raise InputError(f"{path}: more than the {max_bytes} bytes read")


def ascii_text(path: str, data: bytes) -> str:
    """`data`, the bytes of the file at `path`, as ASCII text; InputError naming the first byte that is not ASCII."""
    try:
        return data.decode("ascii")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not an ASCII text file (byte {exc.start} is {data[exc.start]:#04x})") from None


def load_npz(path: str, names: tuple[str, ...] | None = None) -> ForeignArrays:
    """The arrays of the `.npz` file at `path` (only `names` where given, those it has: a split of a large file), their
    sizes checked from their headers before any is read (`check_npz_sizes`)."""
    if not os.path.exists(path):
        raise InputError(f"{path}: no such file")
    if not zipfile.is_zipfile(path):
        raise InputError(f"{path}: not an .npz file (not a zip archive)")
    try:
        with zipfile.ZipFile(path) as archive:
            check_npz_sizes(path, archive, names)
        with np.load(path, allow_pickle=False) as npz:
            return ForeignArrays(path, {k: npz[k] for k in npz.files if names is None or k in names})
    except InputError:
        raise
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise InputError(f"{path}: not a readable .npz file ({exc})") from None


def check_npz_sizes(path: str, archive: zipfile.ZipFile, names: tuple[str, ...] | None = None) -> None:
    """Refuse (InputError naming the file and the array) an array of `archive` (those of `names` where given) whose
    `.npy` header (read with `numpy.lib.format`, no data) claims more bytes than the archive holds for it (a forged
    header: NumPy would allocate what it claims before reading), or arrays that together claim more than half the
    memory available; a header that is not one is a damaged file."""
    total = 0
    for info in archive.infolist():
        if not info.filename.endswith(".npy"):
            continue
        name = info.filename[: -len(".npy")]
        if names is not None and name not in names:
            continue
        with archive.open(info) as fh:
            version = np.lib.format.read_magic(fh)
            read_header = (
                np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            )
            shape, _, dtype = read_header(fh)
            held = info.file_size - fh.tell()
        claimed = math.prod(shape) * dtype.itemsize
        if claimed > held:
            raise InputError(
                f"{path}: array '{name}' has a header that claims shape {shape} of {dtype} ({_size(claimed)}), "
                f"but the archive holds {_size(held)} for it"
            )
        total += claimed
    avail = available_memory()
    if total > avail // 2:
        raise InputError(f"{path}: the arrays read need {_size(total)}, more than half the {_size(avail)} available")


def _size(n_bytes: int) -> str:
    for unit, scale in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n_bytes >= scale:
            return f"{n_bytes / scale:,.1f} {unit}"
    return f"{n_bytes} bytes"


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
