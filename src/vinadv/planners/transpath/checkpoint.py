"""The TransPath authors' weights (`cf.pth`, `focal.pth`: a plain `torch.save` of their `Autoencoder`'s state dict),
read with the allow-list reader and checked key by key.

`vinadv.planners.torchfile.read_torch_file` reads the file without PyTorch's unpickler (tensors and an OrderedDict
only: nothing in it can run code; a damaged archive, NaN or infinite tensors refused); a file it does not follow is
read by `vinadv.planners.weights.torch_load` (`torch.load(weights_only=True)`, the same checks). The state dict must
hold exactly the keys and shapes of `vinadv.planners.transpath.model.TransPath` (158 tensors, all floating): anything
else is refused in one line naming the keys. The two models have the same keys, so the mode is the user's word
(`--mode cf|f`), recorded with the file's sha256.
"""

from __future__ import annotations

import os

import numpy as np
import torch

from vinadv.errors import InputError
from vinadv.planners.torchfile import read_torch_file
from vinadv.planners.transpath.model import TransPath
from vinadv.planners.weights import torch_load

__all__ = ["expected_shapes", "from_authors_state_dict"]

_SHOWN = 4  # keys named in a refusal before "(+n more)"


def _names(keys) -> str:
    keys = sorted(keys)
    shown = ", ".join(keys[:_SHOWN])
    return shown + (f" (+{len(keys) - _SHOWN} more)" if len(keys) > _SHOWN else "")


def expected_shapes() -> dict[str, tuple[int, ...]]:
    """The state-dict keys and shapes of the authors' model (either mode)."""
    return {k: tuple(v.shape) for k, v in TransPath("cf").state_dict().items()}


def _read(name: str) -> object:
    data = read_torch_file(name)
    return torch_load(name, "TransPath state dict") if data is None else data


def from_authors_state_dict(path: str | os.PathLike, mode: str) -> TransPath:
    """The TransPath model of `mode` (`cf` or `f`) in the authors' weights file `path`, in eval mode. Raises InputError
    naming the file and the keys for anything but the authors' `Autoencoder` state dict."""
    name = str(path)
    model = TransPath(mode)  # refuses another mode
    data = _read(name)
    if not isinstance(data, dict) or not data or not all(isinstance(k, str) for k in data):
        raise InputError(f"{name}: not a TransPath state dict (a mapping of names to tensors)")
    if "state_dict" in data and isinstance(data["state_dict"], dict):
        raise InputError(f"{name}: a training checkpoint; expected the authors' plain state dict (weights/*.pth)")
    not_arrays = [k for k, v in data.items() if not isinstance(v, np.ndarray | torch.Tensor)]
    if not_arrays:
        raise InputError(f"{name}: entries that are not tensors: {_names(not_arrays)}")
    expected = expected_shapes()
    unexpected, missing = set(data) - set(expected), set(expected) - set(data)
    if unexpected or missing:
        parts = [
            f"unexpected keys {_names(unexpected)}" if unexpected else "",
            f"missing {_names(missing)}" if missing else "",
        ]
        raise InputError(f"{name}: not the TransPath authors' model: " + "; ".join(p for p in parts if p))
    wrong = [f"{k} {tuple(data[k].shape)} (expected {s})" for k, s in expected.items() if tuple(data[k].shape) != s]
    if wrong:
        raise InputError(
            f"{name}: not the TransPath authors' model (64 channels, 4 blocks, 64x64): " + ", ".join(wrong[:_SHOWN])
        )
    state = {}
    for key, value in data.items():
        tensor = torch.from_numpy(np.array(value)) if isinstance(value, np.ndarray) else value.detach().clone()
        if not tensor.is_floating_point():
            raise InputError(f"{name}: tensor {key!r} is {tensor.dtype}, expected floating weights")
        state[key] = tensor.to(torch.float32)
    model.load_state_dict(state)
    return model.eval()
