"""The VIN's training entry: `train_vin`, the imitation loop (`vinadv.planners.imitation`) on a fresh VIN, or one
started from weights (`--init`), with its value-iteration kernels initialised as `TrainConfig.vi_init` says."""

from __future__ import annotations

import torch

from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import move_model
from vinadv.planners.device import resolve_device
from vinadv.planners.imitation import TrainConfig, start_from, train_model
from vinadv.planners.records import TrainingRecord
from vinadv.planners.vin.arrays import VINConfig, default_k
from vinadv.planners.vin.model import VIN, init_shift_kernels
from vinadv.planners.vin.weights import load_vin

__all__ = ["train_vin"]


def train_vin(maps: MapSet, config: TrainConfig, **options) -> tuple[VIN, TrainingRecord]:
    """Train a VIN on `maps`; `options` and the result as `train_model`'s (the model on the CPU, in eval mode, and
    the training record). `config.init` names a VIN weights file to start from."""
    config.validate()
    torch.manual_seed(config.seed)
    n_actions = move_model(maps.moves).n_actions  # the maps' moves: 8, or 4 on `news`
    vin_config = VINConfig(k=config.k or default_k(maps.size), l_h=config.l_h, l_q=config.l_q, n_actions=n_actions)
    model = VIN(vin_config)
    if config.vi_init == "shift":
        init_shift_kernels(model)
    record = options.get("record")
    if config.init:
        # at the file's own k, so that the record keeps it (`init_k`) where this training's differs
        start = load_vin(config.init, size=maps.size)
        record = start_from(model, start, config.init, record, maps.moves)
    cpu = resolve_device(config.device).type == "cpu"
    options["record"] = {
        **(record or {}),
        "value_iteration": "compiled (vinadv.planners.vin.value_iteration)" if cpu else "torch",
    }
    return train_model(model, maps, config, vin_config.to_dict(), **options)
