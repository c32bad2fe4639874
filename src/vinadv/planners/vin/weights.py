"""Reading and writing VIN weights files; the trained weights shipped with vinadv.

File format "vinadv.vin/1": a torch file (`torch.save`) holding a dict
`{"format": "vinadv.vin/1", "config": VINConfig dict, "state_dict": {name: float32 tensor}, "record": dict}`,
where `record` is the training record (command, seed, data checksum, metrics...). A plain state dict as saved by
the common PyTorch ports (`torch.save(net.state_dict(), ...)`, keys `h.weight h.bias r.weight q.weight w fc.weight`)
loads too: `l_i`, `l_h`, `l_q` and the action count come from the tensor shapes, `k` from the map size (or `k=`).

Files are read without running code: by `vinadv.planners.torchfile` (no PyTorch; tensors and plain values only),
and what it cannot read by `torch.load(weights_only=True)`. `load_vin_weights` gives NumPy weights for the planning
engine; `load_vin` the PyTorch `VIN`. What every planner's files share (the shipped folder, checksums) is in
`vinadv.planners.weights`.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.actions import ACTION_DELTAS
from vinadv.grid.moves import MOVES, move_model
from vinadv.outfile import save_torch
from vinadv.planners.torchfile import read_torch_file
from vinadv.planners.vin.arrays import STATE_KEYS, VINConfig, VINWeights, default_k
from vinadv.planners.weights import MAX_CHANNELS, WEIGHTS_DIR, check_iterations, torch_load, weights_file

WEIGHTS_FORMAT = "vinadv.vin/1"
__all__ = [
    "STATE_KEYS",
    "WEIGHTS_FORMAT",
    "default_weights_path",
    "load_vin",
    "load_vin_weights",
    "read_weights",
    "save_vin",
]


def default_weights_path(size: int = 28) -> Path:
    """Path of the shipped weights for `size x size` maps: `vinadv/weights/vin{size}.pt` (may not exist)."""
    return WEIGHTS_DIR / f"vin{int(size)}.pt"


def save_vin(model, path: str | os.PathLike, record: dict | None = None) -> None:
    """Write `model` (a `VIN`; float32 state dict on CPU) with its config and `record` to `path`, atomically.

    `record` must hold only JSON-like values (dict, list, str, int, float, bool, None).
    """
    import torch

    # Through JSON: the record must load under weights_only=True (plain types only; torch.__version__, for one,
    # is a str subclass that the safe loader refuses).
    try:
        record = json.loads(json.dumps(dict(record or {})))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"record must hold only JSON values: {exc}") from None
    state = {k: v.detach().to("cpu", torch.float32).contiguous().clone() for k, v in model.state_dict().items()}
    payload = {
        "format": WEIGHTS_FORMAT,
        "config": model.config.to_dict(),
        "state_dict": state,
        "record": record,
    }
    save_torch(payload, path, mkdir=True)


def load_vin_weights(path: str | os.PathLike | None = None, size: int = 28, k: int | None = None) -> VINWeights:
    """The VIN weights in `path` (either format), or the shipped weights for `size x size` maps when None, as
    NumPy (`VINWeights`), read without PyTorch where the file allows (`vinadv.planners.torchfile`).

    A port-style plain state dict gets `k = default_k(size)` unless `k` is given; `k` also overrides the k of a
    vinadv file. Raises InputError naming the file for a missing, unreadable, corrupted or mismatched file.
    """
    name = weights_file(path, default_weights_path(size), "VIN", size)
    if k is not None:
        check_iterations(name, k)
    data = read_torch_file(name)
    if data is None:
        data = _torch_load(name)
    if not isinstance(data, dict):
        raise InputError(f"{name}: expected a dict of weights, found {type(data).__name__}")
    if "format" in data:
        fmt = data["format"]
        if fmt != WEIGHTS_FORMAT:
            raise InputError(f"{name}: format {fmt!r} is not supported (expected {WEIGHTS_FORMAT!r})")
        for field in ("config", "state_dict"):
            if not isinstance(data.get(field), dict):
                raise InputError(f"{name}: field '{field}' is missing or not a dict")
        config = _config_from_dict(name, data["config"])
        state = data["state_dict"]
        record = data.get("record") or {}
        if not isinstance(record, dict):
            raise InputError(f"{name}: field 'record' is not a dict")
    else:
        state = data.get("state_dict", data) if isinstance(data.get("state_dict"), dict) else data
        config = _config_from_state(name, state, default_k(size) if k is None else k)
        record = {}
    if k is not None and k != config.k:
        config = VINConfig(**{**config.to_dict(), "k": int(k)})
    _check_planner_shapes(name, state, config)
    _check_state(name, state, config)
    arrays = {key: np.ascontiguousarray(state[key], dtype=np.float32) for key in STATE_KEYS}
    return VINWeights(config, arrays, record, name)


def read_weights(path: str | os.PathLike, size: int = 28, k: int | None = None) -> tuple[Any, dict]:
    """Load a weights file (either format); returns the PyTorch `VIN` (eval mode, CPU) and the record (`{}` for
    ports). Raises InputError naming the file for a missing, unreadable, corrupted or mismatched file."""
    weights = load_vin_weights(path, size=size, k=k)
    return weights.module(), weights.record


def load_vin(path: str | os.PathLike | None = None, size: int = 28, k: int | None = None):
    """The PyTorch `VIN` in `path`, or the shipped weights for `size x size` maps when `path` is None
    (`load_vin_weights`, then the module). Its `record` attribute holds the training record (`{}` for port files)
    and `weights_path` the file it came from."""
    return load_vin_weights(path, size=size, k=k).module()


def _torch_load(name: str) -> Any:
    """`torch.load(weights_only=True)` with the tensors as NumPy arrays (float32 for the floating ones, so that
    bfloat16 reads too); what `read_torch_file` could not read."""
    import torch

    data = torch_load(name, "vinadv/PyTorch weights file")

    def arrays(value):
        if isinstance(value, torch.Tensor):
            return value.detach().to(torch.float32).numpy() if value.is_floating_point() else value.numpy()
        if isinstance(value, dict):
            return {key: arrays(v) for key, v in value.items()}
        return value

    return arrays(data)


def _check_planner_shapes(name: str, state: dict, config: VINConfig) -> None:
    """Refuse weights whose input or output size the planner cannot feed: 2 input channels (obstacles, goal),
    one logit per move of a movement model (`vinadv.grid.moves`: 8, or 4 for `news`; which model the weights plan
    is their record's, checked by the planner, `check_action_count`). Other shapes are checked against the config by
    `_check_state`."""
    counts = sorted({move_model(m).n_actions for m in MOVES})
    got = state.get("h.weight")
    if isinstance(got, np.ndarray) and got.ndim > 1 and got.shape[1] != VINConfig.l_i:
        expected = (got.shape[0], VINConfig.l_i, *got.shape[2:])
        raise InputError(
            f"{name}: 'h.weight' has shape {tuple(got.shape)}, expected {expected} "
            f"(the planner has {VINConfig.l_i} input channels)"
        )
    got = state.get("fc.weight")
    if isinstance(got, np.ndarray) and got.ndim > 0 and got.shape[0] not in counts:
        raise InputError(
            f"{name}: 'fc.weight' has shape {tuple(got.shape)}, expected ({len(ACTION_DELTAS)}, ...) "
            f"(the planner has {' or '.join(map(str, counts))} actions)"
        )
    if config.l_i != VINConfig.l_i or config.n_actions not in counts:
        raise InputError(
            f"{name}: config has l_i={config.l_i}, n_actions={config.n_actions}; the planner needs "
            f"l_i={VINConfig.l_i}, n_actions {' or '.join(map(str, counts))}"
        )


def _config_from_dict(name: str, raw: dict[str, Any]) -> VINConfig:
    allowed = set(VINConfig.__dataclass_fields__)
    unknown = set(raw) - allowed
    if unknown:
        raise InputError(f"{name}: field 'config' has unknown entries {sorted(unknown)}")
    for key, value in raw.items():
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise InputError(f"{name}: config entry '{key}' must be a positive integer, got {value!r}")
        if key == "k":
            check_iterations(name, value, "config entry 'k'")
        elif value > MAX_CHANNELS:
            raise InputError(f"{name}: config entry '{key}' is {value}, expected at most {MAX_CHANNELS}")
    return VINConfig(**raw)


def _config_from_state(name: str, state: dict, k: int) -> VINConfig:
    missing = [key for key in STATE_KEYS if key not in state]
    if missing:
        raise InputError(f"{name}: not VIN weights: state dict lacks {missing} (has {sorted(map(str, state))[:8]})")
    for key in STATE_KEYS:
        if not isinstance(state[key], np.ndarray):
            raise InputError(f"{name}: state dict entry '{key}' is not a tensor")
    h, fc = state["h.weight"], state["fc.weight"]
    if h.ndim != 4 or fc.ndim != 2:
        raise InputError(
            f"{name}: 'h.weight' has shape {tuple(h.shape)} and 'fc.weight' {tuple(fc.shape)}; "
            f"expected 4 and 2 dimensions"
        )
    return VINConfig(
        k=int(k), l_i=int(h.shape[1]), l_h=int(h.shape[0]), l_q=int(fc.shape[1]), n_actions=int(fc.shape[0])
    )


def _check_state(name: str, state: dict, config: VINConfig) -> None:
    expected = config.state_shapes()
    missing = [key for key in STATE_KEYS if key not in state]
    extra = [str(key) for key in state if key not in expected]
    if missing or extra:
        raise InputError(f"{name}: state dict keys do not match a VIN: missing {missing}, unexpected {extra}")
    for key, want in expected.items():
        got = state[key]
        if not isinstance(got, np.ndarray):
            raise InputError(f"{name}: state dict entry '{key}' is not a tensor")
        if tuple(got.shape) != want:
            raise InputError(
                f"{name}: '{key}' has shape {tuple(got.shape)}, expected {want} for config {config.to_dict()}"
            )
        if got.dtype.kind != "f" or not np.isfinite(got).all():
            raise InputError(f"{name}: '{key}' is not a finite float tensor")
