"""The Neural A* authors' Lightning checkpoint, read as tensors and checked key by key, and their train.yaml.

The checkpoint (`epoch=..-step=...ckpt` of omron-sinicx/neural-astar) is a dict with `state_dict`, `epoch`,
`global_step`, `pytorch-lightning_version` and the loops' state; `vinadv.planners.weights.torch_load` reads it with
torch's weights-only unpickler, so nothing in it can run code. Its `state_dict` holds the Lightning module's planner
(`planner.encoder.model.*`: the CNN encoder; `planner.astar.neighbor_filter`: the differentiable A*'s 3x3 neighbour
filter) and the vanilla A* it compares with (`vanilla_astar.astar.neighbor_filter`). vinadv takes exactly that: a
CNN encoder of depth 1..4 on the "m+" input, and the 8-neighbour filter (ones, centre 0: Moore moves). Anything else
(a Unet encoder, the "m" input, a learned `const`, another filter) is refused in one line naming the keys.

train.yaml is the Hydra configuration the authors train with; `read_train_config` reads its subset (nested mappings
of scalars: the authors' file is that), so the import records the training settings without a YAML library.
"""

from __future__ import annotations

import os
import re
from typing import Any

import torch

from vinadv.errors import InputError
from vinadv.planners.neural_astar.model import CHANNELS, NeuralAstar, NeuralAstarConfig, encoder_shapes
from vinadv.planners.weights import torch_load

__all__ = ["ENCODER_PREFIX", "FILTER_KEYS", "from_lightning_checkpoint", "read_train_config"]

#: where the Lightning module keeps the encoder's tensors
ENCODER_PREFIX = "planner.encoder."
#: the neighbour filters of the Neural A* planner (required) and of the vanilla A* beside it (optional)
FILTER_KEYS = ("planner.astar.neighbor_filter", "vanilla_astar.astar.neighbor_filter")
_SHOWN = 4  # keys named in a refusal before "(+n more)"


def _names(keys) -> str:
    keys = sorted(keys)
    shown = ", ".join(keys[:_SHOWN])
    return shown + (f" (+{len(keys) - _SHOWN} more)" if len(keys) > _SHOWN else "")


def moore_filter() -> torch.Tensor:
    """The 8-neighbour filter `(1, 1, 3, 3)`: ones with a zero centre (every Moore neighbour is expanded)."""
    f = torch.ones(1, 1, 3, 3)
    f[0, 0, 1, 1] = 0.0
    return f


def _depth_of(encoder: dict[str, Any]) -> int:
    """The depth whose expected keys differ least from the checkpoint's encoder keys."""
    return min(range(1, len(CHANNELS) + 1), key=lambda d: len(set(encoder) ^ set(encoder_shapes(d))))


def from_lightning_checkpoint(path: str | os.PathLike) -> tuple[NeuralAstar, dict]:
    """The Neural A* model in the authors' Lightning checkpoint `path`, in eval mode, and what the checkpoint says of
    itself (`epoch`, `global_step`, `pytorch_lightning_version`, `depth`). Raises InputError naming the file and the
    keys for anything but the authors' CNN-encoder model with the 8-neighbour filter."""
    name = str(path)
    data = torch_load(name, "Lightning checkpoint")
    state = data.get("state_dict") if isinstance(data, dict) else None
    if not isinstance(state, dict) or not all(isinstance(k, str) for k in state):
        raise InputError(f"{name}: not a Lightning checkpoint (no 'state_dict' of named tensors)")
    not_tensors = [k for k, v in state.items() if not isinstance(v, torch.Tensor)]
    if not_tensors:
        raise InputError(f"{name}: state_dict entries that are not tensors: {_names(not_tensors)}")
    encoder = {k[len(ENCODER_PREFIX) :]: v for k, v in state.items() if k.startswith(ENCODER_PREFIX)}
    if not encoder:
        raise InputError(f"{name}: no Neural A* encoder (no {ENCODER_PREFIX}* keys); its keys: {_names(state)}")
    depth = _depth_of(encoder)
    expected = encoder_shapes(depth)
    others = set(state) - {ENCODER_PREFIX + k for k in encoder} - set(FILTER_KEYS)
    unexpected = {ENCODER_PREFIX + k for k in set(encoder) - set(expected)} | others
    missing = {ENCODER_PREFIX + k for k in set(expected) - set(encoder)}
    if FILTER_KEYS[0] not in state:
        missing.add(FILTER_KEYS[0])
    if unexpected or missing:
        parts = [
            f"unexpected keys {_names(unexpected)}" if unexpected else "",
            f"missing {_names(missing)}" if missing else "",
        ]
        raise InputError(
            f"{name}: not the Neural A* authors' CNN encoder ('m+' input, depth 1..{len(CHANNELS)}): "
            + "; ".join(p for p in parts if p)
        )
    wrong = [
        f"{ENCODER_PREFIX}{k} {tuple(encoder[k].shape)} (expected {shape})"
        for k, shape in expected.items()
        if tuple(encoder[k].shape) != shape
    ]
    if wrong:
        raise InputError(
            f"{name}: not the Neural A* authors' CNN encoder ('m+' input: 2 channels in; depth {depth}): "
            + ", ".join(wrong[:_SHOWN])
        )
    for key in FILTER_KEYS:
        if key in state and not torch.equal(state[key].to(torch.float32), moore_filter()):
            raise InputError(
                f"{name}: {key} is not the 8-neighbour filter (ones with a zero centre, shape (1, 1, 3, 3)): vinadv "
                "searches Moore moves only"
            )
    model = NeuralAstar(NeuralAstarConfig(depth=depth))
    try:
        model.encoder.load_state_dict({k: encoder[k].detach().clone() for k in expected})
    except RuntimeError as exc:  # a dtype torch cannot copy (complex, say)
        raise InputError(f"{name}: the encoder's tensors do not load ({str(exc).splitlines()[0]})") from None
    model.eval()
    source = {
        "path": name,
        "epoch": data.get("epoch"),
        "global_step": data.get("global_step"),
        "pytorch_lightning_version": data.get("pytorch-lightning_version"),
        "depth": depth,
    }
    return model, {k: v if isinstance(v, int | str) or v is None else str(v) for k, v in source.items()}


_KEY = re.compile(r"^( *)([A-Za-z_][\w.-]*):(?: +(.*?))?\s*$")


def _scalar(text: str) -> Any:
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "\"'":
        return text[1:-1]
    lowered = text.lower()
    if lowered in ("true", "false"):
        return lowered == "true"
    if lowered in ("null", "~"):
        return None
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def read_train_config(path: str | os.PathLike) -> dict:
    """The nested mappings of scalars in the YAML file `path` (the authors' train.yaml): `key: value` lines, nesting
    by indentation, `#` comments, quoted or bare strings, integers, floats, true/false/null. Anything else (lists,
    flow collections, anchors, multi-line values) is refused with InputError naming the file and line."""
    name = str(path)
    try:
        with open(name, encoding="utf-8") as fh:
            lines = fh.read().splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{name}: cannot read the training configuration ({exc})") from None
    root: dict = {}
    stack: list[tuple[int, dict]] = [(-1, root)]
    for number, raw in enumerate(lines, 1):
        line = raw.split(" #", 1)[0].rstrip() if not raw.lstrip().startswith("#") else ""
        if not line.strip():
            continue
        match = _KEY.match(line)
        value = None if match is None else match.group(3)
        if match is None or (value and value[0] in "[{&*|>-!"):
            raise InputError(f"{name}:{number}: not a 'key: value' line of a plain YAML mapping: {raw.strip()!r}")
        indent, key = len(match.group(1)), match.group(2)
        while indent <= stack[-1][0]:
            stack.pop()
        parent = stack[-1][1]
        if key in parent:
            raise InputError(f"{name}:{number}: key {key!r} given twice")
        if value:
            parent[key] = _scalar(value)
        else:
            parent[key] = {}
            stack.append((indent, parent[key]))
    return root


def check_train_config(config: dict, depth: int, name: str) -> None:
    """Refuse (InputError naming the file `name` and the field) a training configuration that describes another
    model than the checkpoint's: an encoder other than the CNN, another input than 'm+', another depth."""
    encoder = config.get("encoder", {})
    if not isinstance(encoder, dict):
        raise InputError(f"{name}: encoder is {encoder!r}, expected a mapping")
    for field, want in (("arch", "CNN"), ("input", "m+"), ("depth", depth)):
        if field in encoder and encoder[field] != want:
            raise InputError(f"{name}: encoder.{field} is {encoder[field]!r}; the checkpoint's model has {want!r}")
