"""Weights for and from other VIN/GPPN code.

- `export_state_dict`: a plain state dict with exactly the port's keys `h.weight h.bias r.weight q.weight w
  fc.weight` (float32, CPU), which `torch.load(weights_only=True)` reads and the kentsommer port's VIN class loads.
- `read_checkpoint`: a GPPN training checkpoint (`{"model": state dict, "best_model": state dict, ...}`, metadata
  with numpy float64 values) read with torch's weights-only unpickler plus an allow-list of numpy's scalar/array
  reconstructors and `argparse.Namespace`: no other object can be built, so a checkpoint cannot run code. It returns
  the state dict and the metadata generically (any model: VIN keys `h r q w policy`, GPPN keys `hid h0 c0 conv
  lstm policy`).
- `gppn_vin_gaps`: what vinadv's VIN lacks to represent a GPPN VIN; such a checkpoint is refused with that list.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

import numpy as np
import torch

from vinadv.errors import InputError
from vinadv.interop.formats.gppn import GPPN_TO_VINADV
from vinadv.outfile import save_torch
from vinadv.planners.gppn import GPPN, GPPNConfig
from vinadv.planners.vin.arrays import STATE_KEYS
from vinadv.planners.vin.model import VIN
from vinadv.planners.weights import torch_load

GPPN_VIN_KEYS = ("h.weight", "h.bias", "r.weight", "q.weight", "w", "policy.weight")


def export_state_dict(model: VIN, path: str | os.PathLike) -> dict[str, tuple[int, ...]]:
    """Write `model`'s weights as a plain state dict (exactly STATE_KEYS, float32, CPU); returns key -> shape."""
    state = model.state_dict()
    plain = {key: state[key].detach().to("cpu", torch.float32).contiguous().clone() for key in STATE_KEYS}
    save_torch(plain, path, mkdir=True)
    return {key: tuple(value.shape) for key, value in plain.items()}


def _allowed_globals() -> list:
    """numpy's pickling helpers under both the numpy 2 (`numpy._core`) and numpy 1 (`numpy.core`) names."""
    core = np._core.multiarray if hasattr(np, "_core") else np.core.multiarray  # numpy 2 / numpy 1.26
    allowed: list = [argparse.Namespace, np.dtype, np.ndarray]
    for name in ("scalar", "_reconstruct"):
        fn = getattr(core, name)
        allowed += [fn, (fn, f"numpy.core.multiarray.{name}")]
    allowed += [type(np.dtype(t)) for t in ("float64", "float32", "int64", "int32", "bool")]
    return allowed


def _plain(value: Any) -> Any:
    """Metadata as JSON-like values: numpy scalars and arrays to Python, Namespace to dict; tensors summarised."""
    if isinstance(value, argparse.Namespace):
        value = vars(value)
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist() if value.size <= 16 else f"array{value.shape}"
    if isinstance(value, torch.Tensor):
        return f"tensor{tuple(value.shape)}"
    return value


def read_checkpoint(path: str | os.PathLike, which: str | None = None) -> tuple[dict[str, torch.Tensor], dict]:
    """`(state_dict, metadata)` of a checkpoint dict `{which: state dict, ...}` (GPPN's training checkpoints).

    `which` defaults to 'best_model' when present, else 'model'. State values that are numpy arrays become
    tensors. Raises InputError naming the file for an unreadable file, an object outside the allow-list, or a
    missing state dict.
    """
    name = str(path)
    if not os.path.exists(name):
        raise InputError(f"{name}: no such checkpoint file")
    data = torch_load(name, "readable checkpoint", _allowed_globals())
    if not isinstance(data, dict):
        raise InputError(f"{name}: expected a checkpoint dict, found {type(data).__name__}")
    which = which or ("best_model" if "best_model" in data else "model")
    state = data.get(which)
    if not isinstance(state, dict):
        raise InputError(f"{name}: entry '{which}' is missing or not a state dict (has {sorted(map(str, data))})")
    out = {}
    for key, value in state.items():
        if isinstance(value, np.ndarray):
            value = torch.from_numpy(np.ascontiguousarray(value))
        if not isinstance(value, torch.Tensor):
            raise InputError(f"{name}: '{which}' entry '{key}' is not a tensor or array")
        out[str(key)] = value
    meta = {str(k): _plain(v) for k, v in data.items() if k not in ("model", "best_model")}
    return out, {"entry": which, **meta}


def gppn_vin_gaps(state: dict[str, torch.Tensor]) -> list[str]:
    """What vinadv's VIN class lacks to represent the GPPN VIN `state` (non-empty: such weights are refused)."""
    missing = [key for key in GPPN_VIN_KEYS if key not in state]
    if missing:
        return [f"not a GPPN VIN: keys {missing} missing (has {sorted(state)[:8]})"]
    gaps = [
        "input polarity: GPPN's maze channel is 1 = free and its h layer zero-pads it, so outside the grid "
        "reads as wall; vinadv's VIN takes 1 = obstacle with zero padding (outside = free), so border cells "
        "differ and no weight change makes the two equal"
    ]
    f = int(state["h.weight"].shape[-1])
    if f != 3:
        gaps.append(f"kernel size f = {f}: vinadv's VIN has 3x3 h, q and w kernels only")
    if int(state["h.weight"].shape[1]) != 2:
        gaps.append(f"{int(state['h.weight'].shape[1]) - 1} orientations: vinadv's VIN has one")
    if int(state["policy.weight"].shape[0]) != 8:
        gaps.append(f"{int(state['policy.weight'].shape[0])} actions: vinadv plans with 8 moves")
    return gaps


GPPN_KEYS = (
    "hid.weight",
    "hid.bias",
    "h0.weight",
    "h0.bias",
    "c0.weight",
    "c0.bias",
    "conv.weight",
    "conv.bias",
    "lstm.weight_ih",
    "lstm.weight_hh",
    "lstm.bias_ih",
    "lstm.bias_hh",
    "policy.weight",
)


def gppn_from_checkpoint(path: str | os.PathLike, k: int, which: str | None = None):
    """vinadv's `GPPN` with the weights of a checkpoint of the GPPN authors' code (`read_checkpoint`), `k`
    iterations (the code does not store them: its `--k`).

    The keys and shapes are the same; the input is too (channel 0 is 1 on free cells, the goal map 1 at the goal,
    zero padding reading as wall); only the order of the 8 actions differs (GPPN's Moore order N,E,W,S,NE,NW,SE,SW),
    so the rows of `policy.weight` are reordered to vinadv's. Refused with an InputError naming the file: another
    model, a 3-D (orientation) maze, or 4 actions (GPPN's 'news' mechanism; vinadv plans with 8 moves).
    """
    state, meta = read_checkpoint(path, which)
    missing = [key for key in GPPN_KEYS if key not in state]
    if missing:
        raise InputError(f"{path}: not a GPPN checkpoint: keys {missing} missing (has {sorted(state)[:8]})")
    if int(state["hid.weight"].shape[1]) != 2:
        raise InputError(
            f"{path}: a GPPN for 3-D mazes ({int(state['hid.weight'].shape[1])} input channels); "
            "vinadv plans on 2-D grids"
        )
    n_actions = int(state["policy.weight"].shape[0])
    if n_actions != 8:
        raise InputError(
            f"{path}: a GPPN with {n_actions} actions (GPPN's 'news' mechanism?); vinadv plans with 8 moves"
        )
    config = GPPNConfig(k=int(k), l_h=int(state["hid.weight"].shape[0]), f=int(state["conv.weight"].shape[-1]))
    config.validate()
    state = {key: state[key].to(torch.float32) for key in GPPN_KEYS}
    policy = torch.empty_like(state["policy.weight"])
    policy[torch.from_numpy(GPPN_TO_VINADV)] = state["policy.weight"]  # GPPN's action g: vinadv's GPPN_TO_VINADV[g]
    state["policy.weight"] = policy
    model = GPPN(config)
    try:
        model.load_state_dict(state)
    except RuntimeError as exc:
        raise InputError(
            f"{path}: weights do not fit a GPPN of {config.to_dict()} ({str(exc).splitlines()[0]})"
        ) from None
    model.eval()
    model.source = {"checkpoint": str(path), "entry": meta["entry"]}
    return model
