"""Loading a planner by spec: `load_planner`, the spec's parts (`split_spec`), the `+d4` average, bring-your-own
planners (`load_custom`) and a loaded planner by reference for another process (`PlannerRef`).

A spec and weights are first made canonical (`resolve_choice`): an old spelling of a name is its name, and a family
planner given the shipped weights of a planner of its own (`vin` with `vin28-robust`) is that planner
(`vin-robust`), so the two load one planner under one name, chosen before it is loaded.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
from dataclasses import dataclass
from pathlib import Path

from vinadv.grid.moves import DEFAULT_MOVES
from vinadv.planners.device import resolve_device
from vinadv.planners.interface import Planner, PlannerError, TorchPlanner, state_checksum
from vinadv.planners.provenance import source_provenance
from vinadv.planners.registry.base import DEFAULT_PLANNER, REGISTRY, SUFFIX, canonical_name
from vinadv.planners.registry.models import model_of_file, zoo_model
from vinadv.planners.search import UserSearchPlanner
from vinadv.planners.weights import weights_checksum


def weights_model(weights: str | os.PathLike | None):
    """The zoo model that `weights` names (a zoo name or old spelling, or a shipped file's path), or None."""
    if weights is None:
        return None
    text = str(weights)
    return model_of_file(text) if os.path.exists(text) else zoo_model(text)


def resolve_choice(spec: str | None, weights: str | None) -> tuple[str, str | None]:
    """The canonical `(spec, weights)` of a planner choice: old spellings made the name (`vin_robust` ->
    `vin-robust`, `+d4` and parameters kept), and a family planner given the shipped weights of one of its fixed
    planners named as that planner, without weights: `("vin", "vin28-robust")` -> `("vin-robust", None)`, the same
    for the file's path; a fixed planner given its own weights the same. Anything else is returned as given."""
    spec = canonical_name(DEFAULT_PLANNER if spec is None else str(spec).strip())
    suffix = SUFFIX if spec.endswith(SUFFIX) else ""
    name = spec[: len(spec) - len(suffix)]
    info = REGISTRY.get(name)
    model = weights_model(weights)
    if info is None or model is None or model.kind != info.kind:
        return spec, weights
    owner = REGISTRY.get(model.planner)
    if owner is not None and not owner.takes_weights and (owner is info or owner.family == info.name):
        return owner.name + suffix, None
    return spec, weights


def same_choice(a: tuple[str | None, str | None], b: tuple[str | None, str | None]) -> bool:
    """Whether two `(planner, weights)` choices name one planner (`resolve_choice`): `("vin_robust", None)`,
    `("vin-robust", None)` and `("vin", "vin28_robust")` do."""
    return resolve_choice(*a) == resolve_choice(*b)


def default_weights(name: str, size: int) -> Path | None:
    """The shipped weights file of planner `name` for `size x size` maps; None for a planner without weights (or
    one not registered)."""
    info = REGISTRY.get(canonical_name(name))
    return None if info is None else info.default_weights(size)


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
    spec, weights = resolve_choice(spec, weights)  # the name chosen here, before the planner loads
    if device is not None:
        device = str(resolve_device(device))  # `auto` made concrete, refused here before anything loads
    return _load(spec, size, weights, corner_cutting, device).for_moves(moves)


def load_planner_for(spec: str | None, weights: str | None, maps, device: str | None = None) -> Planner:
    """`load_planner` for the maps `maps` describes: anything with their `size`, `corner_cutting` and `moves` (a
    `MapSet`, a `PairSet`, a job's config that names them)."""
    return load_planner(
        spec, maps.size, weights=weights, corner_cutting=maps.corner_cutting, device=device, moves=maps.moves
    )


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
        params = info.parse_params(spec, given or {})
        if not info.takes_weights and info.default_file is not None:
            weights = str(_fixed_weights(info, size))
        return info.load(size, weights, corner_cutting, device, **info.kwargs, **params)
    if ":" in spec:
        return load_custom(spec, size, device)
    raise PlannerError(
        f"unknown planner {spec!r}: use one of {', '.join(REGISTRY)}, or FILE.py:FACTORY / MODULE:FACTORY for your own"
    )


def _fixed_weights(info, size: int) -> Path:
    """The shipped weights of a planner that loads no others (`vin-robust`); PlannerError when this copy lacks
    them (another map size)."""
    path = info.default_weights(size)
    if not path.exists():
        raise PlannerError(
            f"planner {info.name!r}: no shipped weights for {size}x{size} maps ({path.name}); train some and load "
            f"them as planner {info.family!r} with --weights"
        )
    return path


def load_symmetric(spec: str, size: int, weights: str | None, corner_cutting: bool, device: str | None) -> TorchPlanner:
    """`BASE+d4`: the planner `BASE` averaged over the grid's 8 symmetries (`vinadv.planners.symmetric`); its run
    records keep the base planner's weights checksum and add `"average": "d4"` to its config."""
    from vinadv.planners.symmetric import DihedralAverage  # noqa: PLC0415 (PyTorch: the VIN planners load without it)

    base_spec = spec[: -len(SUFFIX)].strip()
    if not base_spec or base_spec.endswith(SUFFIX):
        raise PlannerError(f"planner {spec!r}: {SUFFIX} follows one planner name or spec, once (e.g. gppn{SUFFIX})")
    # `_load`, not `load_planner`: the base's movement model is checked once, on the average (`load_planner`)
    base = _load(base_spec, size, weights, corner_cutting, device)
    module = base.logits_module
    if not base.capabilities.policy:  # the average is over policies: a search planner has none
        raise PlannerError(
            f"planner {spec!r}: {base.name!r} declares no policy (a search planner); {SUFFIX} averages a policy "
            "planner's action probabilities (vin, gppn or your own torch module)"
        )
    if not base.capabilities.gradients or module is None:
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
    planner = _custom_planner(net, spec, size, factory_name, config, device)
    # what resumed bench chunks are compared by (`vinadv.planners.provenance`), out of the spec the entry key hashes
    folder = Path(source).parent if _is_file(source) else Path(getattr(module, "__file__", None) or ".").parent
    planner.provenance = source_provenance(module, folder)
    return planner


def _custom_planner(net, spec: str, size: int, factory_name: str, config: dict, device: str | None) -> Planner:
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
        spec, weights = resolve_choice(spec, weights)  # one planner, one reference: `vin-robust`, not `vin` + file
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
