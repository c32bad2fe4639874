"""`check_planner`: the checks every command applies to a planner, runnable in a bring-your-own author's own tests.

    from vinadv.planners import check_planner

    def test_my_planner_keeps_the_contract():
        check_planner(make(28))  # my_planner.py's factory

A planner (a `Planner`, or a user's object with `plan_paths`, or a `torch.nn.Module` with the policy contract, given
`size`) is checked for its name, size and movement model, then planned on a few small maps generated for its size
and model, and what it does is held against what it declares (`Capabilities`, scikit-learn's estimator tags):

- `plan` answers one checked path per start (a policy planner's logits pass `check_logits` and `check_masking`, a
  search planner's paths `check_paths`);
- a declared policy: `logits` pass `check_logits`;
- expansions: declared exactly where `plan` reports the expanded cells, of the maps' shape;
- value maps (its own or the stand-in): `(B, N, N)` float;
- gradients: declared exactly where it offers a differentiable module (`logits_module` for a policy planner,
  `differentiable_paths` for a search planner), whose output has the right shape and a gradient with respect to
  the obstacles.

The first problem is a `PlannerError` naming the planner, in one line; a planner that passes is returned (wrapped
where it was a user's object), ready to plan.
"""

from __future__ import annotations

import sys

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.generator import MIN_SIZE, generate_maps
from vinadv.grid.moves import check_moves
from vinadv.planners.interface import Capabilities, Planner, PlannerError, TorchPlanner, check_logits, is_planner
from vinadv.planners.search import UserSearchPlanner

__all__ = ["check_planner"]

#: maps `check_planner` generates (of the planner's size and movement model), and starts on each
CHECK_MAPS = 3
CHECK_STARTS = 2


def check_planner(
    planner, size: int | None = None, *, corner_cutting: bool = True, n_maps: int = CHECK_MAPS, seed: int = 0
) -> Planner:
    """`planner` checked against the contract and its declared capabilities (module doc) on `n_maps` generated maps
    of its size and movement model with 2 starts each, under `corner_cutting`; the planner (a user's object wrapped:
    `size` is its map side, default its `size` attribute). A problem: `PlannerError`, one line naming it."""
    planner = _as_planner(planner, size)
    name = planner.name
    if not isinstance(name, str) or not name:
        raise PlannerError(f"planner {name!r}: its name must be a non-empty string")
    size = planner.size
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < MIN_SIZE:
        raise PlannerError(f"planner {name!r}: its size {size!r} must be an int >= {MIN_SIZE} (the map side)")
    try:
        moves = check_moves(planner.moves, corner_cutting)
    except InputError as exc:
        raise PlannerError(f"planner {name!r}: its moves {planner.moves!r}: {exc}") from None
    capabilities = planner.capabilities
    if not isinstance(capabilities, Capabilities):
        raise PlannerError(f"planner {name!r}: capabilities is {type(capabilities).__name__}, not a Capabilities")
    maps = generate_maps(n_maps, int(size), seed, n_starts=CHECK_STARTS, corner_cutting=corner_cutting, moves=moves)
    obstacles, starts, goals = maps.obstacles, maps.starts, maps.goals
    result = planner.plan(obstacles, starts, goals, corner_cutting, moves)
    rows = len(obstacles) * CHECK_STARTS
    if len(result.paths) != rows:
        raise PlannerError(f"planner {name!r}: plan answered {len(result.paths)} paths for {rows} starts")
    _check_expansions(planner, capabilities, result, rows)
    if capabilities.policy:
        planner.logits(obstacles, goals)  # checked by `check_logits`
    # a planner whose value maps read the start is asked as the key-points ranking asks it
    with_starts = {"starts": starts[:, 0]} if capabilities.start_values else {}
    value = np.asarray(planner.value_maps(obstacles, goals, **with_starts))
    if value.shape != obstacles.shape or value.dtype.kind != "f":
        raise PlannerError(
            f"planner {name!r}: value_maps returned shape {value.shape} and dtype {value.dtype}; expected "
            f"{obstacles.shape} float"
        )
    _check_gradients(planner, capabilities, obstacles, starts[:, 0], goals)
    return planner


def _as_planner(obj, size: int | None) -> Planner:
    """A `Planner` as it is; a user's object with `plan_paths` as a `UserSearchPlanner`, a `torch.nn.Module` as a
    `TorchPlanner` (`size`, or the object's `size`, is the map side)."""
    if is_planner(obj):
        return obj
    label = getattr(obj, "name", None) or type(obj).__name__
    size = getattr(obj, "size", None) if size is None else size
    torch = sys.modules.get("torch")  # without PyTorch loaded, nothing is a module
    is_module = torch is not None and isinstance(obj, torch.nn.Module)
    if not callable(getattr(obj, "plan_paths", None)) and not is_module:
        raise PlannerError(
            f"planner {label!r}: a {type(obj).__name__} is not a planner; expected a Planner, an object with "
            "plan_paths (a search planner) or a torch.nn.Module (a policy planner)"
        )
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)):
        raise PlannerError(f"planner {label!r}: give its map side (size), got {size!r}", "size")
    if is_module:
        return TorchPlanner(obj, label, int(size))
    return UserSearchPlanner(obj, label, int(size))


def _check_expansions(planner: Planner, capabilities: Capabilities, result, rows: int) -> None:
    expanded = getattr(result, "expanded", None)
    if capabilities.expansions and expanded is None:
        raise PlannerError(f"planner {planner.name!r} declares expansions, but plan reported no expanded cells")
    if not capabilities.expansions and expanded is not None:
        raise PlannerError(
            f"planner {planner.name!r} reports expanded cells but does not declare expansions (capabilities)"
        )


def _check_gradients(planner: Planner, capabilities: Capabilities, obstacles, starts, goals) -> None:
    """A declared gradient module (of the logits, or of the path map for a planner without a policy) exists, gives
    the right shape and a gradient with respect to the obstacles; an undeclared one is refused too."""
    name = planner.name
    module = planner.logits_module if capabilities.policy else getattr(planner, "differentiable_paths", None)
    kind = "differentiable" if capabilities.policy else "differentiable_paths"
    if not capabilities.gradients:
        if module is not None:
            raise PlannerError(f"planner {name!r} offers a module ({kind}) but does not declare gradients")
        return
    if module is None:
        raise PlannerError(f"planner {name!r} declares gradients, but its {kind} is None")
    import torch  # noqa: PLC0415 (PyTorch: only a planner with gradients needs it)

    device = getattr(planner, "device", torch.device("cpu"))
    b, n = obstacles.shape[0], obstacles.shape[1]
    x = torch.from_numpy(obstacles.astype(np.float32)).to(device).requires_grad_(True)
    g = torch.from_numpy(goals.astype(np.int64)).to(device)
    if hasattr(module, "eval"):
        module.eval()  # as the saliency attack runs it
    try:
        if capabilities.policy:
            out, expected = module(x, g), (b, 8, n, n)
        else:
            out, expected = module(x, torch.from_numpy(starts.astype(np.int64)).to(device), g), (b, n, n)
    except (Exception, SystemExit) as exc:  # a user's module: say which planner failed, in one line
        raise PlannerError(f"planner {name!r}: its {kind} module failed: {type(exc).__name__}: {exc}") from None
    if not isinstance(out, torch.Tensor) or tuple(out.shape) != expected:
        got = tuple(out.shape) if isinstance(out, torch.Tensor) else type(out).__name__
        raise PlannerError(f"planner {name!r}: its {kind} module gave {got}; expected a tensor of shape {expected}")
    if capabilities.policy:
        check_logits(name, out.detach(), b, n)
    grad = torch.autograd.grad(out.sum(), x, allow_unused=True)[0] if out.requires_grad else None
    if grad is None:
        raise PlannerError(f"planner {name!r}: its {kind} module gives no gradient with respect to the obstacles")
