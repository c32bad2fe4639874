"""The model zoo: the weights shipped with vinadv under names, with their sha256, training record and licence.

The index is `vinadv/weights/zoo.json` (format `vinadv.zoo/1`, package data beside the weights it names):
`{"format": ..., "models": {NAME: {planner, kind, file, sha256, size, moves, description, record, metrics, licence,
licence_file}}}`, where `planner` is the registered planner that loads the file by default, `kind` the weights
format that reads it (`vin`, `gppn`, `neural-astar`: the `vin28_robust` weights are VIN weights, so `--planner vin
--weights vin28_robust` loads them too), `file`, `record`, `metrics` and `licence_file` name files of the weights
folder (None: none), `size` the map side it was trained on (None: any).

Wherever a weights file is read (`vinadv.planners.weights.weights_file`, the one door of every planner's loader),
`resolve` lets a zoo name stand for its file, and every file of the zoo, named or shipped by default, is checked
against its sha256 before it is read (`verify`): a changed or damaged file is refused in one line naming it and both
checksums. Reads JSON and hashes files only: no NumPy, no PyTorch.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from vinadv.errors import InputError
from vinadv.jsonfile import read_json_document

ZOO_FORMAT = "vinadv.zoo/1"
#: the weights formats a zoo model may be read by, by the name the loaders pass to `weights_file`
KINDS = {"vin": "vin", "gppn": "gppn", "neural-astar": "neural-astar"}


@dataclass(frozen=True)
class ZooModel:
    """One model of the zoo (see the module doc); `folder` the weights folder its files are in."""

    name: str
    planner: str
    kind: str
    file: str
    sha256: str
    size: int | None
    moves: str
    description: str
    record: str | None
    metrics: str | None
    licence: str
    licence_file: str | None
    folder: Path

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


def _weights_dir() -> Path:
    from vinadv.planners.weights import WEIGHTS_DIR  # noqa: PLC0415 (that module imports this one)

    return WEIGHTS_DIR


def read_zoo(folder: str | os.PathLike | None = None) -> dict[str, ZooModel]:
    """The zoo of the weights folder `folder` (default: the shipped one), by name; InputError naming the index file
    and the field for an index that is not one."""
    folder = Path(_weights_dir() if folder is None else folder)
    return dict(_read_zoo(str(folder.resolve())))


@lru_cache(maxsize=8)
def _read_zoo(folder: str) -> tuple[tuple[str, ZooModel], ...]:
    index = Path(folder) / "zoo.json"
    data = read_json_document(index, ZOO_FORMAT, "model zoo index")
    models = data.get("models")
    if not isinstance(models, dict):
        raise InputError(f"{index}: field 'models' is not an object")
    fields = [f for f in ZooModel.__dataclass_fields__ if f not in ("name", "folder")]
    out = []
    for name, m in models.items():
        if not isinstance(m, dict) or set(m) != set(fields):
            raise InputError(f"{index}: model {name!r} must have exactly the fields {', '.join(fields)}")
        if m["kind"] not in KINDS.values():
            raise InputError(f"{index}: model {name!r}: field 'kind' is {m['kind']!r}, not one of {', '.join(KINDS)}")
        sha = m["sha256"]
        if not (isinstance(sha, str) and len(sha) == 64 and all(c in "0123456789abcdef" for c in sha)):
            raise InputError(f"{index}: model {name!r}: field 'sha256' is not 64 lowercase hex digits")
        out.append((name, ZooModel(name=name, folder=Path(folder), **m)))
    return tuple(out)


def zoo_model(name: str, folder: str | os.PathLike | None = None) -> ZooModel | None:
    """The zoo model `name`, or None when the zoo has none of that name."""
    return read_zoo(folder).get(str(name))


def model_of_file(path: str | os.PathLike, folder: str | os.PathLike | None = None) -> ZooModel | None:
    """The zoo model whose file `path` is (the same file once resolved), or None."""
    try:
        target = Path(path).resolve()
    except OSError:
        return None
    for model in read_zoo(folder).values():
        if model.path.resolve() == target:
            return model
    return None


def resolve(weights: str | os.PathLike, kind: str, folder: str | os.PathLike | None = None) -> str:
    """The weights file that `weights` names: itself when it is a file (or not a zoo name), else the file of the zoo
    model of that name, which must hold weights of `kind` (say `vin`: InputError naming both kinds otherwise)."""
    text = str(weights)
    if os.path.exists(text):
        return text  # a file of that name wins over a zoo name: the user named it
    model = zoo_model(text, folder)
    if model is None:
        return text
    if model.kind != kind:
        raise InputError(
            f"weights {text!r}: the model zoo's {text} holds {model.kind} weights (planner {model.planner}), not "
            f"{kind} weights"
        )
    return str(model.path)


def verify(path: str | os.PathLike, folder: str | os.PathLike | None = None) -> None:
    """When `path` is a file of the zoo, check its sha256 against the zoo's: InputError (one line, naming the file
    and both checksums) on a mismatch. Files outside the zoo are not checked (their checksum is recorded, not
    known in advance)."""
    model = model_of_file(path, folder)
    if model is None:
        return
    from vinadv.planners.weights import weights_checksum  # noqa: PLC0415 (that module imports this one)

    got = weights_checksum(path)
    if got != model.sha256:
        raise InputError(
            f"{path}: sha256 {got} does not match the model zoo's {model.sha256} for {model.name}: the file was "
            "changed or damaged (reinstall vinadv)"
        )
