"""The tensors and plain values of a `torch.save` file, read without PyTorch: the VIN planner's weights reach its
NumPy engine without the second or two that importing PyTorch costs.

Reads the zip format PyTorch writes (since 1.6): `<dir>/data.pkl`, a pickle whose tensors are calls
`torch._utils._rebuild_tensor_v2(storage, offset, size, stride, requires_grad, hooks[, metadata])` on storages kept
as `<dir>/data/<key>` (persistent ids `("storage", torch.<Type>Storage, key, location, numel)`), little-endian.
Only those names and `collections.OrderedDict` are accepted, so, as with `torch.load(weights_only=True)`, a file
cannot run code. Anything else (the legacy format, other classes, big-endian storages, dtypes NumPy lacks such as
bfloat16, a view outside its storage) gives None: the caller reads that file with PyTorch, which also words its
errors.

A file this reader finds damaged is never handed to PyTorch, which checks less: a zip archive whose members fail
their CRC-32 (`check_archive`: PyTorch's reader does not check it, and would load a flipped byte of tensor data as
other weights), a storage of the wrong length or a truncated pickle raise InputError naming the file. So do
floating tensors holding NaN or infinities (`check_finite`): no planner plans with them.
"""

from __future__ import annotations

import collections
import io
import os
import pickle
import zipfile

import numpy as np

from vinadv.errors import InputError

_STORAGE_DTYPES = {
    "FloatStorage": np.float32,
    "DoubleStorage": np.float64,
    "HalfStorage": np.float16,
    "LongStorage": np.int64,
    "IntStorage": np.int32,
    "ShortStorage": np.int16,
    "CharStorage": np.int8,
    "ByteStorage": np.uint8,
    "BoolStorage": np.bool_,
}


class _Unsupported(Exception):
    """Something this reader does not handle: PyTorch reads the file instead."""


class _Damaged(Exception):
    """A zip archive torch.save wrote whose content is not what it says: refused, never read by PyTorch."""


def check_archive(path: str | os.PathLike, archive: zipfile.ZipFile | None = None) -> None:
    """InputError naming `path` when it is a zip archive with a member whose CRC-32 does not match its bytes (a member
    stored without one, CRC 0, as `torch.serialization.config.save.compute_crc32 = False` writes, is not checked);
    nothing for a file that is not a zip archive (PyTorch's legacy format)."""
    try:
        if archive is None:
            if not zipfile.is_zipfile(path):
                return
            with zipfile.ZipFile(path) as opened:
                check_archive(path, opened)
            return
        for info in archive.infolist():
            if info.CRC == 0 and info.file_size:
                continue
            with archive.open(info) as fh:  # ZipExtFile checks the CRC-32 when the member is read to its end
                while fh.read(1 << 20):
                    pass
    except (zipfile.BadZipFile, EOFError, OSError, ValueError, NotImplementedError) as exc:
        why = str(exc).splitlines()[0] if str(exc) else "truncated"
        raise InputError(f"{path}: a damaged weights file ({why})") from None


def check_finite(path: str | os.PathLike, data, where: str = "") -> None:
    """InputError naming `path` and the entry when a floating array (NumPy, or a torch tensor) in `data` (dicts,
    lists and tuples of them, nested) holds NaN or an infinity."""
    if isinstance(data, dict):
        for key, value in data.items():
            check_finite(path, value, f"{where}.{key}" if where else str(key))
        return
    if isinstance(data, (list, tuple)):
        for i, value in enumerate(data):
            check_finite(path, value, f"{where}[{i}]")
        return
    if isinstance(data, np.ndarray):
        bad = data.dtype.kind in "fc" and not np.isfinite(data).all()
    elif hasattr(data, "is_floating_point") and hasattr(data, "isfinite"):  # a torch tensor
        bad = bool(data.is_floating_point() and not data.isfinite().all())
    else:
        return
    if bad:
        raise InputError(f"{path}: tensor '{where}' holds NaN or infinite values: not usable weights")


def _rebuild_tensor(storage, offset, size, stride, requires_grad=False, hooks=None, metadata=None) -> np.ndarray:
    """`torch._utils._rebuild_tensor_v2` as a NumPy array (a copy), checked to lie inside its storage."""
    if hooks or not isinstance(storage, np.ndarray):
        raise _Unsupported("backward hooks or a tensor without a storage")
    size, stride = tuple(int(s) for s in size), tuple(int(s) for s in stride)
    if len(size) != len(stride) or min(size, default=1) < 0 or min(stride, default=0) < 0 or offset < 0:
        raise _Unsupported("a malformed view")
    if 0 in size:
        return np.empty(size, dtype=storage.dtype)
    last = offset + sum((n - 1) * s for n, s in zip(size, stride))
    if last >= len(storage):
        raise _Unsupported("a view outside its storage")
    view = np.lib.stride_tricks.as_strided(
        storage[offset:], shape=size, strides=[s * storage.itemsize for s in stride], writeable=False
    )
    return np.array(view)


class _Unpickler(pickle.Unpickler):
    def __init__(self, data: bytes, archive: zipfile.ZipFile, prefix: str):
        super().__init__(io.BytesIO(data))
        self.archive, self.prefix, self.storages = archive, prefix, {}

    def find_class(self, module: str, name: str):
        if (module, name) == ("torch._utils", "_rebuild_tensor_v2"):
            return _rebuild_tensor
        if (module, name) == ("collections", "OrderedDict"):
            return collections.OrderedDict
        if module == "torch" and name in _STORAGE_DTYPES:
            return np.dtype(_STORAGE_DTYPES[name])
        raise _Unsupported(f"{module}.{name}")

    def persistent_load(self, pid):
        if not (isinstance(pid, tuple) and len(pid) == 5 and pid[0] == "storage" and isinstance(pid[1], np.dtype)):
            raise _Unsupported("a persistent id other than a storage")
        dtype, key, numel = pid[1], str(pid[2]), int(pid[4])
        if key not in self.storages:
            try:
                raw = self.archive.read(f"{self.prefix}data/{key}")
            except KeyError:
                raise _Damaged(f"no storage {key}") from None
            if len(raw) != numel * dtype.itemsize:
                raise _Damaged(f"storage {key} holds {len(raw)} bytes, not {numel * dtype.itemsize}")
            self.storages[key] = np.frombuffer(raw, dtype=dtype)
        return self.storages[key]


def read_torch_file(path: str | os.PathLike) -> object | None:
    """The object `torch.load(path, weights_only=True)` gives, with NumPy arrays for tensors; None when this reader
    cannot read the file (see the module docstring: the caller reads it with PyTorch). InputError naming the file for
    a damaged zip archive (a member failing its CRC-32, a missing or short storage, a truncated pickle) and for
    floating tensors holding NaN or infinities: such a file is never handed to a reader that checks less."""
    try:
        archive = zipfile.ZipFile(path)
    except (OSError, zipfile.BadZipFile, EOFError, ValueError):
        return None  # not a zip archive (PyTorch's legacy format), or unreadable: PyTorch words it
    with archive:
        check_archive(path, archive)
        try:
            names = archive.namelist()
            pickles = [n for n in names if n.endswith("/data.pkl") and n.count("/") == 1]
            if len(pickles) != 1:
                return None
            prefix = pickles[0][: -len("data.pkl")]
            if prefix + "byteorder" in names and archive.read(prefix + "byteorder").strip() != b"little":
                return None
            data = _Unpickler(archive.read(pickles[0]), archive, prefix).load()
        except _Unsupported:
            return None
        except _Damaged as exc:
            raise InputError(f"{path}: a damaged weights file ({exc})") from None
        except (EOFError, pickle.UnpicklingError) as exc:
            raise InputError(f"{path}: a damaged weights file (its pickle: {type(exc).__name__})") from None
        except (KeyError, ValueError, AttributeError, TypeError, IndexError, RecursionError):
            return None  # a pickle this reader does not follow: PyTorch reads it, or words its error
    check_finite(path, data)
    return data
