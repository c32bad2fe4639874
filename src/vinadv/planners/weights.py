"""Reading and writing VIN weights; the trained weights shipped with vinadv.

File format "vinadv.vin/1": a torch file (`torch.save`) holding a dict
`{"format": "vinadv.vin/1", "config": VINConfig dict, "state_dict": {name: float32 tensor}, "record": dict}`,
where `record` is the training record (command, seed, data checksum, metrics...). A plain state dict as saved by
the common PyTorch ports (`torch.save(net.state_dict(), ...)`, keys `h.weight h.bias r.weight q.weight w fc.weight`)
loads too: `l_i`, `l_h`, `l_q` and the action count come from the tensor shapes, `k` from the map size (or `k=`).

Files are always read with `torch.load(weights_only=True)`: a weights file cannot run code.
"""

from __future__ import annotations

import hashlib
import json
import os
import zipfile
from pathlib import Path
from typing import Any

import torch

from vinadv.errors import InputError
from vinadv.grid.actions import ACTION_DELTAS
from vinadv.outfile import atomic_output
from vinadv.planners.vin import VIN, VINConfig, default_k

WEIGHTS_FORMAT = "vinadv.vin/1"
STATE_KEYS = ("h.weight", "h.bias", "r.weight", "q.weight", "w", "fc.weight")
WEIGHTS_DIR = Path(__file__).resolve().parent.parent / "weights"


def default_weights_path(size: int = 28) -> Path:
    """Path of the shipped weights for `size x size` maps: `vinadv/weights/vin{size}.pt` (may not exist)."""
    return WEIGHTS_DIR / f"vin{int(size)}.pt"


def weights_checksum(path: str | os.PathLike) -> str:
    """SHA-256 of the file's bytes, as hex: identifies the model in run records."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def save_vin(model: VIN, path: str | os.PathLike, record: dict | None = None) -> None:
    """Write `model` (float32 state dict on CPU) with its config and `record` to `path`, atomically.

    `record` must hold only JSON-like values (dict, list, str, int, float, bool, None).
    """
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
    with atomic_output(path, "wb", mkdir=True) as fh:
        torch.save(payload, fh)


def read_weights(path: str | os.PathLike, size: int = 28, k: int | None = None) -> tuple[VIN, dict]:
    """Load a weights file (either format); returns the model (eval mode, CPU) and the record (`{}` for ports).

    Raises InputError naming the file for a missing, unreadable, corrupted or mismatched file.
    """
    name = str(path)
    if not os.path.exists(name):
        raise InputError(f"{name}: no such weights file")
    try:
        data = torch.load(name, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises many types for a bad file (pickle, zip, EOF, unsafe global)
        raise InputError(_unreadable(name, exc)) from None
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
    model = VIN(config)
    _check_state(name, state, model)
    model.load_state_dict({key: state[key].to(torch.float32) for key in STATE_KEYS})
    model.eval()
    return model, record


def load_vin(path: str | os.PathLike | None = None, size: int = 28, k: int | None = None) -> VIN:
    """The VIN in `path`, or the shipped weights for `size x size` maps when `path` is None.

    A port-style plain state dict gets `k = default_k(size)` unless `k` is given; `k` also overrides the k of a
    vinadv file. The model's `record` attribute holds the training record (`{}` for port files) and
    `weights_path` the file it came from. Raises InputError for a missing/corrupted/mismatched file.
    """
    if path is None:
        path = default_weights_path(size)
        if not path.exists():
            raise InputError(
                f"no shipped VIN weights for {size}x{size} maps ({path}); train some with "
                f"`vinadv vin train` and pass --weights"
            )
    model, record = read_weights(path, size=size, k=k)
    model.record = record
    model.weights_path = str(path)
    return model


def _unreadable(name: str, exc: Exception) -> str:
    """Why torch could not load `name`, in vinadv's words (torch's own message advises `weights_only=False`,
    which would let the file run code: never repeated)."""
    text = str(exc)
    if "Unsupported global" in text or "Unsupported class" in text or "GLOBAL" in text:
        return (
            f"{name}: holds Python objects, not only tensors and plain values; refused (weights files are "
            "loaded without running code)"
        )
    kind = "a zip archive, but not one torch wrote" if zipfile.is_zipfile(name) else "damaged or another kind of file"
    return f"{name}: not a vinadv/PyTorch weights file ({kind})"


def _check_planner_shapes(name: str, state: dict, config: VINConfig) -> None:
    """Refuse weights whose input or output size the planner cannot feed: 2 input channels (obstacles, goal),
    one logit per move of `ACTION_DELTAS`. Other shapes are checked against the config by `_check_state`."""
    for key, axis, want in (("h.weight", 1, VINConfig.l_i), ("fc.weight", 0, len(ACTION_DELTAS))):
        got = state.get(key)
        if not isinstance(got, torch.Tensor) or got.ndim <= axis:
            continue  # reported by `_check_state`
        if got.shape[axis] != want:
            expected = list(got.shape)
            expected[axis] = want
            raise InputError(
                f"{name}: '{key}' has shape {tuple(got.shape)}, expected {tuple(expected)} "
                f"(the planner has {want} {'input channels' if axis else 'actions'})"
            )
    if config.l_i != VINConfig.l_i or config.n_actions != len(ACTION_DELTAS):
        raise InputError(
            f"{name}: config has l_i={config.l_i}, n_actions={config.n_actions}; the planner needs "
            f"l_i={VINConfig.l_i}, n_actions={len(ACTION_DELTAS)}"
        )


def _config_from_dict(name: str, raw: dict[str, Any]) -> VINConfig:
    allowed = set(VINConfig.__dataclass_fields__)
    unknown = set(raw) - allowed
    if unknown:
        raise InputError(f"{name}: field 'config' has unknown entries {sorted(unknown)}")
    for key, value in raw.items():
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise InputError(f"{name}: config entry '{key}' must be a positive integer, got {value!r}")
    return VINConfig(**raw)


def _config_from_state(name: str, state: dict, k: int) -> VINConfig:
    missing = [key for key in STATE_KEYS if key not in state]
    if missing:
        raise InputError(f"{name}: not VIN weights: state dict lacks {missing} (has {sorted(map(str, state))[:8]})")
    for key in STATE_KEYS:
        if not isinstance(state[key], torch.Tensor):
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


def _check_state(name: str, state: dict, model: VIN) -> None:
    expected = model.state_dict()
    missing = [key for key in STATE_KEYS if key not in state]
    extra = [str(key) for key in state if key not in expected]
    if missing or extra:
        raise InputError(f"{name}: state dict keys do not match a VIN: missing {missing}, unexpected {extra}")
    for key, want in expected.items():
        got = state[key]
        if not isinstance(got, torch.Tensor):
            raise InputError(f"{name}: state dict entry '{key}' is not a tensor")
        if tuple(got.shape) != tuple(want.shape):
            raise InputError(
                f"{name}: '{key}' has shape {tuple(got.shape)}, expected {tuple(want.shape)} "
                f"for config {model.config.to_dict()}"
            )
        if not torch.is_floating_point(got) or not torch.isfinite(got).all():
            raise InputError(f"{name}: '{key}' is not a finite float tensor")
