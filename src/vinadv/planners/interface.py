"""One interface for every planner: whole-map action logits, and paths by DESIGN.md's rollout.

A whole-map policy planner answers `policy_logits(obstacles (B, N, N) bool, goals (B, 2)) -> (B, 8, N, N)` float
logits in DESIGN.md's action order (N, S, E, W, NE, NW, SE, SW); the logits do not depend on the agent's cell, so
one map per map serves all its rollouts. `Planner.plan_maps` turns them into paths with the compiled rollout of
`vinadv.planners.rollout` (argmax, lowest index on ties), the same for every planner. A planner may plan faster its
own way as long as the paths are the same: the VIN keeps its exact engine (`VINPlanner`).

Every planner's logits pass `check_logits`: a planner that returns another shape, a non-float type, NaN or +inf is
refused with a `PlannerError` (an `InputError`: the planner is the user's input) naming it.

PyTorch is imported by the planners that run it, when they run it: the VIN plans from NumPy weights
(`vinadv.planners.vin.arrays`) and a process that only plans with it never loads PyTorch.
"""

from __future__ import annotations

import copy
import hashlib
import sys
from abc import ABC, abstractmethod
from typing import TYPE_CHECKING

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.actions import N_ACTIONS
from vinadv.grid.moves import DEFAULT_MOVES, move_model
from vinadv.grid.shortest_paths import shortest_distances, valid_moves
from vinadv.planners.batching import chunk_slices, forward_batches, over_maps, torch_threads
from vinadv.planners.device import full_precision
from vinadv.planners.result import PlanResult, check_plan_inputs
from vinadv.planners.rollout import rollout_logits
from vinadv.planners.spec import PlannerSpec
from vinadv.planners.vin import engine
from vinadv.planners.vin.arrays import VINWeights
from vinadv.planners.weights import check_action_count, trained_moves, weights_checksum

if TYPE_CHECKING:  # PyTorch is loaded only by the planners that run it
    import torch
    from torch import nn

#: maps per chunk of `plan_maps`: bounds the memory of the logits (B * 8 * N * N floats) and of the path buffers.
DEFAULT_CHUNK = 1024
#: maps per forward of a torch planner on a GPU (`TorchPlanner.device_batch_size`): a whole planning chunk, so the
#: candidates of an exhaustive attack (about 500 a 28x28 map) go in one batch, several maps at once
DEVICE_BATCH = DEFAULT_CHUNK


class PlannerError(InputError):
    """A planner that does not keep the interface (wrong shape, type, NaN), or that cannot be loaded."""


def check_logits(name: str, logits, b: int, n: int) -> np.ndarray:
    """`logits` as a float32/float64 NumPy array `(b, 8, n, n)` without NaN or +inf (-inf masks a move); else a
    `PlannerError` naming `name`."""
    torch = sys.modules.get("torch")  # without PyTorch loaded, nothing is a tensor
    if torch is not None and isinstance(logits, torch.Tensor):
        if not torch.is_floating_point(logits):
            raise PlannerError(f"planner {name!r} returned {logits.dtype} logits; expected a float tensor")
        if logits.is_meta:  # shapes without data: nothing to copy to the CPU
            raise PlannerError(f"planner {name!r} returned logits on the 'meta' device, which holds no values")
        logits = logits.detach().to("cpu", torch.float32).numpy()
    elif isinstance(logits, np.ndarray):
        if logits.dtype.kind != "f":
            raise PlannerError(f"planner {name!r} returned {logits.dtype} logits; expected float")
    else:
        raise PlannerError(f"planner {name!r} returned {type(logits).__name__}; expected a (B, 8, N, N) float array")
    if logits.shape != (b, N_ACTIONS, n, n):
        raise PlannerError(
            f"planner {name!r} returned logits of shape {tuple(logits.shape)}; expected "
            f"(B, 8, N, N) = ({b}, {N_ACTIONS}, {n}, {n})"
        )
    if logits.dtype not in (np.float32, np.float64):
        logits = logits.astype(np.float32)
    # NaN orders nothing, and +inf ties every move it marks (an argmax then picks by position): both refused;
    # -inf is a masked move, allowed
    for what, bad in (("NaN", np.isnan), ("+inf", np.isposinf)):
        found = bad(logits)
        if found.any():
            maps = int(found.any(axis=(1, 2, 3)).sum())
            raise PlannerError(f"planner {name!r} returned {what} logits (on {maps} of {b} maps)")
    return logits


#: SHA-256 of no bytes: what `state_checksum` recorded for a module without state before it returned None there
#: (runs stored by an older vinadv may hold it; they compare equal to None)
EMPTY_SHA256 = hashlib.sha256().hexdigest()


def check_masking(
    name: str, logits: np.ndarray, obstacles: np.ndarray, goals: np.ndarray, corner_cutting: bool, moves: str
) -> None:
    """Refuse (`PlannerError` naming `name`) logits `(B, 8, N, N)` that mask (-inf) every legal move of a cell that
    can reach the goal: the rollout would then take an arbitrary move there. -inf on some moves is masking, allowed;
    checked only when some logit is -inf (the shortest paths it needs cost a Dijkstra per map)."""
    masked = np.isneginf(logits)
    if not masked.any():
        return
    open_move = valid_moves(obstacles, corner_cutting, moves) & ~masked.transpose(0, 2, 3, 1)
    dist, _ = shortest_distances(obstacles, goals, corner_cutting, moves)
    stuck = np.isfinite(dist) & (dist > 0) & ~open_move.any(axis=-1)
    if stuck.any():
        b, r, c = (int(v) for v in np.argwhere(stuck)[0])
        maps = int(stuck.any(axis=(1, 2)).sum())
        raise PlannerError(
            f"planner {name!r} returned -inf logits for every legal move of cell ({r}, {c}) of map {b}, which can "
            f"reach the goal (cells like it on {maps} of {len(logits)} maps)"
        )


def state_checksum(module: nn.Module) -> str | None:
    """SHA-256 (hex) of a module's state dict: names, dtypes, shapes and bytes, in name order; None for a module
    without parameters or buffers (a planner without weights, as `Planner.checksum` says of one)."""
    import torch

    state = module.state_dict()
    if not state:
        return None
    h = hashlib.sha256()
    for key, value in sorted(state.items()):
        t = value.detach().to("cpu").contiguous()
        h.update(f"{key}:{t.dtype}:{tuple(t.shape)};".encode())
        h.update(t.numpy().tobytes() if t.dtype != torch.bfloat16 else t.float().numpy().tobytes())
    return h.hexdigest()


class Planner(ABC):
    """A whole-map policy planner for N x N maps.

    Attributes:
        name: the registry name or the user's spec (`vin`, `gppn`, `optimal`, `file.py:factory`), used in errors.
        size: N, the map side the planner was made for.
        moves: the movement model it plans for (`vinadv.grid.moves`): the actions its rollouts take and the L of
            their step limit. `octile` unless the planner says otherwise (the learned planners were trained on
            octile maps); `for_moves` gives the planner for the maps' model or refuses.
    """

    name: str
    size: int
    moves: str = DEFAULT_MOVES
    #: the device type (`cpu`, `cuda`) its forward was asked to run on (`--device`), recorded in `spec()`; None: the
    #: planner's default (the VIN's exact CPU engine, a torch planner on the CPU), recorded as before devices were
    device_type: str | None = None

    def for_moves(self, moves: str) -> Planner:
        """This planner for maps of the movement model `moves`: itself when it plans that model (a planner that can
        follow several, `optimal`, returns its own for `moves`), else PlannerError, one line naming both models. A
        planner is never masked down to another model's actions or judged with its costs: an 8-action policy on
        `news` maps, or an octile-trained one on `moore` maps, would be scored on moves it was not made for."""
        model = move_model(moves)
        if model.name != self.moves:
            raise PlannerError(
                f"planner {self.name!r} plans {self.moves} moves ({move_model(self.moves).description}); the maps use "
                f"{model.name!r} moves ({model.description})"
            )
        return self

    @abstractmethod
    def policy_logits(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray | torch.Tensor:
        """`(B, 8, N, N)` float action logits of every cell, for obstacles `(B, N, N)` bool and goals `(B, 2)`."""

    @property
    def checksum(self) -> str | None:
        """SHA-256 identifying the planner's weights (None for a planner without weights): `_checksum` where a
        subclass sets it."""
        return getattr(self, "_checksum", None)

    @property
    def config(self) -> dict:
        """Hyper-parameters worth recording (JSON values): `_config` where a subclass sets it."""
        return getattr(self, "_config", {})

    def spec(self) -> PlannerSpec:
        """What a run records about the planner: name, size, config and weights checksum, and the device type where
        one was chosen (`device_type`)."""
        spec = PlannerSpec(name=self.name, size=int(self.size), config=self.config, weights_sha256=self.checksum)
        if self.device_type is not None:
            spec["device"] = self.device_type
        return spec

    @property
    def differentiable(self) -> nn.Module | None:
        """A module computing the logits differentiably: `module(obstacles (B,N,N) float, goals (B,2) int64)`
        -> `(B, 8, N, N)` (the gradient attacks use it); None for a planner without gradients."""
        return None

    def value_maps(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """`(B, N, N)` float: how good each cell is for reaching the goal, for the value-based attack ranking.

        A planner without a value map gets a stand-in: the log-probability of the action it chooses at each cell
        (`max_a log_softmax(logits)`, its confidence). The VIN answers its value map `max_a q`, `optimal` minus
        the exact cost-to-go.
        """
        import torch

        logits = torch.from_numpy(self.logits(obstacles, goals))
        return torch.log_softmax(logits.double(), dim=1).max(dim=1).values.numpy()

    def logits(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """`policy_logits`, checked (`check_logits`): `(B, 8, N, N)` float32/float64 NumPy."""
        obstacles = np.ascontiguousarray(obstacles, dtype=bool)
        goals = np.ascontiguousarray(goals, dtype=np.int64)
        self._check_size(obstacles)
        raw = self.policy_logits(obstacles, goals)
        return check_logits(self.name, raw, obstacles.shape[0], obstacles.shape[1])

    def plan_maps(
        self,
        obstacles: np.ndarray,
        goals: np.ndarray,
        starts: np.ndarray,
        corner_cutting: bool = True,
        chunk_size: int = DEFAULT_CHUNK,
        progress: bool = False,
    ) -> PlanResult:
        """Paths from `starts (B, S, 2)`: path `b * S + s` from start `s` of map `b`, `chunk_size` maps at a time."""
        obstacles, goals, starts = check_multi_inputs(obstacles, goals, starts)
        self._check_size(obstacles)
        parts = []
        for sl in chunk_slices(len(obstacles), chunk_size, progress, f"planning ({self.name})"):
            logits = self.logits(obstacles[sl], goals[sl])
            check_masking(self.name, logits, obstacles[sl], goals[sl], corner_cutting, self.moves)
            parts.append(
                rollout_logits(
                    logits,
                    obstacles[sl],
                    goals[sl],
                    starts[sl],
                    corner_cutting,
                    moves=self.moves,
                )
            )
        return PlanResult.concat(parts)

    def plan_batch(
        self, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True
    ) -> PlanResult:
        """One path per map: `starts (B, 2)`; same paths as `plan_maps` with one start per map."""
        obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
        return self.plan_maps(obstacles, goals, starts[:, None, :], corner_cutting)

    def _check_size(self, obstacles: np.ndarray) -> None:
        if obstacles.ndim == 3 and obstacles.shape[1] != self.size:
            n = obstacles.shape[1]
            raise PlannerError(f"planner {self.name!r} is for {self.size}x{self.size} maps, the maps are {n}x{n}")


def check_multi_inputs(obstacles, goals, starts) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`check_plan_inputs` for `starts (B, S, 2)`: normalised `(obstacles, goals, starts)`."""
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    obstacles, _, goals = check_plan_inputs(obstacles, np.zeros((len(obstacles), 2)), goals)
    starts = np.ascontiguousarray(starts, dtype=np.int64)
    b, n = obstacles.shape[0], obstacles.shape[1]
    if starts.ndim != 3 or starts.shape[0] != b or starts.shape[2] != 2:
        raise InputError(f"starts has shape {starts.shape}, expected ({b}, S, 2)")
    if starts.size and (starts.min() < 0 or starts.max() >= n):
        raise InputError(f"starts has a cell outside the {n}x{n} grid")
    return obstacles, goals, starts


class TorchPlanner(Planner):
    """A planner around a `torch.nn.Module` whose `forward(obstacles, goals)` takes obstacles as 0/1 float32
    `(B, N, N)` and goals as int64 `(B, 2)` and returns `(B, 8, N, N)` logits (the bring-your-own contract).

    The module runs in eval mode without gradients, on `device` (the module must be there already: the loaders move
    it). On the CPU the maps are split between threads (`vinadv.planners.batching.over_maps`), each running the
    forward on one torch thread, so `forward` must not change the module's state, in batches of 16 to 31 maps
    where a thread has that many (`vinadv.planners.batching.forward_batches`: small enough to stay in the caches,
    large enough that a map's logits do not depend on its batch). On another device (a GPU) `device_batch_size`
    maps go in one forward, one batch after another: each batch's maps are sent as one uint8 tensor (a quarter of
    float32's bytes) and its logits come back in one copy. `module` stays available for gradient-based attacks.

    `device` None is the CPU, not recorded in `spec()`; a device given is recorded by its type (`device_type`).
    """

    def __init__(
        self,
        module: nn.Module,
        name: str,
        size: int,
        checksum: str | None = None,
        config: dict | None = None,
        device: str | torch.device | None = None,
        device_batch_size: int = DEVICE_BATCH,
    ):
        import torch
        from torch import nn

        if not isinstance(module, nn.Module):
            raise PlannerError(f"planner {name!r}: expected a torch.nn.Module, got {type(module).__name__}")
        self.module, self.name, self.size = module, name, int(size)
        self._checksum = checksum if checksum is not None else state_checksum(module)
        self._config = dict(config or {})
        self.device_batch_size = max(1, int(device_batch_size))
        self.device = torch.device("cpu" if device is None else device)
        self.device_type = None if device is None else self.device.type

    @property
    def differentiable(self) -> nn.Module:
        return self.module

    def policy_logits(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        import torch

        self.module.eval()
        b, n = obstacles.shape[0], obstacles.shape[1]
        out = np.empty((b, N_ACTIONS, n, n), dtype=np.float32)
        on_cpu = self.device.type == "cpu"

        def forward(lo: int, hi: int) -> None:
            with torch.no_grad():  # per thread: grad mode is thread-local
                for sl in forward_batches(lo, hi, on_cpu, self.device_batch_size):
                    # sent as uint8 (a quarter of float32's bytes to a GPU), made 0/1 float32 where the forward runs
                    obs = torch.from_numpy(obstacles[sl].view(np.uint8)).to(self.device).float()
                    g = torch.from_numpy(goals[sl].astype(np.int64)).to(self.device)
                    try:
                        raw = self.module(obs, g)
                    except (Exception, SystemExit) as exc:  # a user's module: say which planner failed, in one line
                        raise PlannerError(
                            f"planner {self.name!r}: forward failed: {type(exc).__name__}: {exc}"
                        ) from None
                    out[sl] = check_logits(self.name, raw, obs.shape[0], n)  # one copy back per batch

        if not on_cpu:  # whole batches on the device, one after another, in float32 (`full_precision`)
            with full_precision(self.device):
                forward(0, b)
            return out
        with torch_threads(1):  # maps split between threads, one torch thread each
            over_maps(b, forward)
        return out


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
    """

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
    def differentiable(self) -> nn.Module:
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

    def plan_maps(
        self,
        obstacles: np.ndarray,
        goals: np.ndarray,
        starts: np.ndarray,
        corner_cutting: bool = True,
        chunk_size: int | None = None,
        progress: bool = False,
    ) -> PlanResult:
        # the PyTorch forward on the device, or for a movement model the engine does not plan (it plans octile
        # moves), then the rollout every planner shares
        if self._device is not None or self.moves != DEFAULT_MOVES:
            chunk = DEFAULT_CHUNK if chunk_size is None else chunk_size
            return super().plan_maps(obstacles, goals, starts, corner_cutting, chunk, progress)
        obstacles, goals, starts = check_multi_inputs(obstacles, goals, starts)
        self._check_size(obstacles)
        return engine.plan_maps(
            obstacles, goals, starts, self.weights, corner_cutting, chunk_size or engine.DEFAULT_CHUNK, progress
        )


def as_planner(planner, size: int) -> Planner:
    """`planner` if it is a `Planner`; a `VIN` or `VINWeights` wrapped as the `vin` planner for `size x size` maps
    (the library functions that take a planner also take a VIN, as before there were other planners); any other
    `torch.nn.Module` as a `TorchPlanner` named after its class."""
    if isinstance(planner, Planner):
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
