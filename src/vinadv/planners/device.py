"""The torch device a planner runs its forward on: `--device cpu|cuda|cuda:N|auto`, checked before any work.

`resolve_device(name)` turns a name into a `torch.device` or refuses it with one line (`InputError` naming the
parameter `device`): a name torch does not read, CUDA on a machine without it, a GPU index the machine lacks. `auto`
is CUDA where it is available, else the CPU. PyTorch is imported when a name is resolved, not before: a command
that plans with the VIN's exact engine (no `--device`) never loads it.

`full_precision(device)`: the planners' forwards on a GPU run in float32 as on the CPU. PyTorch lets cuDNN compute
convolutions in TF32 (a 10-bit mantissa) by default, which moves logits by about 1e-3 of their size and would
break near ties far more often than the order of float32 sums does; inside the block it may not (restored after).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import TYPE_CHECKING

from vinadv.errors import InputError

if TYPE_CHECKING:
    import torch

#: the device names the commands take (`--device`), in words
DEVICE_NAMES = "cpu, cuda, cuda:N or auto"
#: the name that picks CUDA where available, else the CPU
AUTO = "auto"


def resolve_device(name: str) -> torch.device:
    """The device `name` names (`cpu`, `cuda`, `cuda:N`, `auto`; `mps` where PyTorch has it), or `InputError`."""
    import torch

    name = str(name).strip()
    if name == AUTO:
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    try:
        device = torch.device(name)
    except (RuntimeError, ValueError):
        raise InputError(f"device {name!r} is not a device; use {DEVICE_NAMES}", "device") from None
    if device.type == "cuda":
        if not torch.cuda.is_available():
            raise InputError(f"device {name!r}: CUDA is not available on this machine; use cpu or auto", "device")
        count = torch.cuda.device_count()
        if device.index is not None and device.index >= count:
            raise InputError(
                f"device {name!r}: this machine has {count} CUDA device(s), cuda:0..cuda:{count - 1}", "device"
            )
    elif device.type == "mps":
        if not torch.backends.mps.is_available():
            raise InputError(f"device {name!r}: MPS is not available on this machine; use cpu or auto", "device")
    elif device.type != "cpu":
        raise InputError(f"device {name!r}: use {DEVICE_NAMES}", "device")
    return device


def cuda_available() -> bool:
    """Whether PyTorch sees a CUDA device here."""
    import torch

    return bool(torch.cuda.is_available())


@contextlib.contextmanager
def full_precision(device: torch.device) -> Iterator[None]:
    """float32 convolutions and matrix products on `device` inside the block (no TF32 on a GPU); nothing on the CPU."""
    if device.type != "cuda":
        yield
        return
    import torch

    matmul = torch.backends.cuda.matmul.allow_tf32
    torch.backends.cuda.matmul.allow_tf32 = False
    try:
        with torch.backends.cudnn.flags(enabled=torch.backends.cudnn.enabled, allow_tf32=False):
            yield
    finally:
        torch.backends.cuda.matmul.allow_tf32 = matmul
