"""The imitation loop of the whole-map planners (the VIN, the GPPN, any torch planner with the planner contract),
shared by their training entries (`vinadv.planners.vin.training.train_vin`,
`vinadv.planners.gppn.training.train_gppn`): on a maps file, every free cell of every map is a supervised state.

The policy depends only on the map, so one forward pass per map gives the logits of all its cells at once.
Dijkstra gives the set of optimal actions at every cell that can reach the goal; where several actions are
optimal any is right, so the loss is the negative log of the probability mass on the optimal set,
`-log sum_{a optimal} softmax(logits)_a`, averaged over the supervised cells (free, reachable, not the goal).

Optimiser: RMSprop (as the original VIN and the common PyTorch ports, eps 1e-6) with a cosine learning-rate
schedule, gradient-norm clipping (value iteration through max can spike the gradient). The last `val_fraction`
of the maps (after a seeded shuffle) is held out. The run is the training harness's (`vinadv.planners.harness`):
after each epoch, and every `checkpoint_min` minutes within one, a checkpoint (model, optimiser, position) is
written, so a killed or time-limited run resumes where it stopped.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace

import numpy as np
import torch

from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.grid.moves import DEFAULT_MOVES, MoveModel, move_model
from vinadv.grid.shortest_paths import optimal_actions, shortest_distances
from vinadv.planners.device import resolve_device
from vinadv.planners.gppn.model import MAX_KERNEL, MAX_WIDTH
from vinadv.planners.harness import CheckpointKind, TrainingRun, TrainingState, hardware_info, split_indices
from vinadv.planners.records import EpochRecord, TrainingRecord
from vinadv.planners.vin import value_iteration
from vinadv.planners.vin.model import VI_INITS, VIN, make_input
from vinadv.planners.weights import trained_moves, weights_checksum

CHECKPOINT_FORMAT = "vinadv.vin-checkpoint/1"
_BITS = 1 << np.arange(8, dtype=np.uint16)


@dataclass
class TrainConfig:
    """Training hyper-parameters. `lr` is the peak RMSprop rate, reached by a linear warm-up over `warmup_steps`
    optimizer steps, then decayed by a cosine to `lr * lr_final_fraction`. `planner` names the model trained
    ('vin' or 'gppn'); `k` and `l_h` are its iterations and width, `l_q` the VIN's q channels, `kernel` the GPPN's
    recurrent kernel."""

    epochs: int = 30
    lr: float = 0.005
    lr_final_fraction: float = 0.02
    batch_size: int = 32
    val_fraction: float = 0.05
    seed: int = 0
    device: str = "cpu"
    k: int | None = None
    l_h: int = 150
    l_q: int = 10
    clip_norm: float = 5.0
    time_limit_min: float | None = None
    init: str | None = None  # start from these weights (continued training) instead of a fresh initialisation
    # RMSprop's mean square starts at 0, so its first steps are ~10x lr: a warm-up keeps them from undoing
    # what an --init model already knows. None: 5% of all steps, at most 200.
    warmup_steps: int | None = None
    planner: str = "vin"
    kernel: int = 3
    # a checkpoint also every this many minutes inside an epoch (an epoch of a slow model can take an hour)
    checkpoint_min: float | None = 10.0
    # adversarial training's settings (`vinadv.hardening.AdversarialConfig.to_dict()`), None: plain training
    adversarial: dict | None = None
    # how a fresh VIN's value-iteration kernels start (`vin.VI_INITS`): 'default' (PyTorch's, the paper's VIN) or
    # 'shift' (`vin.init_shift_kernels`)
    vi_init: str = "default"
    # run the training forward and backward through `torch.compile` (a torch planner other than the VIN, whose CPU
    # value iteration is compiled by Numba already): the same function, fused kernels (docs/guide/planners.md)
    compile: bool = False

    def validate(self) -> None:
        if self.epochs < 1:
            raise InputError(f"epochs must be >= 1, got {self.epochs}", "epochs")
        if not self.lr > 0:
            raise InputError(f"lr must be > 0, got {self.lr}", "lr")
        if self.batch_size < 1:
            raise InputError(f"batch_size must be >= 1, got {self.batch_size}", "batch_size")
        if not 0 <= self.val_fraction < 1:
            raise InputError(f"val_fraction must be in [0, 1), got {self.val_fraction}", "val_fraction")
        if self.warmup_steps is not None and self.warmup_steps < 0:
            raise InputError(f"warmup_steps must be >= 0, got {self.warmup_steps}", "warmup_steps")
        if self.vi_init not in VI_INITS:
            raise InputError(f"vi_init must be one of {', '.join(VI_INITS)}, got {self.vi_init!r}", "vi_init")
        if self.vi_init != "default" and self.planner != "vin":
            raise InputError(f"vi_init {self.vi_init!r} is the VIN's, not the {self.planner}'s", "vi_init")
        if self.vi_init != "default" and self.init:
            raise InputError(
                f"vi_init {self.vi_init!r} starts a fresh VIN and init continues from weights: give one of them",
                "vi_init",
                "init",
            )
        for name in ("l_h", "l_q"):
            if not 1 <= getattr(self, name) <= MAX_WIDTH:
                raise InputError(f"{name} must be in [1, {MAX_WIDTH}], got {getattr(self, name)}", name)
        if not 1 <= self.kernel <= MAX_KERNEL or self.kernel % 2 == 0:
            raise InputError(f"kernel must be odd and in [1, {MAX_KERNEL}], got {self.kernel}", "kernel")
        if self.compile and self.planner == "vin":
            raise InputError(
                "compile is for torch planners such as the GPPN; the VIN's value iteration is compiled already",
                "compile",
            )

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class ImitationState(TrainingState):
    """The harness's state plus the imitation loop's: optimizer steps taken, the unfinished epoch's sums (a checkpoint
    inside an epoch), the maps `augment` added and what each call said."""

    step: int = 0
    partial: list = field(default_factory=lambda: [0.0, 0, 0])  # loss, cells, correct of the unfinished epoch
    added_obstacles: np.ndarray | None = None
    added_goals: np.ndarray | None = None
    augment_rounds: list = field(default_factory=list)

    def position(self) -> str:
        return f"epoch {self.epoch}, step {self.step}"


#: the VIN's and GPPN's checkpoints: the settings a resumed run must share with its checkpoint (a setting a
#: checkpoint lacks holds its default)
CHECKPOINT_KIND = CheckpointKind(
    CHECKPOINT_FORMAT,
    "vinadv",
    (
        "planner",
        "lr",
        "lr_final_fraction",
        "batch_size",
        "val_fraction",
        "seed",
        "k",
        "l_h",
        "l_q",
        "kernel",
        "epochs",
        "adversarial",
    ),
    TrainConfig().to_dict(),
)


def optimal_action_bits(maps: MapSet) -> np.ndarray:
    """Optimal actions of every cell of `maps` under their movement model, as a bit mask: see `action_bits`."""
    return action_bits(maps.obstacles, maps.goals, maps.corner_cutting, maps.moves)


def action_bits(
    obstacles: np.ndarray,
    goals: np.ndarray,
    corner_cutting: bool = True,
    moves: str | MoveModel = DEFAULT_MOVES,
) -> np.ndarray:
    """Optimal actions of every cell as a bit mask: `(n, N, N)` uint8, bit `a` set when action `a` is optimal under
    the movement model `moves` (`vinadv.grid.moves`: its costs; on `news` only bits 0..3, its actions), for
    obstacles `(n, N, N)` bool and goals `(n, 2)`.

    Zero at obstacles, the goal and cells that cannot reach the goal (they are not supervised).
    """
    out = np.zeros(obstacles.shape, dtype=np.uint8)
    for i in range(0, len(obstacles), 1024):  # bounds the (chunk, N, N, 8) temporaries
        obs, g = obstacles[i : i + 1024], goals[i : i + 1024]
        dist, _ = shortest_distances(obs, g, corner_cutting, moves)
        opt = optimal_actions(dist, obs, corner_cutting, moves)
        out[i : i + 1024] = (opt.astype(np.uint16) * _BITS).sum(axis=-1).astype(np.uint8)
    return out


#: `augment(model, epoch, train_idx)`, called before each epoch: None, or `(obstacles (m, N, N) bool, goals (m, 2),
#: info dict)` of maps to add to the training maps from then on (adversarial training, `vinadv.hardening`)
Augment = Callable[[torch.nn.Module, int, np.ndarray], "tuple[np.ndarray, np.ndarray, dict] | None"]


def bits_to_mask(bits: torch.Tensor, n_actions: int = 8) -> torch.Tensor:
    """`(...,)` uint8 bit masks -> `(..., n_actions)` bool."""
    shifts = torch.arange(n_actions, device=bits.device, dtype=torch.int32)
    return ((bits.to(torch.int32).unsqueeze(-1) >> shifts) & 1).bool()


def optimal_set_loss(logits: torch.Tensor, optimal: torch.Tensor) -> torch.Tensor:
    """Mean of `-log sum_{a in optimal} softmax(logits)_a` over rows: `(M, A)` logits, `(M, A)` bool, each row
    with at least one optimal action."""
    masked = logits.masked_fill(~optimal, float("-inf"))
    return (torch.logsumexp(logits, dim=-1) - torch.logsumexp(masked, dim=-1)).mean()


def cell_logits(model: torch.nn.Module, obstacles: np.ndarray, goals: np.ndarray, device: torch.device):
    """`(B, N, N, A)` logits of every cell, with gradients. A `VIN` runs its own input and (on CPU) the compiled
    value iteration; any other module follows the planner contract `forward(obstacles (B, N, N) float 0/1,
    goals (B, 2) int64) -> (B, A, N, N)`."""
    if isinstance(model, VIN):
        x = make_input(obstacles, goals).to(device)
        if device.type == "cpu":  # the compiled value-iteration loop: same function, several times faster on CPU
            return model.fc(value_iteration.q_values(model, x).permute(0, 2, 3, 1))
        return model.action_logits(x)
    obs = torch.from_numpy(np.asarray(obstacles, dtype=np.float32)).to(device)
    return model(obs, torch.from_numpy(np.asarray(goals, dtype=np.int64)).to(device)).permute(0, 2, 3, 1)


def batch_loss(
    model: torch.nn.Module, obstacles: np.ndarray, goals: np.ndarray, bits: np.ndarray, device: torch.device
):
    """Loss, number of supervised cells and number whose argmax is optimal, for one batch of maps."""
    logits = cell_logits(model, obstacles, goals, device)
    mask = bits_to_mask(torch.from_numpy(bits).to(device), logits.shape[-1])
    supervised = mask.any(dim=-1)
    logits, mask = logits[supervised], mask[supervised]
    loss = optimal_set_loss(logits, mask)
    correct = mask.gather(1, logits.argmax(dim=-1, keepdim=True)).sum()
    return loss, int(supervised.sum()), int(correct)


def evaluate_loss(
    model: torch.nn.Module, maps: MapSet, bits: np.ndarray, idx: np.ndarray, batch_size: int, device: torch.device
) -> dict:
    """Loss and action accuracy over the maps `idx` (cell-weighted), without gradients."""
    total_loss, cells, correct = 0.0, 0, 0
    model.eval()
    with torch.no_grad():
        for i in range(0, len(idx), batch_size):
            b = idx[i : i + batch_size]
            loss, n, c = batch_loss(model, maps.obstacles[b], maps.goals[b], bits[b], device)
            total_loss += loss.item() * n
            cells += n
            correct += c
    return {"loss": total_loss / max(cells, 1), "action_accuracy": correct / max(cells, 1), "cells": cells}


def start_from(
    model: torch.nn.Module, start: torch.nn.Module, path, record: TrainingRecord | None, moves: str = DEFAULT_MOVES
) -> TrainingRecord:
    """Load `start`'s weights (read from `path`, `--init`) into `model`; the record gains their checksum (and
    their k where it differs: the iterations are not weights, so training may go on with more or fewer; and the
    movement model they were trained on where it is not `moves`, the maps': an octile model may start a moore one,
    the same 8 actions with other costs, while a news model's 4 actions do not fit 8 and are refused by the
    config check)."""
    if replace(start.config, k=model.config.k) != model.config:
        raise InputError(
            f"init {path}: its {type(start).__name__} ({start.config}) is not the one to train ({model.config})", "init"
        )
    model.load_state_dict(start.state_dict())
    rec: TrainingRecord = {**(record or {}), "init_sha256": weights_checksum(path)}
    if start.config.k != model.config.k:
        rec["init_k"] = start.config.k
    start_moves = trained_moves(path, getattr(start, "record", {}))
    if start_moves != moves:
        rec["init_moves"] = start_moves
    return rec


def train_model(
    model: torch.nn.Module,
    maps: MapSet,
    config: TrainConfig,
    model_config: dict,
    checkpoint: str | os.PathLike | None = None,
    resume: bool = False,
    progress: bool = True,
    record: TrainingRecord | None = None,
    log: Callable[[str], None] | None = None,
    augment: Augment | None = None,
) -> tuple[torch.nn.Module, TrainingRecord]:
    """Train `model` (a `VIN`, or any module with the planner contract, see `cell_logits`) on `maps`; returns it
    (CPU, eval mode) and the training record (`TrainingRecord`).

    With `augment` (see `Augment`), the maps it returns before an epoch join the training maps, with their own
    Dijkstra supervision, for that epoch and the rest: an epoch keeps its number of steps (so the learning-rate
    schedule does not change) and draws its batches from the training maps and the added ones together. The added
    maps are kept in the checkpoint and every call's `info` in the record (`augment_rounds`).

    Args:
        maps: the training maps (their starts and expert paths are not needed: every cell is supervised).
        config: hyper-parameters (`TrainConfig`); `config.planner` names the model in the record and checkpoint.
        model_config: the model's hyper-parameters, for the record.
        checkpoint: file written after every epoch; with `resume`, training continues from it.
        record: extra entries for the record (command, data checksum...), kept as given.
        log: called with one line per epoch (None: silent).
    """
    config.validate()
    n_actions = move_model(maps.moves).n_actions
    if getattr(getattr(model, "config", None), "n_actions", n_actions) != n_actions:
        raise InputError(
            f"the model has {model.config.n_actions} actions; the maps use {maps.moves!r} moves, which have {n_actions}"
        )
    device = resolve_device(config.device)
    size = maps.size
    model = model.to(device)
    optimizer = torch.optim.RMSprop(model.parameters(), lr=config.lr, eps=1e-6)
    train_idx, val_idx = split_indices(len(maps), config.val_fraction, config.seed)
    steps_per_epoch = math.ceil(len(train_idx) / config.batch_size)
    total_steps = steps_per_epoch * config.epochs
    rec: TrainingRecord = dict(record or {})
    rec.update(
        format=f"vinadv.{config.planner}-training-record/1",
        planner=config.planner,
        seed=config.seed,
        train_config=config.to_dict(),
        model=model_config,
        size=size,
        n_maps=len(maps),
        n_train=len(train_idx),
        n_val=len(val_idx),
        corner_cutting=bool(maps.corner_cutting),
        # the supervision's movement model: the planners that load the weights plan it (`trained_moves`)
        moves=maps.moves,
        hardware=hardware_info(device),
        loss="-log sum_{a optimal} softmax(logits)_a, mean over free reachable non-goal cells",
        optimizer="RMSprop(eps=1e-6), cosine lr schedule per step, grad-norm clipping",
    )
    run = TrainingRun(
        CHECKPOINT_KIND,
        config,
        model,
        optimizer,
        ImitationState(),
        checkpoint=checkpoint,
        resume=resume,
        data_sha256=rec.get("data", {}).get("sha256"),
        progress=progress,
        log=log,
        every_min=config.checkpoint_min,
    )
    state: ImitationState = run.state
    # `forward` computes the logits; `model` keeps the parameters (the compiled wrapper shares them) and is saved
    forward = torch.compile(model) if config.compile else model
    bits = optimal_action_bits(maps)
    obstacles, goals = maps.obstacles, maps.goals
    if state.added_obstacles is not None and len(state.added_obstacles):  # resumed with added maps
        obstacles = np.concatenate([maps.obstacles, state.added_obstacles])
        goals = np.concatenate([maps.goals, state.added_goals])
        added = action_bits(state.added_obstacles, state.added_goals, maps.corner_cutting, maps.moves)
        bits = np.concatenate([bits, added])
    for epoch in run.epochs():
        done = state.step - epoch * steps_per_epoch  # batches of this epoch done before a mid-epoch checkpoint
        if augment is not None and not done and len(state.augment_rounds) <= epoch:
            found = augment(model, epoch, train_idx)
            new_obs, new_goals, info = found if found is not None else (None, None, {})
            if new_obs is not None and len(new_obs):
                state.added_obstacles = (
                    new_obs if state.added_obstacles is None else np.concatenate([state.added_obstacles, new_obs])
                )
                state.added_goals = (
                    new_goals if state.added_goals is None else np.concatenate([state.added_goals, new_goals])
                )
                obstacles = np.concatenate([obstacles, new_obs])
                goals = np.concatenate([goals, new_goals])
                bits = np.concatenate([bits, action_bits(new_obs, new_goals, maps.corner_cutting, maps.moves)])
            state.augment_rounds.append(
                {
                    "epoch": epoch + 1,
                    "added": 0 if new_obs is None else len(new_obs),
                    "added_total": len(obstacles) - len(maps),
                    **info,
                }
            )
            run.say(f"epoch {epoch + 1}: {state.augment_rounds[-1]}")
        model.train()
        pool = np.concatenate([train_idx, np.arange(len(maps), len(obstacles))])
        order = pool[np.random.default_rng([config.seed, epoch]).permutation(len(pool))][: len(train_idx)]
        loss_sum, cell_sum, correct_sum = state.partial if done else (0.0, 0, 0)
        epoch_start = time.time()
        for i in run.progress(range(done * config.batch_size, len(order), config.batch_size), epoch):
            b = order[i : i + config.batch_size]
            lr = _lr_at(state.step, total_steps, config)
            for group in optimizer.param_groups:
                group["lr"] = lr
            loss, n, c = batch_loss(forward, obstacles[b], goals[b], bits[b], device)
            optimizer.zero_grad(set_to_none=True)
            loss.backward()
            grad_norm = torch.nn.utils.clip_grad_norm_(model.parameters(), config.clip_norm)
            if torch.isfinite(grad_norm):  # skip the rare non-finite step instead of poisoning the weights
                optimizer.step()
            state.step += 1
            loss_sum += loss.item() * n
            cell_sum += n
            correct_sum += c
            run.postfix(loss=f"{loss_sum / max(cell_sum, 1):.4f}", lr=f"{lr:.2g}")
            if run.due():
                state.partial, state.wall_s = [loss_sum, cell_sum, correct_sum], run.elapsed()
                run.save()
        state.partial = [0.0, 0, 0]
        val = evaluate_loss(forward, maps, bits, val_idx, config.batch_size, device) if len(val_idx) else {}
        wall_s = run.clock(epoch)
        entry: EpochRecord = {
            "epoch": epoch + 1,
            "train_loss": loss_sum / max(cell_sum, 1),
            "train_action_accuracy": correct_sum / max(cell_sum, 1),
            "val_loss": val.get("loss"),
            "val_action_accuracy": val.get("action_accuracy"),
            "lr_end": _lr_at(state.step - 1, total_steps, config),
            "epoch_s": round(time.time() - epoch_start, 2),
            "wall_s": round(wall_s, 2),
        }
        run.close_epoch(
            entry,
            f"epoch {entry['epoch']}/{config.epochs}: train loss {entry['train_loss']:.4f} "
            f"acc {entry['train_action_accuracy']:.4f}"
            + (f", val loss {entry['val_loss']:.4f} acc {entry['val_action_accuracy']:.4f}" if val else "")
            + f" ({entry['epoch_s']:.0f} s)",
        )
    rec.update(
        epochs=state.epochs,
        epochs_done=state.epoch,
        wall_time_s=round(state.wall_s, 1),
        steps=state.step,
        stopped_early=run.stopped,
    )
    if augment is not None:
        rec.update(augment_rounds=state.augment_rounds, added_maps=len(obstacles) - len(maps))
    model = model.to("cpu").eval()
    return model, rec


def _lr_at(step: int, total: int, config: TrainConfig) -> float:
    f = config.lr_final_fraction
    warmup_steps = min(200, math.ceil(0.05 * total)) if config.warmup_steps is None else config.warmup_steps
    warmup = min(1.0, (step + 1) / warmup_steps) if warmup_steps else 1.0
    return warmup * config.lr * (f + (1 - f) * 0.5 * (1 + math.cos(math.pi * min(step, total) / max(total, 1))))
