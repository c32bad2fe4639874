"""The Value Iteration Network (Tamar et al., 2016): its model, weights, exact planning engine and compiled value
iteration.

- `arrays`: hyper-parameters (`VINConfig`), input encoding and weights as NumPy (`VINWeights`), without PyTorch;
- `model`: the PyTorch `VIN` (the layout of the common ports), `VINPolicy`, `make_input`, `init_shift_kernels`;
- `weights`: weights files (`load_vin_weights`, `load_vin`, `save_vin`) and the shipped weights;
- `engine`: the batched planning engine (`plan_maps`, `plan_batch`, `action_maps`), the reference's paths exactly;
- `value_iteration`: the k-step loop as one compiled autograd function, for training on CPU;
- `flat`: the flat zero-padded map layout of the engine's and the near-tie replay's kernels.
- `training`: `train_vin`, the VIN's training entry (the imitation loop, `vinadv.planners.imitation`).

Importing this package loads no PyTorch (the engine plans without it): the names of `model` are imported from it
at their first use.
"""

from __future__ import annotations

from vinadv import lazy_names
from vinadv.planners.vin.arrays import (
    GOAL_VALUE,
    K_BY_SIZE,
    STATE_KEYS,
    VINConfig,
    VINWeights,
    as_vin_weights,
    default_k,
    input_array,
)
from vinadv.planners.vin.weights import (
    WEIGHTS_FORMAT,
    default_weights_path,
    load_vin,
    load_vin_weights,
    read_weights,
    save_vin,
)

#: the names of `vinadv.planners.vin.model` (PyTorch), imported at their first use
_MODEL_NAMES = ("VI_INITS", "VIN", "VINPolicy", "init_shift_kernels", "make_input")

__all__ = [
    "GOAL_VALUE",
    "K_BY_SIZE",
    "STATE_KEYS",
    "WEIGHTS_FORMAT",
    "VINConfig",
    "VINWeights",
    "as_vin_weights",
    "default_k",
    "default_weights_path",
    "input_array",
    "load_vin",
    "load_vin_weights",
    "read_weights",
    "save_vin",
    *_MODEL_NAMES,
]


# PEP 562: `from vinadv.planners.vin import VIN` imports PyTorch then, and only then
_, __getattr__, __dir__ = lazy_names(__name__, {"model": _MODEL_NAMES})
