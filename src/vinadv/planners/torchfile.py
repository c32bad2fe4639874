"""The tensors and plain values of a `torch.save` file, read without PyTorch: the VIN planner's weights reach its
NumPy engine without the second or two that importing PyTorch costs.

Reads the zip format PyTorch writes (since 1.6): `<dir>/data.pkl`, a pickle whose tensors are calls
`torch._utils._rebuild_tensor_v2(storage, offset, size, stride, requires_grad, hooks[, metadata])` on storages kept
as `<dir>/data/<key>` (persistent ids `("storage", torch.<Type>Storage, key, location, numel)`), little-endian.
Only those names and `collections.OrderedDict` are accepted, so, as with `torch.load(weights_only=True)`, a file
cannot run code. Anything else (the legacy format, other classes, big-endian storages, dtypes NumPy lacks such as
bfloat16, a view outside its storage) gives None: the caller reads that file with PyTorch, which also words its
errors.
"""

from __future__ import annotations

import collections
import io
import os
import pickle
import zipfile

import numpy as np

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
            raw = self.archive.read(f"{self.prefix}data/{key}")
            if len(raw) != numel * dtype.itemsize:
                raise _Unsupported("a storage of the wrong length")
            self.storages[key] = np.frombuffer(raw, dtype=dtype)
        return self.storages[key]


def read_torch_file(path: str | os.PathLike) -> object | None:
    """The object `torch.load(path, weights_only=True)` gives, with NumPy arrays for tensors; None when this reader
    cannot read the file (see the module docstring), including a damaged or missing one."""
    try:
        with zipfile.ZipFile(path) as archive:
            names = archive.namelist()
            pickles = [n for n in names if n.endswith("/data.pkl") and n.count("/") == 1]
            if len(pickles) != 1:
                return None
            prefix = pickles[0][: -len("data.pkl")]
            if prefix + "byteorder" in names and archive.read(prefix + "byteorder").strip() != b"little":
                return None
            return _Unpickler(archive.read(pickles[0]), archive, prefix).load()
    except (_Unsupported, OSError, zipfile.BadZipFile, KeyError, EOFError, ValueError, pickle.UnpicklingError):
        return None
    except (AttributeError, TypeError, IndexError, RecursionError):  # a malformed pickle: PyTorch words its error
        return None
