"""Weights files of any planner: the folder of the shipped weights, the file a command reads, its checksum.

Each planner's own file format lives beside its model (`vinadv.planners.vin.weights` for the VIN,
`vinadv.planners.gppn` for the GPPN); what they share is here.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from vinadv.errors import InputError

#: the weights shipped with vinadv (`vin28.pt`, `gppn28.pt`, ...)
WEIGHTS_DIR = Path(__file__).resolve().parent.parent / "weights"
__all__ = ["WEIGHTS_DIR", "check_trained_size", "weights_checksum", "weights_file"]


def weights_checksum(path: str | os.PathLike) -> str:
    """SHA-256 of the file's bytes, as hex: identifies the model in run records."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def weights_file(path: str | os.PathLike | None, shipped: Path, planner: str, size: int) -> str:
    """The weights file to read: `path`, or the `shipped` weights of `planner` for `size x size` maps when None.
    Raises InputError naming a missing file (and, for shipped weights, how to make some)."""
    if path is None:
        if not shipped.exists():
            raise InputError(
                f"no shipped {planner} weights for {size}x{size} maps ({shipped}); train some with "
                f"`vinadv {planner.lower()} train` and pass --weights"
            )
        path = shipped
    name = str(path)
    if not os.path.exists(name):
        raise InputError(f"{name}: no such weights file")
    return name


def check_trained_size(name: str | os.PathLike | None, record: dict, size: int, planner: str) -> None:
    """Refuse (InputError naming the file `name` and both sizes) weights whose training `record` says they were
    trained on maps of another size than `size`: a VIN's or GPPN's convolutions run on any map, so nothing else
    would notice. Weights without a recorded size (ports of other code) are taken as they are."""
    trained = record.get("size") if isinstance(record, dict) else None
    if isinstance(trained, int) and not isinstance(trained, bool) and trained != size:
        raise InputError(
            f"{name or 'the weights'}: {planner} weights trained on {trained}x{trained} maps, the maps are "
            f"{size}x{size}"
        )
