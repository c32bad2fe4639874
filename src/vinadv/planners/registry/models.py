"""The model zoo: the weights shipped with vinadv, each declared once with its planner (`register(...,
models=(Model(...),))` in `vinadv.planners.registry.declarations`): name, file, sha256, map size, movement model,
training record, metrics and licence.

Wherever a weights file is read (`vinadv.planners.weights.weights_file`, the one door of every planner's loader),
`resolve` lets a model's name (or an old spelling of it, `vin28_robust`) stand for its file, and every file of the
zoo, named or shipped by default, is checked against its sha256 before it is read (`verify`): a changed or damaged
file is refused in one line naming it and both checksums. Hashes files only: no NumPy, no PyTorch.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

from vinadv.checksums import file_sha256
from vinadv.errors import InputError

#: the weights shipped with vinadv (`vin28.pt`, `gppn28.pt`, ...): package data
WEIGHTS_DIR = Path(__file__).resolve().parents[2] / "weights"
#: the weights formats a zoo model may be read by, by the name the loaders pass to `weights_file`
KINDS = ("vin", "gppn", "neural-astar", "transpath-cf", "transpath-focal")
#: the zoo's models by name, in declaration order; filled by `add_model` (the registry's `register`)
MODELS: dict[str, ZooModel] = {}
#: every old spelling of a model's name (`vin28_robust`) -> its name (`vin28-robust`)
MODEL_ALIASES: dict[str, str] = {}


@dataclass(frozen=True)
class Model:
    """A shipped weights file, as its planner's declaration gives it.

    Attributes:
        name: the zoo name (`--weights NAME`), hyphens only.
        file: the file in the weights folder.
        sha256: its checksum, checked before every read.
        size: the map side it was trained on (None: any size, a fully convolutional model).
        moves: the movement model it plans.
        description: one line.
        licence: its licence, in words.
        record, metrics, licence_file: files of the weights folder beside it (None: none).
        aliases: old spellings of `name`, still accepted.
    """

    name: str
    file: str
    sha256: str
    size: int | None
    moves: str
    description: str
    licence: str
    record: str | None = None
    metrics: str | None = None
    licence_file: str | None = None
    aliases: tuple[str, ...] = field(default=())


@dataclass(frozen=True)
class ZooModel(Model):
    """A model of the zoo with the planner that declared it: `planner` loads it by default and `kind` is the weights
    format that reads it (`vin`, `gppn`, `neural-astar`: the `vin28-robust` weights are VIN weights, so
    `--planner vin --weights vin28-robust` loads them too, as the planner `vin-robust`)."""

    planner: str = ""
    kind: str = ""
    loader: str = ""

    @property
    def folder(self) -> Path:
        return WEIGHTS_DIR  # read at each call: tests point it at a copy

    @property
    def path(self) -> Path:
        return self.folder / self.file

    def training_record(self) -> dict | None:
        """The training (or import) record, read from its file; None when the model has none."""
        if self.record is None:
            return None
        return json.loads((self.folder / self.record).read_text(encoding="utf-8"))

    def to_dict(self) -> dict:
        """JSON-ready: every field, the files as absolute paths, and a summary of the training record (its format,
        the command that made the weights, when it started, the training data's sha256)."""
        record = self.training_record() or {}
        data = record.get("data") if isinstance(record.get("data"), dict) else {}
        return {
            "name": self.name,
            "planner": self.planner,
            "loader": self.loader,
            "kind": self.kind,
            "weights": str(self.path),
            "sha256": self.sha256,
            "size": self.size,
            "moves": self.moves,
            "description": self.description,
            "training": {
                "record": None if self.record is None else str(self.folder / self.record),
                "format": record.get("format"),
                "command": record.get("command"),
                "started": record.get("started"),
                "data_sha256": data.get("sha256"),
            },
            "metrics": None if self.metrics is None else str(self.folder / self.metrics),
            "licence": self.licence,
            "licence_file": None if self.licence_file is None else str(self.folder / self.licence_file),
        }


def add_model(model: Model, planner: str, kind: str, loader: str, taken: set[str]) -> ZooModel:
    """Add `model`, declared by `planner` (whose weights format is `kind`, loaded by `loader`), to the zoo. Refuses
    (InputError) a name or alias in `taken` (the planners' names and aliases: a zoo name may be its planner's own,
    `vin-mpd32`) or the zoo's already, a name with `_`, a kind not in `KINDS` or a checksum that is not 64 hex
    digits."""
    if kind not in KINDS:
        raise InputError(f"model {model.name!r}: kind {kind!r} is not one of {', '.join(KINDS)}", "kind")
    if "_" in model.name or not model.name or model.name != model.name.strip():
        raise InputError(f"model {model.name!r}: a zoo name is spelled with hyphens, not underscores", "name")
    for name in (model.name, *model.aliases):
        if name in MODELS or name in MODEL_ALIASES or (name in taken and name != planner):
            raise InputError(f"model name {name!r}: already taken", "name")
    sha = model.sha256
    if not (isinstance(sha, str) and len(sha) == 64 and all(c in "0123456789abcdef" for c in sha)):
        raise InputError(f"model {model.name!r}: sha256 is not 64 lowercase hex digits", "sha256")
    fields = {f: getattr(model, f) for f in Model.__dataclass_fields__}
    zoo = ZooModel(**fields, planner=planner, kind=kind, loader=loader)
    MODELS[zoo.name] = zoo
    MODEL_ALIASES.update(dict.fromkeys(model.aliases, zoo.name))
    return zoo


def read_zoo() -> dict[str, ZooModel]:
    """The zoo's models by name (a copy), in declaration order."""
    from vinadv.planners import registry  # noqa: F401, PLC0415 (its declarations fill the zoo)

    return dict(MODELS)


def zoo_model(name: str) -> ZooModel | None:
    """The zoo model `name` (or an old spelling of it, `vin28_robust`), or None when the zoo has none of that name."""
    zoo = read_zoo()
    name = str(name)
    return zoo.get(MODEL_ALIASES.get(name, name))


def model_of_file(path: str | os.PathLike) -> ZooModel | None:
    """The zoo model whose file `path` is (the same file once resolved), or None."""
    try:
        target = Path(path).resolve()
    except (OSError, ValueError):
        return None
    for model in read_zoo().values():
        if model.path.resolve() == target:
            return model
    return None


def resolve(weights: str | os.PathLike, kind: str) -> str:
    """The weights file that `weights` names: itself when it is a file (or not a zoo name), else the file of the zoo
    model of that name, which must hold weights of `kind` (say `vin`: InputError naming both kinds otherwise)."""
    text = str(weights)
    if os.path.exists(text):
        return text  # a file of that name wins over a zoo name: the user named it
    model = zoo_model(text)
    if model is None:
        return text
    if model.kind != kind:
        raise InputError(
            f"weights {text!r}: the model zoo's {model.name} holds {model.kind} weights (planner {model.planner}), "
            f"not {kind} weights"
        )
    return str(model.path)


def verify(path: str | os.PathLike) -> None:
    """When `path` is a file of the zoo, check its sha256 against the zoo's: InputError (one line, naming the file
    and both checksums) on a mismatch. Files outside the zoo are not checked (their checksum is recorded, not
    known in advance)."""
    model = model_of_file(path)
    if model is None:
        return
    got = file_sha256(path)
    if got != model.sha256:
        raise InputError(
            f"{path}: sha256 {got} does not match the model zoo's {model.sha256} for {model.name}: the file was "
            "changed or damaged (reinstall vinadv)"
        )
