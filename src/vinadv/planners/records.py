"""The dicts the planners hand to other modules and write as JSON, named: a planner's evaluation figures
(`PlannerMetrics`, from `vinadv.evaluation.planner_metrics`) and the record of a training (`TrainingRecord`, from
`vinadv.planners.imitation`, kept inside the weights file and beside it).

TypedDicts, so they stay plain dicts (`json.dumps` takes them as they are); the classes name the keys that other
modules read. Nothing here imports PyTorch.
"""

from __future__ import annotations

from typing import NotRequired, TypedDict

__all__ = [
    "DataRecord",
    "EpochRecord",
    "LengthBucketMetrics",
    "PlannerMetrics",
    "RolloutMetrics",
    "TrainingRecord",
]


class LengthBucketMetrics(TypedDict):
    """Rollouts whose optimal path has `moves[0]` to `moves[1]` moves (`evaluation.LENGTH_BUCKET` wide)."""

    moves: list[int]
    rollouts: int
    success_rate: float
    optimal_rate: float
    terminations: dict[str, int]


class RolloutMetrics(TypedDict):
    """Rollout figures (`evaluation.rollout_metrics`): rates are fractions in [0, 1] (NaN without rollouts), costs
    in path-cost units, `terminations` the count per reason (`vinadv.vocabulary.TERMINATIONS`); `by_length` only
    where the optimal move counts were given."""

    rollouts: int
    success_rate: float
    optimal_rate: float
    optimal_rate_of_reached: float
    mean_extra_cost: float
    mean_extra_cost_relative: float
    terminations: dict[str, int]
    by_length: NotRequired[list[LengthBucketMetrics]]


class PlannerMetrics(RolloutMetrics):
    """A planner's figures on a set of maps (`evaluation.evaluate_planner`, `evaluate_vin`): the maps (count, side,
    starts per map, seed, corner cutting), the action accuracy over `action_cells` supervised cells (None for a
    search planner, which has no policy), then the rollout figures."""

    maps: int
    size: int
    starts_per_map: int
    seed: int
    corner_cutting: bool
    action_accuracy: float | None
    action_cells: int


class EpochRecord(TypedDict):
    """One epoch of a training: losses and action accuracies (the validation ones None without held-out maps), the
    learning rate at its last step, its seconds and the seconds since the training started."""

    epoch: int
    train_loss: float
    train_action_accuracy: float
    val_loss: float | None
    val_action_accuracy: float | None
    lr_end: float
    epoch_s: float
    wall_s: float


class DataRecord(TypedDict):
    """The maps file a training read (the `train` commands), its movement model included (`moves`)."""

    path: str
    sha256: str
    maps: int
    size: int
    seed: int
    corner_cutting: bool
    moves: str


class TrainingRecord(TypedDict, total=False):
    """The record of a training, saved in the weights file (`record`) and as JSON beside it; `{}` for weights that
    came from elsewhere (a port's state dict).

    `training.train_model` writes `format` ... `optimizer` when it starts and `epochs` ... `stopped_early` (with
    `augment_rounds` and `added_maps` under adversarial training) when it ends; `train_vin` adds `value_iteration`,
    `--init` adds `init_sha256` (and `init_k`); the `train` commands add `record_version` (`vinadv.records.TRAINING`:
    readers take the record through `vinadv.records.upgrade`), `command`, `vinadv`, `started`, `data` and `finished`.
    """

    record_version: int
    format: str
    planner: str
    seed: int
    train_config: dict
    model: dict
    size: int
    n_maps: int
    n_train: int
    n_val: int
    corner_cutting: bool
    hardware: dict
    loss: str
    optimizer: str
    epochs: list[EpochRecord]
    epochs_done: int
    wall_time_s: float
    steps: int
    stopped_early: str | None
    augment_rounds: list[dict]
    added_maps: int
    value_iteration: str
    init_sha256: str
    init_k: int
    command: str
    vinadv: str
    started: str
    finished: str
    data: DataRecord
