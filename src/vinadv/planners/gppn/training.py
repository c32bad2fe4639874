"""The GPPN's training entry: `train_gppn`, the imitation loop (`vinadv.planners.imitation`) on a fresh GPPN, or one
started from weights (`--init`)."""

from __future__ import annotations

import torch

from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import move_model
from vinadv.planners.gppn.model import GPPN, GPPNConfig, load_gppn
from vinadv.planners.imitation import TrainConfig, start_from, train_model
from vinadv.planners.records import TrainingRecord
from vinadv.planners.vin.arrays import default_k

__all__ = ["train_gppn"]


def train_gppn(maps: MapSet, config: TrainConfig, **options) -> tuple[GPPN, TrainingRecord]:
    """Train a GPPN (`config.k` iterations, width `config.l_h`, kernel `config.kernel`) on `maps`; `options` and the
    result as `train_model`'s. `config.init` names a GPPN weights file to start from."""
    config.validate()
    torch.manual_seed(config.seed)
    n_actions = move_model(maps.moves).n_actions  # the maps' moves: 8, or 4 on `news`
    gppn_config = GPPNConfig(k=config.k or default_k(maps.size), l_h=config.l_h, f=config.kernel, n_actions=n_actions)
    model = GPPN(gppn_config)
    if config.init:
        options["record"] = start_from(
            model, load_gppn(config.init, size=maps.size), config.init, options.get("record"), maps.moves
        )
    return train_model(model, maps, config, gppn_config.to_dict(), **options)
