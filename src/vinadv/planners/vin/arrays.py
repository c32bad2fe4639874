"""A VIN's hyper-parameters and weights without PyTorch: what the planning engine and its near-tie replay need.

`VINWeights` holds the float32 state dict as NumPy arrays with its `VINConfig`, training record and file; the
PyTorch `VIN` (`vinadv.planners.vin.model`) is built from it only when something asks for it (`VINWeights.module`:
training, gradients, the generic rollout, a replay check). `vinadv run` with the VIN never imports PyTorch once
the near-tie replay's settings are known on the machine (`vinadv.planners.vin.replay`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from vinadv.planners.records import TrainingRecord

GOAL_VALUE = 10.0
#: value-iteration steps k for the map sizes of the VIN paper; other sizes use `default_k`.
K_BY_SIZE = {8: 10, 16: 20, 28: 36}
#: state-dict keys of a VIN, those of the common PyTorch ports
STATE_KEYS = ("h.weight", "h.bias", "r.weight", "q.weight", "w", "fc.weight")


def default_k(size: int) -> int:
    """k for an N x N map: 10, 20, 36 at 8, 16, 28 (the VIN paper), else about 1.3 N (enough to cross the map)."""
    return K_BY_SIZE.get(size, int(np.ceil(1.3 * size)))


@dataclass(frozen=True)
class VINConfig:
    """Hyper-parameters: k value-iteration steps, l_i input channels, l_h hidden channels, l_q q channels."""

    k: int = 36
    l_i: int = 2
    l_h: int = 150
    l_q: int = 10
    n_actions: int = 8

    def to_dict(self) -> dict:
        return asdict(self)

    def state_shapes(self) -> dict[str, tuple[int, ...]]:
        """The shape of each state-dict entry of a VIN with this config."""
        return {
            "h.weight": (self.l_h, self.l_i, 3, 3),
            "h.bias": (self.l_h,),
            "r.weight": (1, self.l_h, 1, 1),
            "q.weight": (self.l_q, 1, 3, 3),
            "w": (self.l_q, 1, 3, 3),
            "fc.weight": (self.n_actions, self.l_q),
        }


def input_array(obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """VIN input `(B, 2, N, N)` float32 from obstacles `(B, N, N)` bool and goals `(B, 2)`: the obstacle image and
    the goal image (`GOAL_VALUE` at the goal)."""
    obstacles = np.asarray(obstacles, dtype=bool)
    b = len(obstacles)
    x = np.zeros((b, 2) + obstacles.shape[1:], dtype=np.float32)
    x[:, 0] = obstacles
    x[np.arange(b), 1, goals[:, 0], goals[:, 1]] = GOAL_VALUE
    return x


@dataclass(eq=False)
class VINWeights:
    """A VIN as NumPy: `config`, `state` (`STATE_KEYS` -> float32 arrays of `config.state_shapes()`), the training
    `record` and the weights file `path` (None when made in memory)."""

    config: VINConfig
    state: dict[str, np.ndarray]
    record: TrainingRecord = field(default_factory=dict)
    path: str | None = None
    _module: object = field(default=None, repr=False)

    @classmethod
    def from_module(cls, vin) -> VINWeights:
        """The weights of a PyTorch `VIN` as they are now (its `record` and `weights_path` kept); `module()` then
        answers that very module."""
        state = {k: np.ascontiguousarray(v.detach().cpu().float().numpy()) for k, v in vin.state_dict().items()}
        path = getattr(vin, "weights_path", None)
        return cls(vin.config, state, dict(getattr(vin, "record", {}) or {}), path, vin)

    def module(self):
        """The PyTorch `VIN` of these weights (eval mode, `record` and `weights_path` set), built at the first call."""
        if self._module is None:
            import torch

            from vinadv.planners.vin.model import VIN  # noqa: PLC0415 (PyTorch)

            vin = VIN(self.config)
            vin.load_state_dict({k: torch.from_numpy(np.array(v, dtype=np.float32)) for k, v in self.state.items()})
            vin.eval()
            vin.record, vin.weights_path = self.record, self.path
            self._module = vin
        return self._module


def as_vin_weights(model) -> VINWeights:
    """`model` if it is `VINWeights`, else the weights of a PyTorch `VIN` (`VINWeights.from_module`)."""
    return model if isinstance(model, VINWeights) else VINWeights.from_module(model)
