"""The training harness (`vinadv.planners.harness`): the held-out split, a state's round trip through a checkpoint,
the refusals of another trainer's checkpoint, other settings and other maps, and the time limit. Tiny models, no
training: cheap. Whole trainings resumed to the uninterrupted weights: the trainers' tests."""

import numpy as np
import pytest
import torch

from vinadv.errors import InputError
from vinadv.planners.harness import CheckpointKind, TrainingRun, TrainingState, split_indices
from vinadv.planners.imitation import CHECKPOINT_KIND, ImitationState, TrainConfig
from vinadv.planners.neural_astar.training import NeuralAstarState, NeuralAstarTrainConfig


def test_split_is_disjoint_and_seeded():
    train, val = split_indices(100, 0.1, seed=3)
    assert len(val) == 10 and len(train) == 90 and not set(train) & set(val)
    assert set(train) | set(val) == set(range(100))
    np.testing.assert_array_equal(split_indices(100, 0.1, seed=3)[1], val)
    with pytest.raises(InputError):
        split_indices(1, 0.5, seed=0)


def _run(kind, config, state, checkpoint, **options):
    torch.manual_seed(0)
    model = torch.nn.Linear(3, 2)
    optimizer = torch.optim.RMSprop(model.parameters(), lr=0.1)
    return TrainingRun(kind, config, model, optimizer, state, checkpoint=checkpoint, **options)


def test_a_state_comes_back_from_its_checkpoint_as_it_was_written(tmp_path):
    ck = tmp_path / "run.ckpt"
    config = TrainConfig(epochs=3)
    run = _run(CHECKPOINT_KIND, config, ImitationState(), ck, data_sha256="a")
    state = run.state
    state.epoch, state.step, state.wall_s, state.epochs = 1, 7, 2.5, [{"epoch": 1}]
    state.added_obstacles, state.added_goals = np.ones((2, 4, 4), dtype=bool), np.zeros((2, 2), dtype=np.int64)
    state.augment_rounds = [{"epoch": 1, "added": 2}]
    run.save()
    stored = torch.load(ck, weights_only=True)
    assert stored["format"] == "vinadv.vin-checkpoint/1" and stored["data_sha256"] == "a"
    assert isinstance(stored["added_obstacles"], torch.Tensor) and stored["partial"] == [0.0, 0, 0]
    lines = []
    back = _run(CHECKPOINT_KIND, config, ImitationState(), ck, resume=True, data_sha256="a", log=lines.append)
    assert lines == [f"resumed from {ck} after epoch 1, step 7"]
    for name in ("epoch", "step", "wall_s", "epochs", "partial", "augment_rounds"):
        assert getattr(back.state, name) == getattr(state, name), name
    np.testing.assert_array_equal(back.state.added_obstacles, state.added_obstacles)
    np.testing.assert_array_equal(back.state.added_goals, state.added_goals)
    # a field the checkpoint lacks (older than it) reads as its default
    del stored["partial"], stored["augment_rounds"]
    old = ImitationState.from_checkpoint(stored, ck)
    assert old.partial == [0.0, 0, 0] and old.augment_rounds == []


def test_a_checkpoint_of_another_trainer_settings_or_maps_is_refused(tmp_path):
    ck = tmp_path / "run.ckpt"
    _run(CHECKPOINT_KIND, TrainConfig(epochs=3), ImitationState(), ck, data_sha256="a").save()
    neural_astar = CheckpointKind("vinadv.neural-astar-checkpoint/1", "Neural A*", ("lr",))
    with pytest.raises(InputError, match="not a Neural A\\* training checkpoint"):
        _run(neural_astar, NeuralAstarTrainConfig(), NeuralAstarState(), ck, resume=True)
    with pytest.raises(InputError, match="lr=0.005, now 0.01"):
        _run(CHECKPOINT_KIND, TrainConfig(epochs=3, lr=0.01), ImitationState(), ck, resume=True)
    with pytest.raises(InputError, match="other maps"):
        _run(CHECKPOINT_KIND, TrainConfig(epochs=3), ImitationState(), ck, resume=True, data_sha256="b")
    # where one side does not know its maps' checksum, the checkpoint resumes
    assert _run(CHECKPOINT_KIND, TrainConfig(epochs=3), ImitationState(), ck, resume=True).state.epoch == 0


@pytest.mark.parametrize("limit", [None, 1e-9])
def test_the_time_limit_stops_after_the_first_epoch_past_it_and_checkpoints_it(tmp_path, limit):
    ck = tmp_path / "run.ckpt"
    run = _run(CHECKPOINT_KIND, TrainConfig(epochs=3, time_limit_min=limit), ImitationState(), ck)
    done = []
    for epoch in run.epochs():
        run.clock(epoch)
        run.close_epoch({"epoch": epoch + 1})
        done.append(epoch)
    if limit is None:
        assert done == [0, 1, 2] and run.stopped is None
    else:
        assert done == [0] and run.stopped == f"time limit of {limit} min reached after epoch 1"
    assert torch.load(ck, weights_only=True)["epoch"] == len(done)
    assert isinstance(run.state, TrainingState)
