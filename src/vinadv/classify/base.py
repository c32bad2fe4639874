"""The common base of the FP/DP classifiers, and the model file format.

Every classifier follows the scikit-learn estimator API: `fit(X, y)`, `predict(X)`, `decision_function(X)`
(positive = FP), `get_params()`. `X` is a `PathPairBatch`; image classifiers also take rendered path images
`(n, N, N, 3)` uint8. `y` holds the label strings 'DP' / 'FP' (from the rule labeller or from people).

Model files are `.npz` archives (read with `allow_pickle=False`, so loading never runs code) with entries
`format` ("vinadv.classifier/1"), `kind`, `params` (JSON constructor arguments), `meta` (JSON fitted state and
the training record) and the fitted arrays.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin

from vinadv.errors import InputError, first_line
from vinadv.outfile import atomic_output
from vinadv.vocabulary import FORK_OR_DETOUR

MODEL_FORMAT = "vinadv.classifier/1"
#: The two classes of the image classifiers, in scikit-learn order (`decision_function > 0` means FP).
FP_DP_CLASSES = np.array(FORK_OR_DETOUR)

_REGISTRY: dict[str, type] = {}


def _registry() -> dict[str, type]:
    """Every model kind: the classes register themselves when their modules are imported (done here, at first use,
    since the package imports its modules lazily)."""
    import vinadv.classify.hybrid  # noqa: PLC0415 (an import cycle: the model modules import this one)
    import vinadv.classify.models  # noqa: PLC0415 (as above)
    import vinadv.classify.similarity  # noqa: F401, PLC0415 (as above)

    return _REGISTRY


def register_kind(*kinds: str):
    """Class decorator: the model kinds a class saves and loads."""

    def wrap(cls):
        for kind in kinds:
            _REGISTRY[kind] = cls
        return cls

    return wrap


class PairClassifier(ClassifierMixin, BaseEstimator):
    """Base of the FP/DP classifiers. Subclasses define `kind`, `fit`, `decision_function`, `_state`,
    `_from_state`."""

    kind = "abstract"

    @staticmethod
    def _label_array(X, y, classes: tuple[str, ...]) -> tuple[np.ndarray, list[str]]:
        """`y` as an array of one label per pair of `X` (else an InputError), and its labels not in `classes`,
        sorted (each classifier words that error itself)."""
        y = np.asarray(y)
        if y.ndim != 1 or len(y) != len(X):
            raise InputError(f"{len(y)} labels for {len(X)} path pairs")
        return y, sorted(set(np.unique(y).tolist()) - set(classes))

    def _check_y(self, X, y) -> np.ndarray:
        y, bad = self._label_array(X, y, FORK_OR_DETOUR)
        if bad:
            raise InputError(f"FP/DP classifiers take the labels 'DP' and 'FP' only, got {bad}")
        if len(np.unique(y)) < 2:
            raise InputError("training needs pairs of both classes, FP and DP")
        self.classes_ = FP_DP_CLASSES.copy()
        return y

    def _check_fitted(self, attribute: str) -> None:
        if not hasattr(self, attribute):
            raise InputError(f"this {type(self).__name__} is not fitted yet: call fit first")

    def predict(self, X) -> np.ndarray:
        """'FP' or 'DP' per pair, `(n,)` str."""
        return np.where(self.decision_function(X) > 0, "FP", "DP")

    # persistence ---------------------------------------------------------------------------------------
    def _json_params(self) -> dict:
        return self.get_params(deep=False)

    def _state(self) -> tuple[dict, dict]:  # pragma: no cover - abstract
        raise NotImplementedError

    @classmethod
    def _from_state(cls, kind: str, params: dict, meta: dict, arrays: dict):  # pragma: no cover - abstract
        raise NotImplementedError

    def save(self, path, record: dict | None = None, record_arrays: dict | None = None) -> None:
        """Write the fitted model to `path` (`.npz` archive), with an optional training record."""
        save_model(self, path, record, record_arrays)

    @classmethod
    def load(cls, path):
        """Read a model written by `save`; refuses a file of another format version or of another kind."""
        return load_model(path, expected=cls)


def pack_state(model) -> tuple[dict, dict]:
    """A fitted classifier as (JSON-ready header: kind, params, meta; named arrays), the form `save` writes and a
    wrapping classifier (the hybrid) nests."""
    meta, arrays = model._state()
    return {"kind": model.kind, "params": model._json_params(), "meta": meta}, arrays


def save_model(model: PairClassifier, path, record: dict | None = None, record_arrays: dict | None = None) -> None:
    """Save `model` (any registered kind) to `path`; `record`/`record_arrays` travel along (training facts)."""
    header, arrays = pack_state(model)
    entries = {f"a.{k}": np.asarray(v) for k, v in arrays.items()}
    entries.update({f"r.{k}": np.asarray(v) for k, v in (record_arrays or {}).items()})
    with atomic_output(path, "wb") as handle:  # a file handle keeps the user's name (np.savez would append .npz)
        np.savez_compressed(
            handle,
            format=np.array(MODEL_FORMAT),
            kind=np.array(model.kind),
            params=np.array(json.dumps(header["params"])),
            meta=np.array(json.dumps(header["meta"])),
            record=np.array(json.dumps(record or {})),
            **entries,
        )


def load_model(path, expected: type | None = None) -> PairClassifier:
    """Load a model file; `expected` (a class) refuses other kinds. Bad files raise InputError naming them.

    The loaded model carries the training record as `record_` (dict) and `record_arrays_` (dict of arrays).
    """
    path = Path(path)
    try:
        archive = dict(np.load(path, allow_pickle=False))
    except FileNotFoundError:
        raise
    except Exception as exc:  # noqa: BLE001 - zipfile and numpy raise a dozen types for a damaged archive
        raise InputError(f"{path}: not a vinadv model file ({first_line(exc)})") from None
    try:
        model = _model_from_archive(path, archive, expected)
    except InputError:
        raise
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        # a field missing or of the wrong type or shape inside an otherwise readable archive
        raise InputError(f"{path}: damaged vinadv model file ({type(exc).__name__}: {exc})") from None
    return model


def _model_from_archive(path: Path, archive: dict, expected: type | None) -> PairClassifier:
    if "format" not in archive or "kind" not in archive:
        raise InputError(f"{path}: not a vinadv model file (no 'format'/'kind' entries)")
    fmt = str(archive["format"])
    if fmt != MODEL_FORMAT:
        raise InputError(f"{path}: model format {fmt!r}; this vinadv reads {MODEL_FORMAT!r} only")
    kind = str(archive["kind"])
    cls = _registry().get(kind)
    if cls is None:
        raise InputError(f"{path}: unknown model kind {kind!r}; known kinds: {sorted(_REGISTRY)}")
    if expected is not None and not issubclass(cls, expected):
        raise InputError(f"{path}: holds a {kind!r} model, not a {expected.__name__}")
    params, meta = json.loads(str(archive["params"])), json.loads(str(archive["meta"]))
    record = json.loads(str(archive["record"])) if "record" in archive else {}
    for name, value in (("params", params), ("meta", meta), ("record", record)):
        if not isinstance(value, dict):
            raise InputError(f"{path}: field '{name}' is not a JSON object")
    arrays = {k[2:]: archive[k] for k in archive if k.startswith("a.")}
    model = cls._from_state(kind, params, meta, arrays)
    model.record_ = record
    model.record_arrays_ = {k[2:]: archive[k] for k in archive if k.startswith("r.")}
    return model


def model_from_state(header: dict, arrays: dict) -> PairClassifier:
    """Rebuild a model from `pack_state` output (used to nest one model inside another)."""
    cls = _registry().get(header["kind"])
    if cls is None:
        raise InputError(f"unknown model kind {header['kind']!r}; known kinds: {sorted(_REGISTRY)}")
    return cls._from_state(header["kind"], header["params"], header["meta"], arrays)
