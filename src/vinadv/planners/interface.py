"""The planner contract: one planning call, `Planner.plan`, and what a planner declares it can do beyond it.

`Planner.plan(obstacles, starts, goals, corner_cutting, moves)` is the one planning call, with one argument order,
always checked, told the maps' corner-cutting rule and movement model: paths, terminations and, where the planner
reports them, the cells each search expanded (`SearchResult.expanded`). One chunk loop serves every planner; a
planner gives the step that plans one chunk (`Planner._chunk_planner`):

- a policy planner answers `policy_logits(obstacles (B, N, N) bool, goals (B, 2)) -> (B, 8, N, N)` float logits in
  DESIGN.md's action order (N, S, E, W, NE, NW, SE, SW); the logits do not depend on the agent's cell, so one map
  per map serves all its rollouts, and the step turns them into paths with the compiled rollout of
  `vinadv.planners.rollout` (argmax, lowest index on ties), the same for every policy planner. A planner may plan
  faster its own way as long as the paths are the same: the VIN's step is its exact engine
  (`vinadv.planners.vin.planner.VINPlanner`);
- a search planner (`vinadv.planners.search.SearchPlanner`) answers paths, one per row, from its `plan_paths`, and
  every answer passes `check_paths`.

What a planner can do beyond planning is declared (`Capabilities`, as scikit-learn's estimator tags), never inferred
from its class: the library asks `planner.capabilities` (`require` refuses in one line), and no module outside this
one asks a planner its class. `vinadv.planners.checks.check_planner` tests a planner against its declaration.

Every planner's logits pass `check_logits`: a planner that returns another shape, a non-float type, NaN or +inf is
refused with a `PlannerError` (an `InputError`: the planner is the user's input) naming it.

PyTorch is imported by the planners that run it, when they run it: the VIN plans from NumPy weights
(`vinadv.planners.vin.arrays`) and a process that only plans with it never loads PyTorch. This module is the
contract: it imports no planner family (the VIN's planner is `vinadv.planners.vin.planner`).
"""

from __future__ import annotations

import hashlib
import sys
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, fields
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

if TYPE_CHECKING:  # PyTorch is loaded only by the planners that run it
    import torch
    from torch import nn

    from vinadv.grid.mapset import MapSet

#: maps per chunk of `plan_maps`: bounds the memory of the logits (B * 8 * N * N floats) and of the path buffers.
DEFAULT_CHUNK = 1024
#: maps per forward of a torch planner on a GPU (`TorchPlanner.device_batch_size`): a whole planning chunk, so the
#: candidates of an exhaustive attack (about 500 a 28x28 map) go in one batch, several maps at once
DEVICE_BATCH = DEFAULT_CHUNK


class PlannerError(InputError):
    """A planner that does not keep the interface (wrong shape, type, NaN), or that cannot be loaded."""


@dataclass(frozen=True)
class Capabilities:
    """What a planner can do beyond `Planner.plan` (declared by each planner class, as scikit-learn's estimator tags).

    Attributes:
        policy: a policy at every cell: `policy_logits` / `logits` answer `(B, 8, N, N)` action logits (the
            per-cell metrics, the gppn and kentsommer protocols, the `+d4` average read it).
        value_maps: value maps of its own from `value_maps` (the VIN's `max_a q`, `optimal`'s minus the cost-to-go, a
            search's heuristic map), not the stand-in every planner has (its policy's confidence, or minus the exact
            cost-to-go for a search planner).
        gradients: a differentiable module (the saliency attack): of the logits for a policy planner
            (`logits_module`), of a path map for a search planner (`differentiable_paths`).
        expansions: `plan` reports the cells each search expanded (`SearchResult.expanded`: the Exp metric).
        start_values: its value maps depend on the search's start, and `value_maps(obstacles, goals, starts)` takes
            the starts `(B, 2)` (an encoder with a start channel: Neural A*'s, TransPath's); the key-points ranking
            passes them, so that it ranks the cells of the search it attacks.
    """

    policy: bool = False
    value_maps: bool = False
    gradients: bool = False
    expansions: bool = False
    start_values: bool = False

    @classmethod
    def from_mapping(cls, name: str, declared) -> Capabilities:
        """`declared` (a `Capabilities`, or a mapping of some of its fields to bools) as `Capabilities`; anything else
        is a `PlannerError` naming the planner `name`."""
        if isinstance(declared, cls):
            return declared
        known = [f.name for f in fields(cls)]
        if not hasattr(declared, "items"):
            raise PlannerError(
                f"planner {name!r}: capabilities {declared!r} is not a Capabilities or a mapping of {known} to bools"
            )
        unknown = sorted(set(declared) - set(known))
        if unknown or not all(isinstance(v, bool) for v in declared.values()):
            raise PlannerError(f"planner {name!r}: capabilities {dict(declared)!r}; expected some of {known} as bools")
        return cls(**declared)


#: what each capability gives, for the refusals of `require`
CAPABILITY_TEXT = {
    "policy": "a policy at every cell (policy_logits)",
    "value_maps": "value maps of its own",
    "gradients": "a differentiable module (gradients)",
    "expansions": "the cells each search expanded",
    "start_values": "value maps that read the start",
}


def require(planner: Planner, capability: str, what: str) -> None:
    """Refuse (`PlannerError`, one line naming the planner and what it lacks) a planner that does not declare
    `capability` (a `Capabilities` field), which `what` ("the gppn protocol") needs."""
    if not getattr(planner.capabilities, capability):
        raise PlannerError(f"{what} needs {CAPABILITY_TEXT[capability]}: planner {planner.name!r} declares none")


def is_planner(obj) -> bool:
    """Whether `obj` is a `Planner` (the one question on a planner's class the library asks, here in the contract)."""
    return isinstance(obj, Planner)


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


#: SHA-256 of no bytes: a stored checksum of a module without state; it compares equal to None, the checksum
#: `state_checksum` gives such a module
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
    """A planner for N x N maps: `plan` (the one planning call) and what `capabilities` declares.

    Attributes:
        name: the registry name or the user's spec (`vin`, `gppn`, `optimal`, `file.py:factory`), used in errors.
        size: N, the map side the planner was made for.
        moves: the movement model it plans for (`vinadv.grid.moves`): the actions its rollouts take and the L of
            their step limit. `octile` unless the planner says otherwise (the learned planners were trained on
            octile maps); `for_moves` gives the planner for the maps' model or refuses.
        capabilities: what it can do beyond `plan` (`Capabilities`); this base class is a whole-map policy planner.
        chunk_size: maps per chunk of `plan` when the caller gives none (None: all in one).
    """

    name: str
    size: int
    moves: str = DEFAULT_MOVES
    capabilities: Capabilities = Capabilities(policy=True)
    chunk_size: int | None = DEFAULT_CHUNK
    #: `vinadv eval`'s search protocol adds TransPath's expansions and cost ratios against their vanilla A* (its
    #: `eval.py`) on octile maps: declared by the planners those ratios are published for
    vanilla_ratios: bool = False
    #: the device type (`cpu`, `cuda`) its forward was asked to run on (`--device`), recorded in `spec()`; None: the
    #: planner's default (the VIN's exact CPU engine, a torch planner on the CPU), left out of `spec()`
    device_type: str | None = None

    def for_moves(self, moves: str) -> Planner:
        """This planner for maps of the movement model `moves`: itself when it plans that model (a planner that can
        follow several, `optimal`, returns its own for `moves`), else PlannerError, one line naming both models. A
        planner is never masked down to another model's actions or judged with its costs: an 8-action policy on
        `news` maps, or an octile-trained one on `moore` maps, would be scored on moves it was not made for."""
        self._check_moves(moves)
        return self

    def _check_moves(self, moves: str) -> None:
        model = move_model(moves)
        if model.name != self.moves:
            raise PlannerError(
                f"planner {self.name!r} plans {self.moves} moves ({move_model(self.moves).description}); the maps use "
                f"{model.name!r} moves ({model.description})"
            )

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
    def logits_module(self) -> nn.Module | None:
        """A module computing the logits differentiably: `module(obstacles (B,N,N) float, goals (B,2) int64)`
        -> `(B, 8, N, N)` (the gradient attacks use it), where `capabilities.gradients`; None otherwise."""
        return None

    def value_maps(self, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """`(B, N, N)` float: how good each cell is for reaching the goal, for the value-based attack ranking.

        A planner without a value map of its own (`capabilities.value_maps` False) gets a stand-in: the
        log-probability of the action it chooses at each cell (`max_a log_softmax(logits)`, its confidence). The
        VIN answers its value map `max_a q`, `optimal` minus the exact cost-to-go.
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

    def plan(
        self,
        obstacles: np.ndarray,
        starts: np.ndarray,
        goals: np.ndarray,
        corner_cutting: bool = True,
        moves: str | None = None,
        *,
        chunk_size: int | None = None,
        progress: bool = False,
    ) -> PlanResult:
        """Plan one path per start: the one planning call.

        Args:
            obstacles: `(B, N, N)` bool, True = obstacle, N the planner's `size`.
            starts: `(B, 2)` int, one start per map, or `(B, S, 2)`, S starts per map: path `b * S + s` is from
                start `s` of map `b`.
            goals: `(B, 2)` int `(row, col)`.
            corner_cutting: the maps' rule: whether a diagonal move may pass between two obstacles.
            moves: the maps' movement model (`vinadv.grid.moves`); a planner of another model is refused in one line
                (`for_moves` gives the planner of the maps' model where there is one). None: the planner's own.
            chunk_size: maps per chunk (bounds memory; default `self.chunk_size`, None there: all maps in one chunk).
            progress: a tqdm bar over chunks.

        Returns:
            `PlanResult`, checked (a policy planner's logits by `check_logits` and `check_masking`, a search planner's
            paths by `check_paths`); a search planner's is a `SearchResult`, with the cells it expanded where it
            reports them (`capabilities.expansions`).
        """
        obstacles, starts, goals = check_starts_inputs(obstacles, starts, goals)
        self._check_size(obstacles)
        if moves is not None:
            self._check_moves(moves)
        step = self._chunk_planner(bool(corner_cutting))
        chunk = self.chunk_size if chunk_size is None else chunk_size
        chunk = max(1, len(obstacles)) if chunk is None else chunk
        parts = [
            step(obstacles[sl], starts[sl], goals[sl])
            for sl in chunk_slices(len(obstacles), chunk, progress, f"planning ({self.name})")
        ]
        return self._result_type().concat(parts)

    def _result_type(self) -> type[PlanResult]:
        """The type of `plan`'s result (a search planner's is `SearchResult`)."""
        return PlanResult

    def _chunk_planner(self, corner_cutting: bool) -> Callable[[np.ndarray, np.ndarray, np.ndarray], PlanResult]:
        """The step of `plan`'s loop: `step(obstacles (b, N, N), starts (b, S, 2), goals (b, 2)) -> PlanResult` for
        one chunk of checked inputs, made once per call. A policy planner's: its checked logits, then the rollout
        every policy planner shares (one adapter); a planner with its own way to the same paths overrides it."""

        def step(obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray) -> PlanResult:
            logits = self.logits(obstacles, goals)
            check_masking(self.name, logits, obstacles, goals, corner_cutting, self.moves)
            return rollout_logits(logits, obstacles, goals, starts, corner_cutting, moves=self.moves)

        return step

    def plan_maps(
        self,
        obstacles: np.ndarray,
        goals: np.ndarray,
        starts: np.ndarray,
        corner_cutting: bool = True,
        chunk_size: int | None = None,
        progress: bool = False,
    ) -> PlanResult:
        """Deprecated: `plan(obstacles, starts, goals, ...)`, the one planning call, in its argument order. Paths from
        `starts (B, S, 2)`: path `b * S + s` from start `s` of map `b`."""
        obstacles, goals, starts = check_multi_inputs(obstacles, goals, starts)
        return self.plan(obstacles, starts, goals, corner_cutting, chunk_size=chunk_size, progress=progress)

    def plan_batch(
        self, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True
    ) -> PlanResult:
        """Deprecated: `plan(obstacles, starts, goals, corner_cutting)`, the one planning call. One path per map:
        `starts (B, 2)`."""
        obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
        return self.plan(obstacles, starts, goals, corner_cutting)

    def _check_size(self, obstacles: np.ndarray) -> None:
        if obstacles.ndim == 3 and obstacles.shape[1] != self.size:
            n = obstacles.shape[1]
            raise PlannerError(f"planner {self.name!r} is for {self.size}x{self.size} maps, the maps are {n}x{n}")


def plan_every_start(
    planner: Planner, maps: MapSet, *, chunk_size: int | None = None, progress: bool = False
) -> PlanResult:
    """`planner.plan` of every start of `maps` (a `vinadv.grid.MapSet`) under the maps' corner-cutting rule and
    movement model: path `b * S + s` from start `s` of map `b`. `chunk_size`, `progress`: as `Planner.plan`'s."""
    return planner.plan(
        maps.obstacles,
        maps.starts,
        maps.goals,
        maps.corner_cutting,
        maps.moves,
        chunk_size=chunk_size,
        progress=progress,
    )


def check_starts_inputs(obstacles, starts, goals) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`plan`'s inputs normalised: `(obstacles (B, N, N) bool, starts (B, S, 2) int64, goals (B, 2) int64)`, from
    starts `(B, 2)` (S = 1) or `(B, S, 2)`; one-line `InputError` naming the parameter otherwise."""
    if np.ndim(starts) == 2:
        obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
        return obstacles, starts[:, None, :], goals
    obstacles, goals, starts = check_multi_inputs(obstacles, goals, starts)
    return obstacles, starts, goals


def check_multi_inputs(obstacles, goals, starts) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`check_plan_inputs` for `starts (B, S, 2)`: normalised `(obstacles, goals, starts)`."""
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    obstacles, _, goals = check_plan_inputs(obstacles, None, goals)
    starts = np.ascontiguousarray(starts, dtype=np.int64)
    b, n = obstacles.shape[0], obstacles.shape[1]
    if starts.ndim != 3 or starts.shape[0] != b or starts.shape[2] != 2:
        raise InputError(f"starts has shape {starts.shape}, expected ({b}, S, 2)", "starts")
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

    Capabilities: a policy at every cell and gradients (the module); value maps are the stand-in.
    """

    capabilities = Capabilities(policy=True, gradients=True)

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
    def logits_module(self) -> nn.Module:
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
