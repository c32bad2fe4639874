"""The planners vinadv knows by name, and bring-your-own planners by spec.

`load_planner(spec, size, ...)` gives a `Planner` for:
- `vin` (default): the VIN and its exact engine; weights from `weights=` or the shipped `vin{N}.pt`.
- `vin_robust`: the same VIN architecture with the shipped weights `vin{N}_robust.pt`, trained from the shift start
  (`vinadv.planners.vin.init_shift_kernels`) with adversarial rounds (`vinadv.hardening`).
- `gppn`: the Gated Path Planning Network; weights from `weights=` or the shipped `gppn{N}.pt`.
- `vin-mpd32`, `gppn-mpd32`: the VIN and the GPPN trained by `vin train` / `gppn train` on the MP dataset's 32x32
  `moore` maps (six families' train and valid splits, `maps import --format mpd` then `maps concat`), shipped as
  `vin_mpd32.pt` and `gppn_mpd32.pt`: they plan `moore` maps of 32x32 and refuse others (size, movement model).
- `optimal`: exact shortest paths (the control: what a perfect planner does).
- `astar`: vanilla A* on the maps' movement model, with its expansions (`vinadv.planners.classical.astar`; on
  `moore` maps the Neural A* authors' vanilla A*).
- `wastar`: weighted A*, `f = g + w * h` (`wastar:w=3`; w >= 1, default 2): fewer expansions, suboptimal paths.
- `neural-astar`: Neural A* (Yonetani et al. 2021), the authors' CNN encoder and search on `moore` maps; weights from
  `weights=` or the shipped `neural_astar_mazes32.pt` (converted from the authors' mazes checkpoint; the encoder is
  fully convolutional, so the same file serves every map size).
- `neural-astar-mpd5`: Neural A* with the shipped `neural_astar_mpd5.pt`, trained by `vinadv neural-astar train` on
  the train splits of the five MP families other than mazes (its record beside it).
- `path/to/file.py:factory` or `package.module:factory`: `factory(size: int)` returns a `torch.nn.Module` whose
  `forward(obstacles, goals)` takes obstacles as 0/1 float32 `(B, N, N)` and goals as int64 `(B, 2)` and returns
  `(B, 8, N, N)` logits in DESIGN.md's action order; or an object with `plan_paths` (a search planner,
  `vinadv.planners.search.UserSearchPlanner`: its paths are checked by `check_paths`). Its source file and weights are
  checksummed for run records.
- a registered name followed by `:` and `key=value` pairs separated by commas, `wastar:w=3`: that planner with those
  parameters (`PlannerParam`; a `module:factory` never holds `=`, so the two read apart). Unknown keys and bad values
  are refused with one line naming them; the values are in the planner's config, so run records keep them.
- any of these but `optimal` with `+d4` after it (`gppn+d4`, `file.py:factory+d4`): that planner averaged over the
  8 rotations and flips of the map (`vinadv.planners.symmetric`), an exactly equivariant planner at 8 forwards.
"""

from __future__ import annotations

import importlib
import importlib.util
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from vinadv.errors import InputError
from vinadv.grid.actions import N_ACTIONS
from vinadv.grid.moves import DEFAULT_MOVES
from vinadv.planners.classical.astar import AStarPlanner, WeightedAStarPlanner
from vinadv.planners.classical.optimal import OptimalPlanner
from vinadv.planners.device import resolve_device
from vinadv.planners.interface import Planner, PlannerError, TorchPlanner, state_checksum
from vinadv.planners.search import SearchPlanner, UserSearchPlanner
from vinadv.planners.vin.planner import VINPlanner
from vinadv.planners.vin.weights import default_weights_path, load_vin_weights
from vinadv.planners.weights import (
    WEIGHTS_DIR,
    check_action_count,
    check_trained_size,
    trained_moves,
    weights_checksum,
)
from vinadv.planners.zoo import zoo_model

#: `load(size, weights, corner_cutting, device, **params)`: a registered planner for `size x size` maps, with the
#: values of its `PlannerParam`s as keyword arguments (none for a planner without parameters); `device` a checked
#: device name (`resolve_device`), or None for the planner's default
Loader = Callable[..., Planner]


@dataclass(frozen=True)
class PlannerParam:
    """A parameter of a registered planner, given in the spec as `name:key=value` (`wastar:w=3`).

    Attributes:
        name: the key (an identifier).
        default: the value when the spec does not give it; its type (int or float) is the parameter's.
        description: one line for `vinadv planners`.
        minimum: the smallest value allowed (None: no bound).
    """

    name: str
    default: float | int
    description: str
    minimum: float | int | None = None

    def parse(self, spec: str, text: str) -> float | int:
        """The value `text` of this parameter, or PlannerError naming the spec, the key and the value."""
        kind = int if isinstance(self.default, int) else float
        try:
            value = kind(text)
        except ValueError:
            value = None
        bound = "" if self.minimum is None else f" >= {self.minimum:g}"
        if value is None or not math.isfinite(value) or (self.minimum is not None and value < self.minimum):
            what = "an integer" if kind is int else "a number"
            raise PlannerError(f"planner {spec!r}: parameter {self.name} must be {what}{bound}, got {text!r}")
        return value

    def to_dict(self) -> dict:
        return {"name": self.name, "default": self.default, "minimum": self.minimum, "description": self.description}


@dataclass(frozen=True)
class PlannerInfo:
    """One registered planner: its name, what it is, how to load it and where its shipped weights are.

    Attributes:
        load: `load(size, weights, corner_cutting, device) -> Planner`; `weights` is None unless `takes_weights`;
            `device` a checked device name, or None for the planner's default (a torch planner on the CPU).
        default_weights: `default_weights(size) -> Path`, the shipped weights for `size x size` maps; None: a
            planner without weights.
        takes_weights: whether `load_planner(..., weights=FILE)` may give it another weights file.
        params: the parameters a spec may give it (`name:key=value,...`), passed to `load` by keyword.
    """

    name: str
    description: str
    load: Loader
    default_weights: Callable[[int], Path] | None = None
    takes_weights: bool = False
    params: tuple[PlannerParam, ...] = ()

    def to_dict(self, size: int = 28) -> dict:
        """Name, description, the shipped weights for `size x size` maps (None: no weights) and whether present."""
        path = None if self.default_weights is None else self.default_weights(size)
        return {
            "name": self.name,
            "description": self.description,
            "weights": None if path is None else str(path),
            "weights_available": None if path is None else path.exists(),
            "params": [p.to_dict() for p in self.params],
        }

    def parse_params(self, spec: str, given: dict[str, str]) -> dict[str, float | int]:
        """Every parameter's value: `given` (key -> text, from the spec) over the defaults; an unknown key or a bad
        value raises PlannerError naming the spec and the key."""
        known = {p.name: p for p in self.params}
        for key in given:
            if key not in known:
                takes = f"takes {', '.join(known)}" if known else "takes no parameters"
                raise PlannerError(f"planner {spec!r}: unknown parameter {key!r} ({self.name} {takes})")
        return {name: (p.parse(spec, given[name]) if name in given else p.default) for name, p in known.items()}


#: the registered planners by name, in the order `vinadv planners` lists them
REGISTRY: dict[str, PlannerInfo] = {}
DEFAULT_PLANNER = "vin"
#: after a planner's name or spec: that planner averaged over the 8 symmetries of the grid (`load_symmetric`)
SUFFIX = "+d4"


def register(
    name: str,
    *,
    description: str,
    load: Loader,
    default_weights: Callable[[int], Path] | None = None,
    takes_weights: bool = False,
    params: tuple[PlannerParam, ...] = (),
) -> PlannerInfo:
    """Register planner `name`: `load_planner(name, ...)` calls `load` (with the values of `params` by keyword),
    `default_weights(name, size)` calls `default_weights(size)`. Registering imports nothing: the loaders import
    their planner's modules (PyTorch) when called. Refuses a name already registered, one that a spec would read
    otherwise (`:`, `=`, `,`, the `+d4` suffix), and parameters whose keys are not distinct identifiers."""
    if name in REGISTRY:
        raise InputError(f"name {name!r}: a planner of that name is already registered", "name")
    if not name or name != name.strip() or any(ch in name for ch in ":=,") or name.endswith(SUFFIX):
        raise InputError(
            f"name {name!r} would not read as a planner name: no ':', '=' or ',', no {SUFFIX} at its end, no spaces "
            "around it",
            "name",
        )
    keys = [p.name for p in params]
    if len(set(keys)) != len(keys) or not all(k.isidentifier() for k in keys):
        raise InputError(f"params {keys!r}: the keys of a planner's parameters are distinct identifiers", "params")
    info = PlannerInfo(name, description, load, default_weights, takes_weights, tuple(params))
    REGISTRY[name] = info
    return info


def _vin_weights_path(size: int) -> Path:
    return default_weights_path(size)


def _vin_robust_weights_path(size: int) -> Path:
    return WEIGHTS_DIR / f"vin{int(size)}_robust.pt"


def _gppn_weights_path(size: int) -> Path:
    from vinadv.planners.gppn import default_gppn_path  # noqa: PLC0415 (PyTorch: the VIN planners load without it)

    return default_gppn_path(size)


def _load_vin(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    loaded = load_vin_weights(weights, size=size)
    check_trained_size(loaded.path, loaded.record, size, "VIN")
    return VINPlanner(loaded, size=size, device=device)  # its `moves` from the record: `load_planner` checks them


def _load_vin_robust(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    path = _vin_robust_weights_path(size)
    if not path.exists():
        raise PlannerError(
            f"no shipped adversarially trained VIN for {size}x{size} maps ({path}); make one with "
            "`vinadv vin train --adversarial` and load it as planner 'vin' with those weights"
        )
    loaded = load_vin_weights(path, size=size)
    check_trained_size(loaded.path, loaded.record, size, "VIN")
    planner = VINPlanner(loaded, size=size, device=device)
    planner.name = "vin_robust"
    return planner


def _load_gppn(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    from vinadv.planners.gppn import load_gppn  # noqa: PLC0415 (PyTorch: the VIN planners load without it)
    from vinadv.planners.padding import ActionPadding  # noqa: PLC0415 (PyTorch, as above)

    model = load_gppn(weights, size=size)
    if device is not None:
        model = model.to(device)
    check_trained_size(model.weights_path, model.record, size, "GPPN")
    moves = trained_moves(model.weights_path, model.record)
    check_action_count(model.weights_path, model.config.n_actions, moves, "GPPN")
    planner = TorchPlanner(
        model if model.config.n_actions == N_ACTIONS else ActionPadding(model),  # news: 4 actions, -inf on the rest
        "gppn",
        size,
        checksum=weights_checksum(model.weights_path),
        config=model.config.to_dict(),
        device=device,
    )
    planner.moves = moves  # the model it was trained on: `load_planner` refuses maps of another
    return planner


#: the learned planners trained on the MP dataset's 32x32 moore maps: registry name -> shipped weights file
MPD_WEIGHTS = {"vin-mpd32": "vin_mpd32.pt", "gppn-mpd32": "gppn_mpd32.pt"}


def _shipped_mpd(name: str) -> Path:
    path = WEIGHTS_DIR / MPD_WEIGHTS[name]
    if not path.exists():
        raise PlannerError(
            f"planner {name!r}: its weights {path} are not shipped in this copy; train them as "
            "docs/guide/mpd.md says and load them as planner 'vin' or 'gppn' with --weights"
        )
    return path


def _load_vin_mpd32(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    planner = _load_vin(size, str(_shipped_mpd("vin-mpd32")), corner_cutting, device)  # size checked: 32
    planner.name = "vin-mpd32"
    return planner


def _load_gppn_mpd32(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    planner = _load_gppn(size, str(_shipped_mpd("gppn-mpd32")), corner_cutting, device)
    planner.name = "gppn-mpd32"
    return planner


def _neural_astar_weights_path(size: int) -> Path:
    return WEIGHTS_DIR / "neural_astar_mazes32.pt"  # one model for every size: the encoder is fully convolutional


def _load_neural_astar(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    from vinadv.planners.neural_astar.model import load_neural_astar  # noqa: PLC0415 (PyTorch: loaded when used)
    from vinadv.planners.neural_astar.planner import NeuralAstarPlanner  # noqa: PLC0415 (PyTorch, as above)

    return NeuralAstarPlanner(load_neural_astar(weights), size, device=device)


def _neural_astar_mpd5_path(size: int) -> Path:
    return WEIGHTS_DIR / "neural_astar_mpd5.pt"  # one model for every size, as `neural-astar`'s


def _load_neural_astar_mpd5(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    from vinadv.planners.neural_astar.model import load_neural_astar  # noqa: PLC0415 (PyTorch: loaded when used)
    from vinadv.planners.neural_astar.planner import NeuralAstarPlanner  # noqa: PLC0415 (PyTorch, as above)

    planner = NeuralAstarPlanner(load_neural_astar(_neural_astar_mpd5_path(size)), size, device=device)
    planner.name = "neural-astar-mpd5"
    return planner


def _load_optimal(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    return OptimalPlanner(size, corner_cutting)


def _load_astar(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    return AStarPlanner(size)  # the move rule comes with each search (`plan_paths`' corner_cutting)


def _load_wastar(size: int, weights: str | None, corner_cutting: bool, device: str | None, w: float) -> Planner:
    return WeightedAStarPlanner(size, w=w)


register(
    "vin",
    description="Value Iteration Network (Tamar et al. 2016) with vinadv's exact planning engine (default)",
    load=_load_vin,
    default_weights=_vin_weights_path,
    takes_weights=True,
)
register(
    "vin_robust",  # the VIN with its own weights: no other weights file (that is planner 'vin' with weights)
    description="the VIN, trained from the shift start and adversarially (`vin train --vi-init shift --adversarial`)",
    load=_load_vin_robust,
    default_weights=_vin_robust_weights_path,
)
register(
    "gppn",
    description="Gated Path Planning Network (Lee et al. 2018): LSTM-gated propagation, the actions of its moves",
    load=_load_gppn,
    default_weights=_gppn_weights_path,
    takes_weights=True,
)
register(
    "vin-mpd32",  # fixed weights, as vin_robust: another file is planner 'vin' with --weights
    description="the VIN trained on the MP dataset's 32x32 moore maps (six families; docs/guide/mpd.md)",
    load=_load_vin_mpd32,
    default_weights=lambda size: WEIGHTS_DIR / MPD_WEIGHTS["vin-mpd32"],
)
register(
    "gppn-mpd32",
    description="the GPPN trained on the MP dataset's 32x32 moore maps (six families; docs/guide/mpd.md)",
    load=_load_gppn_mpd32,
    default_weights=lambda size: WEIGHTS_DIR / MPD_WEIGHTS["gppn-mpd32"],
)
register(
    "optimal",
    description="exact shortest paths (Dijkstra, lowest action index on ties): the control",
    load=_load_optimal,
)
register(
    "astar",
    description="A* search on the maps' moves, with its expansions (on moore maps the Neural A* authors' vanilla A*)",
    load=_load_astar,
)
register(
    "wastar",
    description="weighted A* search, f = g + w*h: fewer expansions, suboptimal paths (wastar:w=3)",
    load=_load_wastar,
    params=(PlannerParam("w", 2.0, "the weight of the heuristic (1: A*)", minimum=1.0),),
)
register(
    "neural-astar",
    description="Neural A* (Yonetani et al. 2021): a CNN's guidance costs searched by A*, on moore maps",
    load=_load_neural_astar,
    default_weights=_neural_astar_weights_path,
    takes_weights=True,
)
register(
    "neural-astar-mpd5",  # its own weights: other weights are planner 'neural-astar' with weights
    description="Neural A* trained by `vinadv neural-astar train` on the five MP families other than mazes",
    load=_load_neural_astar_mpd5,
    default_weights=_neural_astar_mpd5_path,
)


def default_weights(name: str, size: int) -> Path | None:
    """The shipped weights file of planner `name` for `size x size` maps; None for a planner without weights (or
    one not registered)."""
    info = REGISTRY.get(name)
    return None if info is None or info.default_weights is None else info.default_weights(size)


def list_planners(size: int = 28) -> list[dict]:
    """The registered planners as JSON-ready dicts (name, description, default weights for `size`, present?)."""
    return [info.to_dict(size) for info in REGISTRY.values()]


def load_planner(
    spec: str | None,
    size: int,
    weights: str | None = None,
    corner_cutting: bool = True,
    device: str | None = None,
    moves: str = DEFAULT_MOVES,
) -> Planner:
    """The planner named or specified by `spec` (None: `vin`) for `size x size` maps.

    Args:
        spec: a registered name, with parameters (`wastar:w=3`) or not, or `file.py:factory` / `module:factory`.
        weights: a weights file for `vin`, `gppn` or `neural-astar` (default: the shipped ones); refused for the
            others.
        corner_cutting: the move rule of the maps (the `optimal` planner's logits follow it).
        device: the torch device of the planner's forward (`cpu`, `cuda`, `cuda:N`, `auto`: checked by
            `vinadv.planners.device.resolve_device`, `InputError` for one this machine lacks), recorded by type in
            `Planner.spec()`. None (default): a torch planner runs on the CPU and the VIN plans with its exact CPU
            engine; with a device the VIN plans with its PyTorch forward there (`VINPlanner`). `optimal` has no
            forward and ignores it.
        moves: the movement model of the maps (`vinadv.grid.moves`): the planner is `Planner.for_moves(moves)`.
            `optimal`, `astar` and `wastar` follow every model; `vin` and `gppn` plan the model their weights were
            trained on (their record's `moves`; `octile` for records without one) and the others `octile` moves;
            maps of another model are refused with one line naming both, rather than planning with masked logits:
            an 8-action policy on `news` maps would be judged on moves it was trained to make and the maps lack.

    Raises `PlannerError` (an `InputError`) naming the spec for anything that cannot be loaded.
    """
    spec = DEFAULT_PLANNER if spec is None else str(spec).strip()
    if device is not None:
        device = str(resolve_device(device))  # `auto` made concrete, refused here before anything loads
    return _load(spec, size, weights, corner_cutting, device).for_moves(moves)


def split_spec(spec: str) -> tuple[str, dict[str, str] | None]:
    """`(name, parameters)` of a spec: `wastar:w=3,x=1` -> `("wastar", {"w": "3", "x": "1"})`; a spec without
    parameters (a name, `file.py:factory`, `module:factory`: no `=`) -> `(spec, None)`. A parameter list that is not
    `key=value` pairs with distinct keys, or that follows something other than a registered name, raises
    PlannerError naming the spec."""
    head, sep, tail = spec.partition(":")
    if not sep or "=" not in tail:
        return spec, None
    name = head.strip()
    if name not in REGISTRY:
        raise PlannerError(
            f"planner {spec!r}: key=value parameters follow a registered planner name ({', '.join(REGISTRY)})"
        )
    given: dict[str, str] = {}
    for item in tail.split(","):
        key, eq, value = (part.strip() for part in item.partition("="))
        if not eq or not key or not value:
            raise PlannerError(f"planner {spec!r}: parameters are key=value pairs separated by commas, got {item!r}")
        if key in given:
            raise PlannerError(f"planner {spec!r}: parameter {key!r} is given twice")
        given[key] = value
    return name, given


def _load(spec: str, size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    if spec.endswith(SUFFIX):
        return load_symmetric(spec, size, weights, corner_cutting, device)
    name, given = split_spec(spec)
    info = REGISTRY.get(name)
    if weights is not None and (info is None or not info.takes_weights):
        raise PlannerError(f"planner {spec!r} takes no weights file (weights={weights!r})")
    if info is not None:
        return info.load(size, weights, corner_cutting, device, **info.parse_params(spec, given or {}))
    if ":" in spec:
        return load_custom(spec, size, device)
    raise PlannerError(
        f"unknown planner {spec!r}: use one of {', '.join(REGISTRY)}, or FILE.py:FACTORY / MODULE:FACTORY for your own"
    )


def load_symmetric(spec: str, size: int, weights: str | None, corner_cutting: bool, device: str | None) -> TorchPlanner:
    """`BASE+d4`: the planner `BASE` averaged over the grid's 8 symmetries (`vinadv.planners.symmetric`); its run
    records keep the base planner's weights checksum and add `"average": "d4"` to its config."""
    from vinadv.planners.symmetric import DihedralAverage  # noqa: PLC0415 (PyTorch: the VIN planners load without it)

    base_spec = spec[: -len(SUFFIX)].strip()
    if not base_spec or base_spec.endswith(SUFFIX):
        raise PlannerError(f"planner {spec!r}: {SUFFIX} follows one planner name or spec, once (e.g. gppn{SUFFIX})")
    # `_load`, not `load_planner`: the base's movement model is checked once, on the average (`load_planner`)
    base = _load(base_spec, size, weights, corner_cutting, device)
    module = base.differentiable
    if isinstance(base, SearchPlanner):  # the average is over policies: a search planner has none
        raise PlannerError(
            f"planner {spec!r}: {base.name!r} is a search planner; {SUFFIX} averages a policy planner's action "
            "probabilities (vin, gppn or your own torch module)"
        )
    if module is None:
        raise PlannerError(
            f"planner {spec!r}: {base.name!r} has no torch module to average ({SUFFIX} takes vin, gppn or your own)"
        )
    average = TorchPlanner(
        DihedralAverage(module).to(base.device),
        f"{base.name}{SUFFIX}",
        size,
        checksum=base.checksum,
        config={**base.config, "average": "d4"},
        device=device,
    )
    average.moves = base.moves  # the symmetries map each model's moves onto its own
    return average


def _is_file(source: str) -> bool:
    """Whether the part of a `SOURCE:FACTORY` spec before the colon names a file (else a module on the path)."""
    return source.endswith(".py") or "/" in source or "\\" in source


def load_custom(spec: str, size: int, device: str | None = None) -> Planner:
    """A bring-your-own planner from `file.py:factory` or `module:factory` (see the module docstring): a
    `TorchPlanner` around the factory's module, or a `UserSearchPlanner` around an object with `plan_paths`."""
    source, _, factory_name = spec.rpartition(":")
    if not source or not factory_name.isidentifier():
        raise PlannerError(f"planner {spec!r}: expected FILE.py:FACTORY or MODULE:FACTORY")
    source_sha = None
    if _is_file(source):
        path = Path(source)
        if not path.is_file():
            raise PlannerError(f"planner {spec!r}: no such file {source}")
        module_name = f"vinadv_user_planner_{abs(hash(str(path.resolve())))}"
        module_spec = importlib.util.spec_from_file_location(module_name, path)
        module = importlib.util.module_from_spec(module_spec)
        sys.modules[module_name] = module  # dataclasses and pickling look the module up by name
        try:
            module_spec.loader.exec_module(module)
        except (Exception, SystemExit) as exc:  # SystemExit: a sys.exit() at import must not end the command
            sys.modules.pop(module_name, None)
            raise PlannerError(f"planner {spec!r}: {source} failed to import: {type(exc).__name__}: {exc}") from None
        source_sha = weights_checksum(path)
    else:
        try:
            module = importlib.import_module(source)
        except (Exception, SystemExit) as exc:
            raise PlannerError(
                f"planner {spec!r}: cannot import module {source!r}: {type(exc).__name__}: {exc}"
            ) from None
        if getattr(module, "__file__", None):
            source_sha = weights_checksum(module.__file__)
    factory = getattr(module, factory_name, None)
    if not callable(factory):
        raise PlannerError(f"planner {spec!r}: {source} has no callable {factory_name!r}")
    try:
        net = factory(int(size))
    except (Exception, SystemExit) as exc:
        raise PlannerError(f"planner {spec!r}: {factory_name}({size}) failed: {type(exc).__name__}: {exc}") from None
    config = {"source": source, "factory": factory_name, "source_sha256": source_sha}
    if callable(getattr(net, "plan_paths", None)):  # a search planner: paths, not logits
        torch = sys.modules.get("torch")  # a search planner may be a torch module (its weights checksummed), or not
        stateful = torch is not None and isinstance(net, torch.nn.Module)
        return UserSearchPlanner(net, spec, size, checksum=state_checksum(net) if stateful else None, config=config)
    import torch

    if not isinstance(net, torch.nn.Module):
        raise PlannerError(
            f"planner {spec!r}: {factory_name}({size}) returned {type(net).__name__}, expected a torch.nn.Module "
            "(a policy planner) or an object with plan_paths (a search planner)"
        )
    net = net.to("cpu" if device is None else device)
    return TorchPlanner(
        net,
        spec,
        size,
        checksum=state_checksum(net),
        config=config,
        device=device,
    )


@dataclass(frozen=True)
class PlannerRef:
    """A loaded planner by reference, for another process (a Dask worker) to load the same one: the spec and weights
    file as absolute paths (None: the shipped weights there; a model of the zoo by its name), the map size, the move
    rule, the checksum the client's planner has (`Planner.checksum`), its movement model and the device its forward
    runs on where one was chosen (None: the planner's default; a worker without that device refuses it with one
    line). `load` refuses a planner whose checksum differs."""

    spec: str
    weights: str | None
    size: int
    corner_cutting: bool
    checksum: str | None
    moves: str = DEFAULT_MOVES
    device: str | None = None

    @classmethod
    def of(cls, planner: Planner, spec: str | None, weights: str | None, corner_cutting: bool) -> PlannerRef:
        """The reference of `planner`, loaded here by `load_planner(spec, ..., weights=weights)`."""
        spec = DEFAULT_PLANNER if spec is None else str(spec).strip()
        source, sep, factory = spec.rpartition(":")
        if sep and _is_file(source):
            spec = f"{Path(source).resolve()}:{factory}"
        if weights is not None and (Path(weights).exists() or zoo_model(str(weights)) is None):
            weights = str(Path(weights).resolve())  # a file; a zoo name stays a name, the same on every machine
        device = str(planner.device) if planner.device_type is not None else None
        return cls(spec, weights, int(planner.size), bool(corner_cutting), planner.checksum, planner.moves, device)

    def load(self, device: str | None = None) -> Planner:
        """The planner, loaded here, on `device` (default: the client's choice, `self.device`)."""
        planner = load_planner(
            self.spec,
            self.size,
            weights=self.weights,
            corner_cutting=self.corner_cutting,
            device=self.device if device is None else device,
            moves=self.moves,
        )
        if planner.checksum != self.checksum:
            raise PlannerError(
                f"planner {self.spec!r} (weights {self.weights or 'shipped'}) here has checksum "
                f"{planner.checksum}, the client's has {self.checksum}; workers need the same planner "
                "files at the same paths"
            )
        return planner
