"""Adversarial training: make a planner more robust by training it on the maps that break it.

Before every epoch (from `start_epoch` on), `AdversarialMaps`:
1. draws `maps_per_epoch` training maps (seeded by `(seed, epoch)`; never a validation map),
2. attacks them with the model as it is now (`strategy`, one pair per map, the strongest by `objective`; the
   default, exhaustive search ranked by harm, finds each map's worst single obstacle),
3. keeps the adversarial maps of the *harmful* pairs (`vinadv.classify.harm`: unreached, or a path that got worse
   than optimal by more than on the original map) — a fork onto another optimal route is not something to unlearn,
4. and hands them to `vinadv.planners.imitation.train_model`, which adds them to the training maps with their own
   Dijkstra supervision (every free cell, the set of optimal actions) for that epoch and the rest.

What each round found is kept in the training record (`augment_rounds`), the added maps in the checkpoint.
This module sits downstream of the attacks and identification it uses; the training loop knows only the hook.
"""

from __future__ import annotations

import copy
import time
from dataclasses import asdict, dataclass

import numpy as np
import torch

from vinadv.attacks.strategies import STRATEGIES, make_attack
from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.identify import OBJECTIVES, identify, objective_strength
from vinadv.planners.vin.planner import as_planner


@dataclass(frozen=True)
class AdversarialConfig:
    """What adversarial training attacks, and with what.

    Attributes:
        maps_per_epoch: training maps attacked before each epoch.
        strategy: the attack strategy (`vinadv.attacks.strategies.STRATEGIES`); exhaustive by default.
        budget: candidates per map for key-points and saliency.
        objective: what "strongest" means ('harm', default, or 'paper').
        start_epoch: the first epoch (0-based) before which maps are attacked (a fresh model's early attacks
            mostly find its ignorance; a model that starts from trained weights can start at 0).
    """

    maps_per_epoch: int = 1000
    strategy: str = "exhaustive"
    budget: int = 8
    objective: str = "harm"
    start_epoch: int = 0

    def validate(self) -> None:
        if self.maps_per_epoch < 1:
            raise InputError(f"maps_per_epoch must be >= 1, got {self.maps_per_epoch}", "maps_per_epoch")
        if self.strategy not in STRATEGIES:
            raise InputError(f"strategy: {self.strategy!r} is not one of {', '.join(STRATEGIES)}", "strategy")
        if self.budget < 1:
            raise InputError(f"budget must be >= 1, got {self.budget}", "budget")
        if self.objective not in OBJECTIVES:
            raise InputError(f"objective: {self.objective!r} is not one of {'|'.join(OBJECTIVES)}", "objective")
        if self.start_epoch < 0:
            raise InputError(f"start_epoch must be >= 0, got {self.start_epoch}", "start_epoch")

    def to_dict(self) -> dict:
        return asdict(self)


class AdversarialMaps:
    """The `augment` hook of `train_model` (see the module doc): `(obstacles, goals, info)` of the harmful
    adversarial maps of the model before epoch `epoch`, or None before `start_epoch`."""

    def __init__(self, maps: MapSet, config: AdversarialConfig, seed: int = 0):
        config.validate()
        self.maps, self.config, self.seed = maps, config, seed

    def __call__(self, model: torch.nn.Module, epoch: int, train_idx: np.ndarray):
        if epoch < self.config.start_epoch:
            return None
        t0 = time.perf_counter()
        rng = np.random.default_rng([self.seed, epoch, 0xAD])
        pick = np.sort(rng.choice(train_idx, min(self.config.maps_per_epoch, len(train_idx)), replace=False))
        # a CPU copy in eval mode: the training model stays where it is, in train mode
        planner = as_planner(copy.deepcopy(model).to("cpu").eval(), self.maps.size)
        maps = self.maps
        attack = make_attack(self.config.strategy, per_map=1, seed=[self.seed, epoch], budget=self.config.budget)
        result = attack.attack(
            maps.obstacles[pick],
            maps.starts[pick, 0],
            maps.goals[pick],
            planner,
            maps.corner_cutting,
            strength=objective_strength(self.config.objective),
        )
        ident = identify(result.pairs)
        harmful = ident.harm.harm == "harmful"
        pairs = result.pairs
        info = {
            "attacked": int(len(pick)),
            "pairs": int(len(pairs)),
            "harmful": int(harmful.sum()),
            "unreached": int((ident.labels == "UrP").sum()),
            "attack_s": round(time.perf_counter() - t0, 2),
        }
        return pairs.obstacles_a[harmful], pairs.goals[harmful], info
