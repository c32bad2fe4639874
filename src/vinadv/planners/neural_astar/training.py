"""Training Neural A* as its authors do (omron-sinicx/neural-astar, branch minimal: `utils/training.py`'s
`PlannerModule`, `scripts/train.py` and `train.yaml`), on vinadv maps files.

- Loss: the L1 distance between the differentiable search's history (the cells it closed, straight-through: 1/0
  in value, the softmax's gradient) and the optimal path map of the same start, `mean |H - P|` over the batch's
  B x N x N cells. The optimal path map is 1 on the expert path's cells except the goal (the authors' `opt_traj`
  follows the optimal policy from the start and stops before the goal); vinadv takes the maps file's expert path
  (one optimal path: on the MP files the authors' policy may choose another among equally short ones).
- The search in training: the encoder in train mode (batch norms on the batch's statistics), Tmax 0.25 (at most a
  quarter of the cells selected), g_ratio 0.5, and the authors' batched loop's gradient
  (`differentiable_astar(..., solved_gradients=True)`).
- RMSprop (PyTorch's defaults but the learning rate, 0.001), batch 100, 50 epochs, seed 1234: train.yaml's.
- Each epoch: the training maps in a seeded shuffle (seed, epoch), one start per map (one of its starts drawn with
  the same seed: the authors draw a fresh start per map each epoch; a file imported with one start per map gives
  the same start each epoch), then the validation figures of the authors' `validation_step`, on the validation
  maps' first starts, with the model in eval mode (running statistics, Tmax 1): per batch of `batch_size` rows,
  p_opt (the share of paths as long as vanilla A*'s), p_exp (the mean of max(0, (E_A* - E) / E_A*)) and
  h_mean = 2 / (1 / (p_opt + 1e-10) + 1 / (p_exp + 1e-10)); the epoch's figures are the batches' means weighted by
  their rows (what Lightning logs on epoch end). vinadv plans these with the exact mode
  (`NeuralAstarPlanner.plan`), which gives the differentiable search's paths and expansions except on float32
  ties (`vinadv neural-astar compare-modes`).
- Model selection: the epoch of the highest validation h_mean (the authors' `ModelCheckpoint(monitor=
  "metrics/h_mean", mode="max")`; the first on ties), whose weights are returned.
- The run is the training harness's (`vinadv.planners.harness`): a checkpoint after every epoch (model, optimiser,
  best weights, figures); a killed or time-limited run resumed with the same settings ends with the same weights as
  one not interrupted (the shuffles and starts are seeded by epoch, and nothing else in training draws random
  numbers).
"""

from __future__ import annotations

import copy
import math
import os
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np
import torch

from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.grid.paths import path_costs
from vinadv.planners.classical.astar import AStarPlanner
from vinadv.planners.device import resolve_device
from vinadv.planners.harness import CheckpointKind, TrainingRun, TrainingState, hardware_info
from vinadv.planners.neural_astar.differentiable import differentiable_astar
from vinadv.planners.neural_astar.model import NeuralAstar, NeuralAstarConfig
from vinadv.planners.neural_astar.planner import MOVES, NeuralAstarPlanner

__all__ = [
    "CHECKPOINT_FORMAT",
    "CHECKPOINT_KIND",
    "RECORD_FORMAT",
    "NeuralAstarState",
    "NeuralAstarTrainConfig",
    "history_loss",
    "optimal_path_maps",
    "train_neural_astar",
    "validation_figures",
]

CHECKPOINT_FORMAT = "vinadv.neural-astar-checkpoint/1"
RECORD_FORMAT = "vinadv.neural-astar-training-record/1"
LOSS = "mean |history - optimal path map (goal excluded)| over the batch's cells (the authors' nn.L1Loss)"
OPTIMIZER = "RMSprop (PyTorch defaults but lr), constant learning rate (the authors' configure_optimizers)"


@dataclass(frozen=True)
class NeuralAstarTrainConfig:
    """The training's settings; the defaults are the authors' train.yaml (and their NeuralAstar defaults).

    Attributes:
        epochs: passes over the training maps (50).
        lr: RMSprop learning rate (0.001).
        batch_size: maps per step, and rows per validation batch (100).
        tmax: the share of cells the search may select in training (0.25).
        seed: initialisation, shuffles and starts (1234).
        depth: encoder blocks 1..4 (4).
        g_ratio: f = g_ratio * g + (1 - g_ratio) * h (0.5).
        device: torch device name (cpu, cuda, cuda:N, auto).
        time_limit_min: stop after the first epoch that ends past this many minutes (None: no limit).
    """

    epochs: int = 50
    lr: float = 0.001
    batch_size: int = 100
    tmax: float = 0.25
    seed: int = 1234
    depth: int = 4
    g_ratio: float = 0.5
    device: str = "cpu"
    time_limit_min: float | None = None

    def validate(self) -> None:
        for name, value in (("epochs", self.epochs), ("batch_size", self.batch_size)):
            if value < 1:
                raise InputError(f"{name} must be >= 1, got {value}", name)
        if not (self.lr > 0 and math.isfinite(self.lr)):
            raise InputError(f"lr must be a positive number, got {self.lr}", "lr")
        if not 0 < self.tmax <= 1:
            raise InputError(f"tmax must be in (0, 1], got {self.tmax}", "tmax")
        if self.seed < 0:
            raise InputError(f"seed must be >= 0, got {self.seed}", "seed")
        if self.time_limit_min is not None and not self.time_limit_min > 0:
            raise InputError(f"time_limit must be > 0 minutes, got {self.time_limit_min}", "time_limit")
        NeuralAstarConfig(depth=self.depth, g_ratio=self.g_ratio).validate()

    def to_dict(self) -> dict:
        return asdict(self)


def check_training_maps(maps: MapSet, name: str) -> None:
    """Refuse (InputError naming `name`) maps Neural A* cannot train on: another movement model than `moore`, maps
    that forbid corner cutting (the authors' neighbour filter opens any free neighbour)."""
    if maps.moves != MOVES:
        raise InputError(f"{name}: maps of movement model {maps.moves!r}; Neural A* searches {MOVES!r} moves")
    if not maps.corner_cutting:
        raise InputError(f"{name}: maps forbid corner cutting; Neural A*'s search cuts corners (moore maps)")


def optimal_path_maps(maps: MapSet, rows: np.ndarray) -> np.ndarray:
    """`(len(rows), N, N)` float32: 1 on the cells of the expert path of each row (a flat index `map * S + start`)
    except its goal, 0 elsewhere (the authors' `opt_traj`)."""
    rows = np.asarray(rows, dtype=np.int64)
    paths = maps.expert.take(rows)
    n = maps.size
    out = np.zeros((len(rows), n, n), dtype=np.float32)
    owners = paths.owners()
    out[owners, paths.cells[:, 0], paths.cells[:, 1]] = 1.0
    goals = maps.goals[rows // maps.n_starts]
    out[np.arange(len(rows)), goals[:, 0], goals[:, 1]] = 0.0
    return out


def history_loss(histories: torch.Tensor, targets: torch.Tensor) -> torch.Tensor:
    """The authors' loss: `mean |histories - targets|` over every cell of the batch (`(B, N, N)` each)."""
    return (histories - targets).abs().mean()


def validation_figures(
    model: NeuralAstar, maps: MapSet, batch_size: int, device: torch.device, astar_expansions: np.ndarray | None = None
) -> dict:
    """p_opt, p_exp, h_mean of `model` (eval mode, exact search) on the first start of every map of `maps`, as the
    authors' `validation_step` logs them over an epoch (module doc), and `rows`."""
    n = len(maps)
    rows = np.arange(n) * maps.n_starts
    starts, goals = maps.starts[:, 0], maps.goals
    planner = NeuralAstarPlanner(model, maps.size, device=device, batch_size=batch_size)
    model.eval()
    result = planner.plan(maps.obstacles, starts, goals, True, MOVES)
    if astar_expansions is None:
        astar_expansions = AStarPlanner(maps.size, MOVES).plan(maps.obstacles, starts, goals, True, MOVES).expansions
    costs = path_costs(result.paths, MOVES)
    optimal = result.reached & (np.abs(costs - maps.expert_costs.reshape(-1)[rows]) <= 1e-6)
    reference = np.asarray(astar_expansions, dtype=np.float64)
    saved = np.maximum((reference - result.expansions) / reference, 0.0)
    sums = {"p_opt": 0.0, "p_exp": 0.0, "h_mean": 0.0}
    for i in range(0, n, batch_size):
        sl = slice(i, i + batch_size)
        p_opt, p_exp = float(optimal[sl].mean()), float(saved[sl].mean())
        weight = len(optimal[sl])
        sums["p_opt"] += p_opt * weight
        sums["p_exp"] += p_exp * weight
        # the authors' harmonic mean with their 1e-10 guard (`vinadv.evaluation.search_metrics.harmonic_mean`)
        sums["h_mean"] += 2.0 / (1.0 / (p_opt + 1e-10) + 1.0 / (p_exp + 1e-10)) * weight
    return {"rows": n, **{k: v / max(n, 1) for k, v in sums.items()}}


def _epoch_rows(maps: MapSet, seed: int, epoch: int) -> np.ndarray:
    """This epoch's rows: the maps in a seeded shuffle, each with one of its real starts drawn with the same seed."""
    rng = np.random.default_rng([seed, epoch, 0x4E41])
    order = rng.permutation(len(maps))
    counts = maps.start_mask.sum(axis=1)[order]
    slot = np.floor(rng.random(len(maps)) * counts).astype(np.int64)
    return order * maps.n_starts + slot


@dataclass
class NeuralAstarState(TrainingState):
    """The harness's state plus the best epoch so far: its record entry (`epoch`, `val_h_mean` ...) and weights."""

    best: dict | None = None
    best_state: dict | None = None


#: Neural A*'s checkpoints: the settings a resumed run must share with them (the epoch count and time limit may
#: change)
CHECKPOINT_KIND = CheckpointKind(
    CHECKPOINT_FORMAT, "Neural A*", ("lr", "batch_size", "tmax", "seed", "depth", "g_ratio")
)


def train_neural_astar(
    train_maps: MapSet,
    val_maps: MapSet,
    config: NeuralAstarTrainConfig,
    checkpoint: str | os.PathLike | None = None,
    resume: bool = False,
    progress: bool = False,
    record: dict | None = None,
    log: Callable[[str], None] | None = None,
    data_sha256: str | None = None,
) -> tuple[NeuralAstar, dict]:
    """Train Neural A* (module doc) on `train_maps`, select by h_mean on `val_maps`.

    Args:
        train_maps, val_maps: moore maps with corner cutting, of one size.
        config: the settings (`NeuralAstarTrainConfig`).
        checkpoint: file written after every epoch; with `resume`, training continues from it.
        progress: a progress bar over each epoch's batches.
        record: fields the training record starts with (the command's: data, command line ...).
        log: called with one line per epoch (None: silent).
        data_sha256: what identifies the maps trained on; a checkpoint of other maps is refused on resume.

    Returns:
        The model of the best validation epoch (CPU, eval mode) and the training record.
    """
    config.validate()
    check_training_maps(train_maps, "training maps")
    check_training_maps(val_maps, "validation maps")
    if val_maps.size != train_maps.size:
        raise InputError(f"validation maps are {val_maps.size}x{val_maps.size}, training maps {train_maps.size}")
    if len(val_maps) < 1 or len(train_maps) < 1:
        raise InputError(f"training needs maps: {len(train_maps)} to train on, {len(val_maps)} to validate on")
    device = resolve_device(config.device)
    torch.manual_seed(config.seed)
    model = NeuralAstar(NeuralAstarConfig(depth=config.depth, g_ratio=config.g_ratio)).to(device)
    optimizer = torch.optim.RMSprop(model.parameters(), lr=config.lr)
    # the checkpoint keeps the encoder's weights (the search has none)
    run = TrainingRun(
        CHECKPOINT_KIND,
        config,
        model.encoder,
        optimizer,
        NeuralAstarState(),
        checkpoint=checkpoint,
        resume=resume,
        data_sha256=data_sha256,
        progress=progress,
        log=log,
    )
    state: NeuralAstarState = run.state
    val_starts = val_maps.starts[:, 0]
    val_astar = AStarPlanner(val_maps.size, MOVES).plan(val_maps.obstacles, val_starts, val_maps.goals, True, MOVES)
    obstacles = torch.from_numpy(train_maps.obstacles.astype(np.float32))
    for epoch in run.epochs():
        t0 = time.time()
        rows = _epoch_rows(train_maps, config.seed, epoch)
        model.train()
        loss_sum = 0.0
        for i in run.progress(range(0, len(rows), config.batch_size), epoch):
            batch = rows[i : i + config.batch_size]
            index = batch // train_maps.n_starts
            obs = obstacles[index].to(device)
            starts = torch.from_numpy(train_maps.starts.reshape(-1, 2)[batch]).to(device)
            goals = torch.from_numpy(train_maps.goals[index]).to(device)
            targets = torch.from_numpy(optimal_path_maps(train_maps, batch)).to(device)
            cost = model(obs, starts, goals)
            search = differentiable_astar(
                cost, 1.0 - obs, starts, goals, config.g_ratio, config.tmax, solved_gradients=True
            )
            loss = history_loss(search.histories, targets)
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            loss_sum += loss.item() * len(batch)
            run.postfix(loss=f"{loss.item():.4f}")
        figures = validation_figures(model, val_maps, config.batch_size, device, val_astar.expansions)
        wall_s = run.clock(epoch)
        entry = {
            "epoch": epoch + 1,
            "train_loss": loss_sum / len(rows),
            "val_p_opt": figures["p_opt"],
            "val_p_exp": figures["p_exp"],
            "val_h_mean": figures["h_mean"],
            "epoch_s": round(time.time() - t0, 2),
            "wall_s": round(wall_s, 2),
        }
        if state.best is None or figures["h_mean"] > state.best["val_h_mean"]:
            state.best = dict(entry)
            state.best_state = {k: v.detach().cpu().clone() for k, v in model.encoder.state_dict().items()}
        run.close_epoch(
            entry,
            f"epoch {epoch + 1}/{config.epochs}: loss {entry['train_loss']:.5f}, val Opt {figures['p_opt']:.3f} "
            f"Exp {figures['p_exp']:.3f} Hmean {figures['h_mean']:.3f} ({entry['epoch_s']:.0f} s)"
            + (" best" if state.best["epoch"] == epoch + 1 else ""),
        )
    best = copy.deepcopy(model).cpu()
    if state.best_state is not None:
        best.encoder.load_state_dict(state.best_state)
    best.eval()
    rec = {
        **(record or {}),
        "format": RECORD_FORMAT,
        "planner": "neural-astar",
        "train_config": config.to_dict(),
        "model": best.config.to_dict(),
        "size": train_maps.size,
        "n_train": len(train_maps),
        "n_val": len(val_maps),
        "moves": MOVES,
        "corner_cutting": True,
        "hardware": hardware_info(device),
        "loss": LOSS,
        "optimizer": OPTIMIZER,
        "selection": "the epoch of the highest validation h_mean (first on ties)",
        "epochs": state.epochs,
        "epochs_done": state.epoch,
        "best_epoch": None if state.best is None else state.best["epoch"],
        "best": state.best,
        "wall_time_s": round(state.wall_s, 1),
        "stopped_early": run.stopped,
    }
    return best, rec
