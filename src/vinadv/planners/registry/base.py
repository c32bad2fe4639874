"""The registry's declarations: `register(name, entry_point="module:function", kwargs=..., models=...)`, one per
planner, in the style of Minigrid's `register(id=..., entry_point=..., kwargs=...)`; its parameters
(`PlannerParam`); the one spelling of every name (hyphens) and the old spellings still accepted (`canonical_name`).

Light: declaring imports nothing of the planners (no NumPy, no PyTorch); a loader is imported when first called.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from vinadv.errors import InputError
from vinadv.planners.registry.models import MODEL_ALIASES, MODELS, WEIGHTS_DIR, Model, ZooModel, add_model

#: `load(size, weights, corner_cutting, device, **kwargs, **params)`: a registered planner for `size x size` maps,
#: with the declaration's `kwargs` and the values of its `PlannerParam`s as keyword arguments; `weights` a file or
#: None (the planner's default), `device` a checked device name or None for the planner's default
Loader = Callable[..., Any]

#: the registered planners by name, in the order `vinadv planners` lists them
REGISTRY: dict[str, PlannerInfo] = {}
#: every old spelling of a planner's name (`vin_robust`) -> its name (`vin-robust`)
ALIASES: dict[str, str] = {}
DEFAULT_PLANNER = "vin"
#: after a planner's name or spec: that planner averaged over the 8 symmetries of the grid (`load_symmetric`)
SUFFIX = "+d4"


def _planner_error(message: str) -> Exception:
    from vinadv.planners.interface import PlannerError  # noqa: PLC0415 (the contract brings NumPy: raised only)

    return PlannerError(message)


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
            raise _planner_error(f"planner {spec!r}: parameter {self.name} must be {what}{bound}, got {text!r}")
        return value

    def to_dict(self) -> dict:
        return {"name": self.name, "default": self.default, "minimum": self.minimum, "description": self.description}


@dataclass(frozen=True)
class PlannerInfo:
    """One registered planner (see `register`).

    Attributes:
        entry_point: `"module:function"` (imported when first called) or the loader itself.
        kwargs: keyword arguments the loader is called with, beside those of every loader.
        default_file: the shipped weights file for `size x size` maps, a format with `{size}` (`vin{size}.pt`);
            None: a planner without weights.
        takes_weights: whether `load_planner(..., weights=FILE)` may give it another weights file; a planner that
            does not loads only its shipped weights (`vin-robust`), and is what its family planner (`vin`) is with
            those weights.
        kind: the weights format its files are in (`vin`, `gppn`, `neural-astar`; None: no weights).
        aliases: old spellings of `name`, still accepted wherever a planner is named.
        recorded_as: the old spelling its bench entry keys are computed with (`vin_robust`; None: its name), so
            stored chunks and committed entries keep their keys.
        models: its shipped weights (the zoo's models it declares).
    """

    name: str
    description: str
    entry_point: str | Loader
    kwargs: dict = field(default_factory=dict)
    default_file: str | None = None
    takes_weights: bool = False
    params: tuple[PlannerParam, ...] = ()
    kind: str | None = None
    aliases: tuple[str, ...] = ()
    recorded_as: str | None = None
    models: tuple[ZooModel, ...] = ()

    @property
    def load(self) -> Loader:
        """The loader (the entry point, imported)."""
        if callable(self.entry_point):
            return self.entry_point
        module, _, function = self.entry_point.partition(":")
        return getattr(importlib.import_module(module), function)

    def default_weights(self, size: int) -> Path | None:
        """The shipped weights for `size x size` maps (they may be absent: `vin16.pt`); None: no weights."""
        return None if self.default_file is None else WEIGHTS_DIR / self.default_file.format(size=int(size))

    @property
    def family(self) -> str | None:
        """The planner that loads any weights of this one's kind (`vin` for `vin-robust`); None: none."""
        if self.kind is None:
            return None
        if self.takes_weights:
            return self.name
        return next((p.name for p in REGISTRY.values() if p.takes_weights and p.kind == self.kind), None)

    def to_dict(self, size: int = 28) -> dict:
        """Name, description, the shipped weights for `size x size` maps (None: no weights) and whether present."""
        path = self.default_weights(size)
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
                raise _planner_error(f"planner {spec!r}: unknown parameter {key!r} ({self.name} {takes})")
        return {name: (p.parse(spec, given[name]) if name in given else p.default) for name, p in known.items()}


def _readable(name: str) -> bool:
    return bool(name) and name == name.strip() and not any(ch in name for ch in ":=,") and not name.endswith(SUFFIX)


def register(
    name: str,
    *,
    description: str,
    entry_point: str | Loader | None = None,
    kwargs: dict | None = None,
    default_file: str | None = None,
    takes_weights: bool = False,
    params: tuple[PlannerParam, ...] = (),
    kind: str | None = None,
    aliases: tuple[str, ...] = (),
    recorded_as: str | None = None,
    models: tuple[Model, ...] = (),
    load: Loader | None = None,
) -> PlannerInfo:
    """Register planner `name`: `load_planner(name, ...)` calls the loader `entry_point` (`"module:function"`, or
    `load=` a function) with `kwargs` and the values of `params` by keyword; `models` are its shipped weights, the
    zoo's. Registering imports nothing: the loaders import their planner's modules (PyTorch) when called.

    Refuses (InputError) a name or alias already registered, one that a spec would read otherwise (`:`, `=`, `,`,
    the `+d4` suffix), a new name with `_` (one spelling: hyphens; `aliases` keep old spellings), and parameters
    whose keys are not distinct identifiers."""
    if not isinstance(name, str) or not _readable(name) or not all(_readable(a) for a in aliases):
        raise InputError(
            f"name {name!r} would not read as a planner name: no ':', '=' or ',', no {SUFFIX} at its end, no spaces "
            "around it",
            "name",
        )
    if "_" in name:
        raise InputError(f"name {name!r}: planner names are spelled with hyphens (old spellings are aliases)", "name")
    for taken in (name, *aliases):
        if taken in REGISTRY or taken in ALIASES or taken in MODEL_ALIASES or (taken in MODELS and taken != name):
            raise InputError(f"name {taken!r}: a planner of that name is already registered", "name")
    keys = [p.name for p in params]
    if len(set(keys)) != len(keys) or not all(k.isidentifier() for k in keys):
        raise InputError(f"params {keys!r}: the keys of a planner's parameters are distinct identifiers", "params")
    entry = entry_point if entry_point is not None else load
    if entry is None or not (callable(entry) or (isinstance(entry, str) and ":" in entry)):
        raise InputError(f"planner {name!r}: entry_point is 'module:function' or a function", "entry_point")
    if models and kind is None:
        raise InputError(f"planner {name!r}: a planner with weights names their kind", "kind")
    taken = set(REGISTRY) | set(ALIASES) | {name, *aliases}
    loader = entry if isinstance(entry, str) else f"{entry.__module__}:{entry.__qualname__}"
    zoo = tuple(add_model(m, name, kind, loader, taken) for m in models)
    info = PlannerInfo(
        name,
        description,
        entry,
        dict(kwargs or {}),
        default_file,
        takes_weights,
        tuple(params),
        kind,
        tuple(aliases),
        recorded_as,
        zoo,
    )
    REGISTRY[name] = info
    ALIASES.update(dict.fromkeys(aliases, name))
    return info


def unregister(name: str) -> None:
    """Remove planner `name`, its aliases and its models (for tests that register their own)."""
    info = REGISTRY.pop(name)
    for alias in info.aliases:
        ALIASES.pop(alias, None)
    for model in info.models:
        MODELS.pop(model.name, None)
        for alias in model.aliases:
            MODEL_ALIASES.pop(alias, None)


def canonical_name(name: str) -> str:
    """The one spelling of a planner's name or spec: an old spelling of a registered name mapped to its name
    (`vin_robust` -> `vin-robust`, `vin_robust+d4` -> `vin-robust+d4`, `vin_robust:x=1` -> `vin-robust:x=1`); anything
    else as it is."""
    text = str(name).strip()
    if text.endswith(SUFFIX):
        return canonical_name(text[: -len(SUFFIX)]) + SUFFIX
    head, sep, tail = text.partition(":")
    if sep and "=" not in tail:
        return text  # FILE.py:FACTORY or MODULE:FACTORY
    return ALIASES.get(head.strip(), head) + sep + tail


def recorded_name(name: str) -> str:
    """The name a planner's bench entry key is computed with: `recorded_as` of a registered planner that declares
    one (`vin-robust` -> `vin_robust`, with `+d4` too), else `name` (old spellings first made
    canonical)."""
    text = canonical_name(name)
    if text.endswith(SUFFIX):
        return recorded_name(text[: -len(SUFFIX)]) + SUFFIX
    info = REGISTRY.get(text)
    return text if info is None or info.recorded_as is None else info.recorded_as


def spec_label(spec: Mapping[str, Any]) -> str:
    """The planner of a recorded `PlannerSpec` as one names it, with its parameters: the registered name followed by
    the values its `PlannerParam`s have in the spec's config (`wastar:w=3`; `wastar`, its default w = 2, is
    `wastar:w=2`), else the name as recorded (`vin`, `gppn+d4`, `file.py:factory`). What tells `wastar:w=2` and
    `wastar:w=3` apart where results are stored and shown (a robustness benchmark's `planner`)."""
    name, config = str(spec["name"]), spec.get("config") or {}
    info = REGISTRY.get(name)
    values = [f"{p.name}={config[p.name]:g}" for p in (info.params if info else ()) if p.name in config]
    return f"{name}:{','.join(values)}" if values else name
