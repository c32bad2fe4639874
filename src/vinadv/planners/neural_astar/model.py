"""Neural A*'s encoder: the map and the start + goal map in, a guidance cost map in (0, 1) out.

The authors' CNN encoder (their `encoder.CNN`, input "m+", the mazes model's configuration):

    X = [map (1 free, 0 obstacle), start map + goal map]                     (B, 2, N, N)
    depth blocks   conv3x3 (bias) -> batch norm -> ReLU,  2 -> 32 -> 64 -> 128 -> 256 channels (the first `depth`)
    then           conv3x3 (bias) -> batch norm,           -> 1 channel
    cost = sigmoid(...)                                                        (B, 1, N, N)

in one `nn.Sequential` called `model`, so the state-dict keys are the checkpoint's (`model.0.weight`,
`model.1.running_mean`, ..., `model.13.num_batches_tracked` at depth 4) without its `planner.encoder.` prefix. The
batch norms use their running statistics (eval mode) when planning. Every layer is a 3x3 convolution with zero padding
1, so the encoder runs on maps of any size; the search's softmax temperature is sqrt(N) (see `differentiable`).

The weights file (`save_neural_astar`, `load_neural_astar`) is `{"format": "vinadv.neural-astar/1", "config",
"state_dict", "record"}`, plain tensors and JSON values, read with the allow-list reader.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass

import torch
from torch import nn

from vinadv.errors import InputError
from vinadv.outfile import save_torch
from vinadv.planners.weights import WEIGHTS_DIR, as_loaded, torch_load, weights_file

NEURAL_ASTAR_FORMAT = "vinadv.neural-astar/1"
#: the output channels of the authors' CNN encoder blocks; a depth-d encoder uses the first d
CHANNELS = (32, 64, 128, 256)
#: input channels of the "m+" encoder input: the map and the start + goal map
INPUT_CHANNELS = 2
#: the converted mazes model (MP dataset, mazes family, 32x32), shipped with vinadv
SHIPPED_WEIGHTS = WEIGHTS_DIR / "neural_astar_mazes32.pt"
__all__ = [
    "CHANNELS",
    "NEURAL_ASTAR_FORMAT",
    "SHIPPED_WEIGHTS",
    "GuidanceEncoder",
    "NeuralAstar",
    "NeuralAstarConfig",
    "encoder_inputs",
    "encoder_shapes",
    "load_neural_astar",
    "save_neural_astar",
]


@dataclass(frozen=True)
class NeuralAstarConfig:
    """The model's settings (the authors' defaults, which their mazes model was trained with). The heuristic's
    tie-break weight is the authors' 0.001 (`vinadv.planners.classical.astar.TIE_BREAK`), which their code does not
    vary.

    Attributes:
        depth: encoder blocks (1..4), the authors' `encoder.depth`.
        g_ratio: the search's f = g_ratio * g + (1 - g_ratio) * h (0.5: A*; 0: best-first search).
        encoder_input: "m+", the map and the start + goal map (the only input vinadv reads).
    """

    depth: int = 4
    g_ratio: float = 0.5
    encoder_input: str = "m+"

    def to_dict(self) -> dict:
        return asdict(self)

    def validate(self) -> None:
        if not 1 <= self.depth <= len(CHANNELS):
            raise InputError(f"Neural A* encoder depth must be 1..{len(CHANNELS)}, got {self.depth}", "depth")
        if not 0.0 <= self.g_ratio <= 1.0:
            raise InputError(f"Neural A* g_ratio must be in [0, 1], got {self.g_ratio}", "g_ratio")
        if self.encoder_input != "m+":
            raise InputError(
                f"Neural A* encoder input {self.encoder_input!r}: only 'm+' (map and start + goal map) is supported",
                "encoder_input",
            )


def encoder_shapes(depth: int) -> dict[str, tuple[int, ...]]:
    """The state-dict keys and shapes of a CNN encoder of `depth` blocks (keys of `GuidanceEncoder`)."""
    channels = [INPUT_CHANNELS, *CHANNELS[:depth], 1]
    shapes: dict[str, tuple[int, ...]] = {}
    for block, (c_in, c_out) in enumerate(zip(channels[:-1], channels[1:], strict=True)):
        conv, norm = 3 * block, 3 * block + 1  # conv, batch norm, ReLU per block
        shapes[f"model.{conv}.weight"] = (c_out, c_in, 3, 3)
        shapes[f"model.{conv}.bias"] = (c_out,)
        for name in ("weight", "bias", "running_mean", "running_var"):
            shapes[f"model.{norm}.{name}"] = (c_out,)
        shapes[f"model.{norm}.num_batches_tracked"] = ()
    return shapes


class GuidanceEncoder(nn.Module):
    """`forward(inputs (B, 2, N, N)) -> (B, 1, N, N)` guidance cost in (0, 1): the authors' CNN encoder."""

    def __init__(self, depth: int = 4):
        super().__init__()
        channels = [INPUT_CHANNELS, *CHANNELS[:depth], 1]
        layers: list[nn.Module] = []
        for c_in, c_out in zip(channels[:-1], channels[1:], strict=True):
            layers += [nn.Conv2d(c_in, c_out, 3, 1, 1), nn.BatchNorm2d(c_out), nn.ReLU()]
        self.model = nn.Sequential(*layers[:-1])  # no ReLU after the last batch norm: the sigmoid follows

    def forward(self, inputs: torch.Tensor) -> torch.Tensor:
        return torch.sigmoid(self.model(inputs))


def encoder_inputs(obstacles: torch.Tensor, starts: torch.Tensor | None, goals: torch.Tensor) -> torch.Tensor:
    """`(B, 2, N, N)`: the map (1 - obstacles: 1 free, as the MP dataset's) and the start map plus the goal map (2 at
    a start that is the goal), the authors' "m+" input; `starts` None marks the goal alone."""
    return torch.stack([1.0 - obstacles, start_goal_marks(obstacles, starts, goals)], dim=1)


def start_goal_marks(obstacles: torch.Tensor, starts: torch.Tensor | None, goals: torch.Tensor) -> torch.Tensor:
    """`(B, N, N)` like `obstacles`: 1 at each map's start and 1 at its goal (2 at a start that is the goal); `starts`
    None marks the goal alone. The marks channel of the Neural A* and TransPath inputs."""
    rows = torch.arange(obstacles.shape[0], device=obstacles.device)
    marks = torch.zeros_like(obstacles)
    if starts is not None:
        marks[rows, starts[:, 0], starts[:, 1]] += 1.0
    marks[rows, goals[:, 0], goals[:, 1]] += 1.0
    return marks


class NeuralAstar(nn.Module):
    """The encoder and the search's settings. `forward(obstacles (B, N, N) float 1/0, starts (B, 2), goals (B, 2))
    -> (B, N, N)` guidance cost maps; the search that uses them is `vinadv.planners.neural_astar.differentiable`
    (and, exactly, `planner.NeuralAstarPlanner`)."""

    def __init__(self, config: NeuralAstarConfig = NeuralAstarConfig()):
        super().__init__()
        config.validate()
        self.config = config
        self.encoder = GuidanceEncoder(config.depth)

    def forward(self, obstacles: torch.Tensor, starts: torch.Tensor | None, goals: torch.Tensor) -> torch.Tensor:
        return self.encoder(encoder_inputs(obstacles, starts, goals))[:, 0]


def save_neural_astar(model: NeuralAstar, path: str | os.PathLike, record: dict | None = None) -> None:
    """Write `{"format": "vinadv.neural-astar/1", "config", "state_dict" (the encoder's, CPU), "record"}` to `path`
    atomically."""
    record = json.loads(json.dumps(dict(record or {})))  # plain JSON types: loadable with weights_only=True
    state = {k: v.detach().to("cpu").contiguous().clone() for k, v in model.encoder.state_dict().items()}
    data = {"format": NEURAL_ASTAR_FORMAT, "config": model.config.to_dict(), "state_dict": state, "record": record}
    save_torch(data, path, mkdir=True)  # a full disk: one line naming the file, no temporary file left


_IMPORT_HINT = "the authors' Lightning checkpoint is converted by `vinadv neural-astar import-weights CKPT --out FILE`"


def load_neural_astar(path: str | os.PathLike | None = None) -> NeuralAstar:
    """The Neural A* model in `path` (a vinadv.neural-astar/1 file), or the shipped mazes model when None, in eval
    mode. Sets `record` (the import or training record) and `weights_path`. Raises InputError naming the file."""
    name = weights_file(path, SHIPPED_WEIGHTS, "neural-astar", 32)
    data = torch_load(name, "readable weights file")
    if isinstance(data, dict) and "state_dict" in data and "pytorch-lightning_version" in data:
        raise InputError(f"{name}: a Lightning checkpoint, not a vinadv Neural A* weights file; {_IMPORT_HINT}")
    if not isinstance(data, dict) or data.get("format") != NEURAL_ASTAR_FORMAT:
        raise InputError(f"{name}: not a Neural A* weights file (expected format {NEURAL_ASTAR_FORMAT!r})")
    try:
        model = NeuralAstar(NeuralAstarConfig(**data["config"]))
        model.encoder.load_state_dict(data["state_dict"])
    except (KeyError, TypeError, RuntimeError, InputError) as exc:
        raise InputError(
            f"{name}: config or state dict do not match a Neural A* model ({str(exc).splitlines()[0]})"
        ) from None
    return as_loaded(model, name, data)
