"""Weights files of any planner: the folder of the shipped weights, the file a command reads, its checksum.

The shipped ones are the model zoo, declared in the registry (`vinadv.planners.registry.models`, which this
module reads and which imports nothing of it). Each planner's own file format lives beside its model
(`vinadv.planners.vin.weights` for the VIN, `vinadv.planners.gppn` for the GPPN); what they share is here.
"""

from __future__ import annotations

import os
import stat
import warnings
import zipfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from vinadv.errors import InputError
from vinadv.planners.registry.models import WEIGHTS_DIR, resolve, verify
from vinadv.planners.registry.models import file_sha256 as weights_checksum
from vinadv.records import TRAINING, upgrade

#: the most iterations (value-iteration steps, recurrent steps) k a weights file's config, or `--k`, may ask for:
#: far past any map a grid planner plans (the VIN's default is about 1.3 N; 1,000 crosses a 750 x 750 map), and
#: bounded so a file saying 10^18 is refused before the loop, not run for ever
MAX_ITERATIONS = 1000
#: the most channels of a layer (a VIN's l_h, l_q) a weights file's config may ask for
MAX_CHANNELS = 4096

__all__ = [
    "MAX_CHANNELS",
    "MAX_ITERATIONS",
    "WEIGHTS_DIR",
    "check_action_count",
    "check_iterations",
    "check_regular_file",
    "check_trained_size",
    "torch_load",
    "trained_moves",
    "weights_checksum",
    "as_loaded",
    "weights_path_checksum",
    "weights_file",
]


def weights_file(path: str | os.PathLike | None, shipped: Path, planner: str, size: int) -> str:
    """The weights file to read: `path` (a file, or the name of a model of the zoo holding `planner` weights:
    `vinadv.planners.registry.models`), or the `shipped` weights of `planner` for `size x size` maps when None. A
    file of the zoo is checked against the zoo's sha256 before it is read. Raises InputError naming a missing file
    (and, for shipped weights, how to make some), or a zoo file whose checksum differs (both checksums)."""
    if path is not None:
        path = resolve(path, planner.lower())
    if path is None:
        if not shipped.exists():
            raise InputError(
                f"no shipped {planner} weights for {size}x{size} maps ({shipped}); train some with "
                f"`vinadv {planner.lower()} train` and pass --weights"
            )
        path = shipped
    name = str(path)
    if not os.path.exists(name):
        raise InputError(f"{name}: no such weights file (nor a model of the zoo: `vinadv planners` lists them)")
    check_regular_file(name)
    verify(name)
    return name


def check_iterations(name: str | os.PathLike | None, k, what: str = "k") -> int:
    """`k` as an int when it is an iteration count in [1, `MAX_ITERATIONS`]; InputError naming the file `name`
    otherwise, before any loop runs."""
    if isinstance(k, bool) or not isinstance(k, int) or not 1 <= k <= MAX_ITERATIONS:
        raise InputError(f"{name or 'the weights'}: {what} is {k!r}, expected an integer in [1, {MAX_ITERATIONS}]")
    return k


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


def trained_moves(name: str | os.PathLike | None, record: dict) -> str:
    """The movement model (`vinadv.grid.moves`) the weights were trained on, from their training `record` (in
    today's form, `vinadv.records.TRAINING`): its `moves`, else its data's `moves`, else `octile` (a record that names
    no maps: weights from elsewhere). A name that is not a model raises InputError naming the file `name`."""
    # late: the commands import this module to start, and `vinadv.grid` brings Numba (tests/test_cli_imports.py)
    from vinadv.grid.moves import DEFAULT_MOVES, MOVES  # noqa: PLC0415

    record = upgrade(TRAINING, record) if isinstance(record, dict) else {}
    data = record.get("data") if isinstance(record.get("data"), dict) else {}
    moves = record.get("moves", data.get("moves", DEFAULT_MOVES))
    if moves not in MOVES:
        raise InputError(
            f"{name or 'the weights'}: record field 'moves' is {moves!r}, expected one of {', '.join(MOVES)}"
        )
    return moves


def check_action_count(name: str | os.PathLike | None, n_actions: int, moves: str, planner: str) -> None:
    """Refuse (InputError naming the file `name`) weights whose action count does not fit the movement model
    `moves` they plan (a 4-action model is a `news` model, an 8-action one `octile` or `moore`)."""
    from vinadv.grid.moves import move_model  # noqa: PLC0415 (late, as in `trained_moves`)

    expected = move_model(moves).n_actions
    if int(n_actions) != expected:
        raise InputError(
            f"{name or 'the weights'}: {planner} weights with {n_actions} actions plan {moves!r} moves, which have "
            f"{expected}"
        )


def torch_load(name: str | os.PathLike, what: str, allowed_globals: Iterable = ()) -> Any:
    """`torch.load(name, weights_only=True)` on the CPU: tensors and plain values (and `allowed_globals`), never
    code. A file torch cannot load so raises InputError in one line, "NAME: not a WHAT (why)", without torch's
    advice to load it with `weights_only=False` (which would run the file's code) and without its warnings. Before
    torch reads it: a file that is not a regular file (a FIFO, a device) is refused by type, a zip archive whose
    members fail their CRC-32 as damaged (`vinadv.planners.torchfile.check_archive`: torch does not check it); after,
    floating tensors holding NaN or infinities (`check_finite`)."""
    import torch

    from vinadv.planners.torchfile import check_archive, check_finite  # noqa: PLC0415 (beside torch)

    check_regular_file(name)
    check_archive(name)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # say, torch's note on a pickle protocol it did not write: the error says
            with torch.serialization.safe_globals(list(allowed_globals)):
                data = torch.load(name, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises many types for a bad file (pickle, zip, EOF, an unsafe global)
        raise InputError(f"{name}: not a {what} ({_why_unreadable(str(name), exc)})") from None
    check_finite(name, data)
    return data


def check_regular_file(name: str | os.PathLike) -> None:
    """InputError naming `name` when it is (or links to) something other than a regular file: a FIFO would block the
    read forever, a device such as /dev/zero never end it."""
    try:
        mode = os.stat(name).st_mode
    except OSError:
        return  # missing or unreadable: the reader words it
    if not stat.S_ISREG(mode):
        kind = "a folder" if stat.S_ISDIR(mode) else "a FIFO" if stat.S_ISFIFO(mode) else "a device or special file"
        raise InputError(f"{name}: {kind}, not a weights file")


def _why_unreadable(name: str, exc: Exception) -> str:
    """Why torch could not load the file `name`, in vinadv's words."""
    text = str(exc)
    if "Unsupported global" in text or "Unsupported class" in text or "GLOBAL" in text:
        return "it holds Python objects, not only tensors and plain values; building them would run code"
    if zipfile.is_zipfile(name):
        return "a zip archive, but not one torch wrote"
    with open(name, "rb") as fh:
        if fh.read(1) == b"\x80":  # a pickle's protocol opcode: pickled by Python, not saved by torch
            return "a Python pickle, not a file torch.save wrote; loading it would run code"
    return "damaged or another kind of file"


def weights_path_checksum(model: object) -> str | None:
    """The sha256 of the weights file a model was read from (its `weights_path`); None for a model made in memory."""
    path = getattr(model, "weights_path", None)
    return weights_checksum(path) if path is not None else None


def as_loaded(model, name: str, data: dict):
    """`model`, read from the weights file `name` (its contents `data`), in eval mode with the file's `record` and
    its `weights_path`; returned."""
    model.eval()
    model.record = data.get("record") or {}
    model.weights_path = name
    return model
