"""The training harness every trainer runs in (the VIN's and GPPN's imitation, `vinadv.planners.imitation`, and
Neural A*'s, `vinadv.planners.neural_astar.training`): the state of a run, its checkpoint (written atomically,
read back refused unless made by the same trainer with the same settings on the same data, restored into the model
and the optimiser), resume, the time limit, the progress bar, and the figures every training record carries
(hardware, the held-out split).

A trainer drives one `TrainingRun`:

    run = TrainingRun(kind, config, model, optimizer, State(), checkpoint=..., resume=..., data_sha256=...)
    for epoch in run.epochs():              # from the checkpoint's epoch on; stops at the time limit
        for i in run.progress(batches, epoch):
            ...                             # one step; `run.postfix(loss=...)`, `run.save()` where `run.due()`
        run.clock(epoch)                    # the epoch is done: `state.epoch`, `state.wall_s`
        run.close_epoch(entry, line)        # recorded, logged, checkpointed, the time limit checked

The checkpoint holds what `save_training_checkpoint` writes, then the state's fields, each under its own name: the
trainer's format string names them, and a field a checkpoint lacks reads as its default.
"""

from __future__ import annotations

import dataclasses
import os
import platform
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from tqdm import tqdm

from vinadv.errors import InputError
from vinadv.outfile import save_torch
from vinadv.planners.weights import torch_load

__all__ = [
    "CheckpointKind",
    "TrainingRun",
    "TrainingState",
    "hardware_info",
    "read_training_checkpoint",
    "restore_training",
    "save_training_checkpoint",
    "split_indices",
]


def split_indices(n: int, val_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Seeded shuffle of `range(n)`, then `(train, val)`: the last `round(n * val_fraction)` (>= 1 if > 0) held out."""
    order = np.random.default_rng([seed, 0x5EED]).permutation(n)
    n_val = 0 if val_fraction <= 0 else max(1, int(round(n * val_fraction)))
    if n - n_val < 1:
        raise InputError(f"{n} maps are too few for a validation fraction of {val_fraction}")
    return np.sort(order[: n - n_val]), np.sort(order[n - n_val :])


def hardware_info(device: torch.device) -> dict:
    """What a training record says of the machine: device, platform, processor, cores, torch threads and version."""
    info = {
        "device": str(device),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
        "torch_threads": torch.get_num_threads(),
        "torch": str(torch.__version__),
    }
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    info["cpu_model"] = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    if device.type == "cuda":
        info["gpu"] = torch.cuda.get_device_name(device)
    return info


def save_training_checkpoint(
    path: str | os.PathLike,
    checkpoint_format: str,
    model: torch.nn.Module,
    optimizer: torch.optim.Optimizer,
    config,
    data_sha256: str | None,
    **position,
) -> None:
    """Write a trainer's checkpoint (atomically: a run killed while writing keeps the last one): its format, the
    weights (on CPU), the optimiser, the settings (`config.to_dict()`), what identifies the training data, and the
    trainer's own `position` fields (epoch, records ...)."""
    save_torch(
        {
            "format": checkpoint_format,
            "model": {k: v.detach().cpu() for k, v in model.state_dict().items()},
            "optimizer": optimizer.state_dict(),
            "train_config": config.to_dict(),
            "data_sha256": data_sha256,
            **position,
        },
        path,
        mkdir=True,
    )


def read_training_checkpoint(
    path: str | os.PathLike,
    checkpoint_format: str,
    trainer: str,
    config: dict,
    same_on_resume: Iterable[str],
    defaults: dict | None = None,
) -> dict:
    """The checkpoint a run resumes from, refused (`InputError`) unless it is a `trainer` checkpoint of
    `checkpoint_format` made with the same `same_on_resume` settings as `config` (a `to_dict()`): resuming under
    other settings would silently mix two trainings. `defaults`: what a setting is in a checkpoint that lacks it."""
    ck = torch_load(path, "readable training checkpoint")
    if not isinstance(ck, dict) or ck.get("format") != checkpoint_format:
        raise InputError(f"{path}: not a {trainer} training checkpoint (expected format {checkpoint_format!r})")
    saved, defaults = dict(ck.get("train_config") or {}), defaults or {}
    for key in same_on_resume:
        if saved.get(key, defaults.get(key)) != config.get(key):
            raise InputError(
                f"{path}: checkpoint was made with {key}={saved.get(key)!r}, now {config.get(key)!r}; "
                "use the same options to resume, or remove the checkpoint"
            )
    return ck


def restore_training(
    path: str | os.PathLike, ck: dict, model: torch.nn.Module, optimizer: torch.optim.Optimizer
) -> None:
    """Load the weights and the optimiser of checkpoint `ck` (read from `path`) into `model` and `optimizer`;
    `InputError` when they do not fit."""
    try:
        model.load_state_dict(ck["model"])
        optimizer.load_state_dict(ck["optimizer"])
    except (RuntimeError, KeyError, ValueError) as exc:
        raise InputError(f"{path}: checkpoint does not match the model ({str(exc).splitlines()[0]})") from None


@dataclass(frozen=True)
class CheckpointKind:
    """What one trainer's checkpoints are.

    Attributes:
        format: the `format` entry (`vinadv.vin-checkpoint/1`: the VIN's and GPPN's; Neural A*'s own).
        trainer: the trainer's name in the refusal of another file.
        same_on_resume: the settings a resumed run must share with its checkpoint.
        defaults: what a setting is in a checkpoint that lacks it (None: absent).
    """

    format: str
    trainer: str
    same_on_resume: tuple[str, ...]
    defaults: dict | None = None


@dataclass
class TrainingState:
    """Where a run is: epochs done, wall time so far (over every resumed part), each epoch's record entry. A trainer
    with more to keep (its step, the best epoch ...) subclasses it with fields of its own: every field goes into the
    checkpoint under its name (an array as a tensor) and comes back from it."""

    epoch: int = 0
    wall_s: float = 0.0
    epochs: list = field(default_factory=list)

    def position(self) -> str:
        """Where a resumed run starts, for its first progress line."""
        return f"epoch {self.epoch}"

    def to_checkpoint(self) -> dict:
        """The fields, by name, as the checkpoint holds them (NumPy arrays as tensors)."""
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        return {k: torch.from_numpy(v) if isinstance(v, np.ndarray) else v for k, v in values.items()}

    @classmethod
    def from_checkpoint(cls, ck: dict, path: str | os.PathLike) -> TrainingState:
        """The state stored in checkpoint `ck` (read from `path`): a field it lacks is the field's default, a tensor
        comes back as a NumPy array, a list as a new list."""
        values: dict[str, Any] = {}
        for f in dataclasses.fields(cls):
            if f.name not in ck:
                continue
            value = ck[f.name]
            if isinstance(value, torch.Tensor):
                value = value.numpy()
            elif isinstance(value, list):
                value = list(value)
            values[f.name] = value
        missing = {"epoch", "wall_s", "epochs"} - set(values)
        if missing:
            raise InputError(f"{path}: not a training checkpoint (no {', '.join(sorted(missing))})")
        values["epoch"], values["wall_s"] = int(values["epoch"]), float(values["wall_s"])
        return cls(**values)


def load_checkpoint(
    path: str | os.PathLike,
    kind: CheckpointKind,
    config,
    model: torch.nn.Module,
    optimizer: torch.optim.Optimizer,
    state_type: type[TrainingState],
    data_sha256: str | None,
) -> TrainingState:
    """Resume from `path`: the checkpoint refused unless it is of `kind`, made with the same settings as `config`
    and on the same data (where both it and the run know their data's checksum: a checkpoint of a caller that gave
    none resumes), its weights and optimiser restored into `model` and `optimizer`, its state returned."""
    ck = read_training_checkpoint(path, kind.format, kind.trainer, config.to_dict(), kind.same_on_resume, kind.defaults)
    saved = ck.get("data_sha256")
    if None not in (saved, data_sha256) and saved != data_sha256:
        raise InputError(f"{path}: checkpoint was made on other maps (checksums differ); remove it to start over")
    restore_training(path, ck, model, optimizer)
    return state_type.from_checkpoint(ck, path)


class TrainingRun:
    """One run of a trainer in the harness (module doc).

    Args:
        kind: the trainer's checkpoints (`CheckpointKind`).
        config: the trainer's settings: `epochs`, `time_limit_min` (stop after the first epoch that ends past it;
            None: no limit) and `to_dict()`.
        model, optimizer: what the checkpoint saves and restores (the model's `state_dict`).
        state: the state of a fresh run (a `TrainingState`, the trainer's subclass).
        checkpoint: file written after every epoch (and at `save`); None: none.
        resume: continue from `checkpoint` where it exists (`load_checkpoint`).
        data_sha256: what identifies the training data, in the checkpoint and checked on resume.
        progress: a progress bar over each epoch's batches (tqdm, on standard error, gone when the epoch ends).
        log: called with one line per epoch, the resume and the stop (None: silent).
        every_min: a checkpoint also `due` this many minutes after the last (None: after epochs only).
    """

    def __init__(
        self,
        kind: CheckpointKind,
        config,
        model: torch.nn.Module,
        optimizer: torch.optim.Optimizer,
        state: TrainingState,
        *,
        checkpoint: str | os.PathLike | None = None,
        resume: bool = False,
        data_sha256: str | None = None,
        progress: bool = False,
        log: Callable[[str], None] | None = None,
        every_min: float | None = None,
    ) -> None:
        self.kind, self.config, self.model, self.optimizer = kind, config, model, optimizer
        self.checkpoint, self.data_sha256 = checkpoint, data_sha256
        self.show_progress, self.log, self.every_min = progress, log, every_min
        self.state = state
        #: why the run stopped before its last epoch (the time limit), None while it did not
        self.stopped: str | None = None
        self._bar = None
        self._started = self._last_save = time.time()
        if resume and checkpoint is not None and Path(checkpoint).exists():
            self.state = load_checkpoint(checkpoint, kind, config, model, optimizer, type(state), data_sha256)
            self.say(f"resumed from {checkpoint} after {self.state.position()}")

    def say(self, line: str) -> None:
        if self.log:
            self.log(line)

    def epochs(self) -> Iterator[int]:
        """The epochs (0-based) still to train: from the resumed state's on, until the last or the time limit. The
        wall clock starts here, on top of the time the checkpoint's runs took."""
        self._started = time.time() - self.state.wall_s
        self._last_save = time.time()
        for epoch in range(self.state.epoch, self.config.epochs):
            yield epoch
            if self.stopped:
                return

    def progress(self, batches: Iterable, epoch: int) -> Iterable:
        """`batches`, with a progress bar over them where the run shows progress."""
        if not self.show_progress:
            self._bar = None
            return batches
        self._bar = tqdm(batches, desc=f"epoch {epoch + 1}/{self.config.epochs}", unit="batch", leave=False)
        return self._bar

    def postfix(self, **figures: str) -> None:
        """Show `figures` (loss, learning rate ...) beside the progress bar, where there is one."""
        if self._bar is not None:
            self._bar.set_postfix(**figures)

    def elapsed(self) -> float:
        """Seconds of training so far, over every resumed part."""
        return time.time() - self._started

    def due(self) -> bool:
        """Whether a checkpoint inside an epoch is due (`every_min` since the last)."""
        return bool(
            self.checkpoint is not None and self.every_min and time.time() - self._last_save > 60 * self.every_min
        )

    def save(self) -> None:
        """Write the checkpoint of the state as it is (none without a checkpoint file)."""
        if self.checkpoint is None:
            return
        save_training_checkpoint(
            self.checkpoint,
            self.kind.format,
            self.model,
            self.optimizer,
            self.config,
            self.data_sha256,
            **self.state.to_checkpoint(),
        )
        self._last_save = time.time()

    def clock(self, epoch: int) -> float:
        """Epoch `epoch` (0-based) is done: the state says so, with the wall time so far (returned)."""
        self.state.epoch = epoch + 1
        self.state.wall_s = self.elapsed()
        return self.state.wall_s

    def close_epoch(self, entry: dict, line: str | None = None) -> None:
        """After `clock`: the epoch's record `entry` kept, its progress `line` logged, the checkpoint written, and the
        run stopped when it is past its time limit with epochs left."""
        self.state.epochs.append(entry)
        if line is not None:
            self.say(line)
        self.save()
        limit = self.config.time_limit_min
        if limit is not None and self.state.wall_s > 60 * limit and self.state.epoch < self.config.epochs:
            self.stopped = f"time limit of {limit} min reached after epoch {self.state.epoch}"
            self.say(self.stopped)
