"""The VIN as a planner: `VINPlanner` (paths from the exact engine, logits, value maps and gradients from the
PyTorch `VIN`) and `as_planner`, which lets the library functions that take a planner also take a VIN.
"""

from __future__ import annotations

import copy
import sys
from typing import TYPE_CHECKING

import numpy as np

from vinadv.grid.moves import DEFAULT_MOVES
from vinadv.planners.batching import DEFAULT_CHUNK as ENGINE_CHUNK
from vinadv.planners.device import full_precision
from vinadv.planners.interface import (
    DEFAULT_CHUNK,
    Capabilities,
    Planner,
    PlannerError,
    TorchPlanner,
    is_planner,
    state_checksum,
)
from vinadv.planners.result import PlanResult
from vinadv.planners.vin import engine
from vinadv.planners.vin.arrays import VINWeights
from vinadv.planners.weights import check_action_count, trained_moves, weights_checksum

if TYPE_CHECKING:  # PyTorch is loaded only by the planners that run it
    import torch
    from torch import nn


class VINPlanner(Planner):
    """The VIN: paths from the exact engine (`vinadv.planners.vin.engine`, the same paths as re-running the network at
    every step), not the generic rollout; logits, value maps and gradients from the PyTorch `VIN`.

    `vin` is `VINWeights` (from a file: planning needs no PyTorch) or a PyTorch `VIN`, read afresh at every call
    (it may be training).

    `device` (`--device`): plan with the PyTorch forward on that device instead (`VINPolicy` through `TorchPlanner`,
    then the rollout every planner shares), a copy of the VIN moved there at first use; value maps and gradients are
    computed there too.
    None (the default) keeps the exact engine, the reference. On the CPU the forward gives the engine's paths (the
    engine replays PyTorch's float32 arithmetic at near ties; docs/guide/gpu.md gives the count measured on 1,000 maps);
    on a GPU other float sums may break a near tie the other way.

    `moves`: the movement model the VIN was trained on (`trained_moves` of its record; `octile` for records without
    one). The engine plans `octile` moves, so a VIN of another model plans with its PyTorch forward on the CPU and
    the rollout every planner shares, which follows the model's moves and costs.

    Capabilities: a policy at every cell, value maps of its own (`max_a q`) and gradients (the PyTorch `VIN`).
    """

    capabilities = Capabilities(policy=True, value_maps=True, gradients=True)

    def __init__(
        self,
        vin,
        size: int,
        checksum: str | None = None,
        device: str | torch.device | None = None,
        name: str = "vin",
    ):
        self.name, self.size = name, int(size)
        self._source = vin
        self._torch: TorchPlanner | None = None
        self._device = device
        if device is not None:
            import torch

            self.device_type = torch.device(device).type
        path = vin.path if isinstance(vin, VINWeights) else getattr(vin, "weights_path", None)
        self.moves = trained_moves(path, getattr(vin, "record", None) or {})
        check_action_count(path, vin.config.n_actions, self.moves, "VIN")
        if checksum is None:
            checksum = weights_checksum(path) if path is not None else state_checksum(self.vin)
        self._checksum = checksum

    @property
    def weights(self) -> VINWeights:
        """The weights as they are now (`VINWeights`)."""
        return self._source if isinstance(self._source, VINWeights) else VINWeights.from_module(self._source)

    @property
    def vin(self):
        """The PyTorch `VIN` (built from the weights at first use)."""
        return self._source.module() if isinstance(self._source, VINWeights) else self._source

    @property
    def config(self) -> dict:
        return self._source.config.to_dict()  # a VIN and VINWeights both carry it: no copy of the weights

    def _torch_planner(self) -> TorchPlanner:
        if self._torch is None:
            from vinadv.planners.vin.model import VINPolicy  # noqa: PLC0415 (PyTorch: the VIN plans without it)

            if self._device is None:
                policy = VINPolicy(self.vin)
            else:  # a copy moved there: the weights' own module stays on the CPU
                policy = VINPolicy(copy.deepcopy(self.vin)).to(self._device)
            self._torch = TorchPlanner(policy, self.name, self.size, self._checksum, self.config, device=self._device)
        return self._torch

    @property
    def device(self) -> torch.device:
        """Where its PyTorch forward runs (the CPU unless a device was given)."""
        return self._torch_planner().device

    @property
    def module(self) -> nn.Module:
        return self._torch_planner().module

    @property
    def logits_module(self) -> nn.Module:
        return self.module

    def policy_logits(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        return self._torch_planner().policy_logits(obstacles, goals)

    def value_maps(self, obstacles: np.ndarray, goals: np.ndarray, batch_size: int = 64) -> np.ndarray:
        """The VIN's value maps `max_a q`, `(B, N, N)` float32, `batch_size` maps per forward."""
        import torch

        from vinadv.planners.vin.model import make_input  # noqa: PLC0415 (PyTorch: the VIN plans without it)

        obstacles = np.ascontiguousarray(obstacles, dtype=bool)
        self._check_size(obstacles)
        out = np.empty(obstacles.shape, np.float32)
        vin, device = self.vin, None
        if self._device is not None:
            vin, device = self._torch_planner().module.vin, self.device
            batch_size = max(batch_size, self._torch_planner().device_batch_size if device.type != "cpu" else 0)
        with torch.no_grad(), full_precision(self.device if device is not None else torch.device("cpu")):
            for i in range(0, len(obstacles), batch_size):
                x = make_input(obstacles[i : i + batch_size], goals[i : i + batch_size])
                if device is not None:
                    x = x.to(device)
                out[i : i + batch_size] = vin.q_values(x).max(dim=1).values.cpu().numpy()
        return out

    def _engine_plans(self) -> bool:
        """Whether `plan` runs the exact engine: no device asked for, and the engine's `octile` moves (else the
        PyTorch forward on the device, or for another movement model, then the rollout every planner shares)."""
        return self._device is None and self.moves == DEFAULT_MOVES

    @property
    def chunk_size(self) -> int:
        return ENGINE_CHUNK if self._engine_plans() else DEFAULT_CHUNK

    def _chunk_planner(self, corner_cutting: bool):
        """`plan`'s step: the exact engine on the weights as they are at the call (read once for all its chunks),
        or the policy rollout every planner shares (`_engine_plans`)."""
        if not self._engine_plans():
            return super()._chunk_planner(corner_cutting)
        weights = self.weights

        def step(obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray) -> PlanResult:
            return engine.plan_chunk(obstacles, goals, starts, weights, corner_cutting)

        return step


def as_planner(planner, size: int) -> Planner:
    """`planner` if it is a `Planner`; a `VIN` or `VINWeights` wrapped as the `vin` planner for `size x size` maps
    (so the library functions that take a planner also take a VIN); any other
    `torch.nn.Module` as a `TorchPlanner` named after its class."""
    if is_planner(planner):
        return planner
    if isinstance(planner, VINWeights):
        return VINPlanner(planner, size)
    if "torch" in sys.modules:  # without PyTorch loaded, nothing is a module
        from torch import nn

        from vinadv.planners.vin.model import VIN  # noqa: PLC0415 (PyTorch: the VIN plans without it)

        if isinstance(planner, VIN):
            return VINPlanner(planner, size)
        if isinstance(planner, nn.Module):  # a module with the bring-your-own contract (a GPPN, say)
            return TorchPlanner(planner, type(planner).__name__.lower(), size)
    raise PlannerError(
        f"planner: expected a Planner, a VIN or a torch.nn.Module, got {type(planner).__name__}", "planner"
    )
