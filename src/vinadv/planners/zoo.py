"""The model zoo, declared in the registry (`vinadv.planners.registry.models`): this module re-exports it for code
that imports `vinadv.planners.zoo`."""

from __future__ import annotations

# the declarations, run (not `from vinadv.planners.registry import ...`: that would name the whole package)
from vinadv.planners.registry.declarations import LOADERS as _DECLARED  # noqa: F401
from vinadv.planners.registry.models import (
    KINDS,
    MODEL_ALIASES,
    MODELS,
    Model,
    ZooModel,
    file_sha256,
    model_of_file,
    read_zoo,
    resolve,
    verify,
    zoo_model,
)

__all__ = [
    "KINDS",
    "MODELS",
    "MODEL_ALIASES",
    "Model",
    "ZooModel",
    "file_sha256",
    "model_of_file",
    "read_zoo",
    "resolve",
    "verify",
    "zoo_model",
]
