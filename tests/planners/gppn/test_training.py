"""The GPPN's training entry (`vinadv.planners.gppn.training`) through the imitation loop: it learns, resumes,
refuses another planner's checkpoint; the CLI."""

import json

import numpy as np
import pytest
import torch

import vinadv.planners.imitation as imitation
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.planners.gppn import GPPN, GPPNConfig, load_gppn, save_gppn
from vinadv.planners.gppn.training import train_gppn
from vinadv.planners.harness import split_indices
from vinadv.planners.imitation import TrainConfig, evaluate_loss, optimal_action_bits
from vinadv.planners.vin.training import train_vin
from vinadv.planners.weights import weights_checksum

pytestmark = pytest.mark.slow


def test_a_short_training_lowers_the_loss_and_resumes(tmp_path):
    torch.set_num_threads(1)
    maps = generate_maps(48, 10, seed=3, n_starts=1)
    config = TrainConfig(planner="gppn", epochs=3, lr=0.01, batch_size=8, k=8, l_h=8, kernel=3, seed=1)
    ck = tmp_path / "g.ckpt"
    model, record = train_gppn(maps, config, checkpoint=ck, progress=False)
    losses = [e["train_loss"] for e in record["epochs"]]
    assert losses[-1] < losses[0]
    assert record["format"] == "vinadv.gppn-training-record/1" and record["model"]["f"] == 3
    # resuming a finished checkpoint with more epochs continues from epoch 3
    more = TrainConfig(**{**config.to_dict(), "epochs": 4})
    with pytest.raises(InputError, match="epochs=3"):  # epochs is part of the schedule: refused, as for the VIN
        train_gppn(maps, more, checkpoint=ck, resume=True, progress=False)
    again, rec2 = train_gppn(maps, config, checkpoint=ck, resume=True, progress=False)
    assert rec2["epochs_done"] == 3 and rec2["epochs"] == record["epochs"]
    for k, v in model.state_dict().items():
        torch.testing.assert_close(again.state_dict()[k], v)
    # a VIN training may not resume a GPPN checkpoint
    with pytest.raises(InputError, match="planner='gppn', now 'vin'"):
        train_vin(
            maps, TrainConfig(**{**config.to_dict(), "planner": "vin"}), checkpoint=ck, resume=True, progress=False
        )
    bits = optimal_action_bits(maps)
    _, val = split_indices(len(maps), config.val_fraction, config.seed)
    assert evaluate_loss(model, maps, bits, val, 8, torch.device("cpu"))["cells"] > 0


def test_init_may_change_the_iterations_but_not_the_weights_shapes(tmp_path):
    torch.set_num_threads(1)
    maps = generate_maps(16, 10, seed=3, n_starts=1)
    start = GPPN(GPPNConfig(k=6, l_h=8, f=3))
    save_gppn(start, tmp_path / "k6.pt")
    # k is a number of iterations, not a weight: a vanishing learning rate keeps the k = 6 weights at k = 9
    config = TrainConfig(planner="gppn", epochs=1, lr=1e-12, batch_size=8, k=9, l_h=8, kernel=3, seed=2)
    model, record = train_gppn(
        maps, TrainConfig(**{**config.to_dict(), "init": str(tmp_path / "k6.pt")}), progress=False
    )
    assert model.config.k == 9 and record["init_k"] == 6
    assert record["init_sha256"] == weights_checksum(tmp_path / "k6.pt")
    for key, value in start.state_dict().items():
        torch.testing.assert_close(model.state_dict()[key], value)
    for other in (GPPNConfig(k=6, l_h=12, f=3), GPPNConfig(k=9, l_h=8, f=5)):
        save_gppn(GPPN(other), tmp_path / "other.pt")
        with pytest.raises(InputError, match="^init .*other.pt"):
            train_gppn(maps, TrainConfig(**{**config.to_dict(), "init": str(tmp_path / "other.pt")}), progress=False)


def test_cli_train_eval_plan(tmp_path, capsys):
    data, weights = tmp_path / "train.npz", tmp_path / "g.pt"
    assert main(["maps", "generate", "--n", "24", "--size", "10", "--seed", "4", "--out", str(data), "--quiet"]) == 0
    assert (
        main(
            [
                "gppn",
                "train",
                "--data",
                str(data),
                "--out",
                str(weights),
                "--epochs",
                "2",
                "--batch-size",
                "8",
                "--k",
                "6",
                "--l-h",
                "6",
                "--kernel",
                "3",
                "--threads",
                "1",
                "--quiet",
            ]
        )
        == 0
    )
    record = json.loads((tmp_path / "g.json").read_text())
    assert record["planner"] == "gppn" and record["epochs_done"] == 2 and record["data"]["maps"] == 24
    model = load_gppn(weights)
    assert model.config.k == 6 and model.config.l_h == 6 and model.record["planner"] == "gppn"
    capsys.readouterr()  # the two commands' results
    assert main(["gppn", "eval", "--weights", str(weights), "--n", "5", "--size", "10", "--starts", "2", "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["rollouts"] == 10 and 0 <= metrics["success_rate"] <= 1
    assert metrics["planner"]["name"] == "gppn" and len(metrics["planner"]["weights_sha256"]) == 64
    assert (
        main(
            [
                "plan",
                "--maps",
                str(data),
                "--out",
                str(tmp_path / "p.npz"),
                "--planner",
                "gppn",
                "--weights",
                str(weights),
                "--json",
            ]
        )
        == 0
    )
    assert json.loads(capsys.readouterr().out)["paths"] == 24 * 7
    # another size than the weights': a clear error, exit 2
    assert main(["gppn", "eval", "--weights", str(weights), "--n", "2", "--size", "12", "--quiet"]) == 2
    assert "trained on 10x10 maps" in capsys.readouterr().err
    assert np.isfinite(metrics["action_accuracy"])


def test_a_run_killed_mid_epoch_resumes_to_the_same_weights(tmp_path, monkeypatch):
    torch.set_num_threads(1)
    maps = generate_maps(40, 8, seed=6, n_starts=1)
    config = TrainConfig(
        planner="gppn", epochs=2, lr=0.01, batch_size=8, k=4, l_h=4, kernel=3, seed=2, checkpoint_min=1e-9
    )  # a checkpoint after every batch
    whole, whole_rec = train_gppn(maps, config, checkpoint=tmp_path / "a.ckpt", progress=False)
    real, calls = imitation.batch_loss, []

    def dies_in_epoch_two(*args):
        calls.append(1)
        if len(calls) == 9:  # epoch 2, after its first two batches (5 per epoch, then one validation call)
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(imitation, "batch_loss", dies_in_epoch_two)
    with pytest.raises(KeyboardInterrupt):
        train_gppn(maps, config, checkpoint=tmp_path / "b.ckpt", progress=False)
    monkeypatch.setattr(imitation, "batch_loss", real)
    ck = torch.load(tmp_path / "b.ckpt", weights_only=True)
    assert ck["epoch"] == 1 and ck["step"] == 7
    resumed, rec = train_gppn(maps, config, checkpoint=tmp_path / "b.ckpt", resume=True, progress=False)
    for k, v in whole.state_dict().items():
        torch.testing.assert_close(resumed.state_dict()[k], v, rtol=0, atol=0)
    assert rec["steps"] == whole_rec["steps"] == 10
    assert rec["epochs"][1]["train_loss"] == pytest.approx(whole_rec["epochs"][1]["train_loss"], rel=1e-6)


def test_compiled_training_trains_the_same_weights(tmp_path):
    torch.set_num_threads(1)
    # compiling is the cost (each graph shape compiles a forward and a backward; 24 maps in batches of 8 and 7 plus
    # one validation map cost three compilations, 46 s): 9 maps are 8 for training, in two equal batches of 4 (one
    # training graph, 4 steps), and 1 for validation (the eval graph). The graph unrolls the k iterations, and its
    # compile time grows with them (cold cache: 37 s of CPU at k = 4, 23 s at k = 2): k = 2 still shares the
    # iteration's weights between two steps. Of the rest, a fifth was inductor probing the C++ compiler: it builds
    # and loads a test library for each vector ISA the CPU's flags name (six builds, 7 s of CPU of 33 on a cold
    # cache). `vec_isa_ok` takes the CPU's flags as they are, so the same vectorized kernels are compiled unprobed.
    maps = generate_maps(9, 8, seed=7, n_starts=1)
    config = TrainConfig(planner="gppn", epochs=2, lr=0.01, batch_size=4, k=2, l_h=4, kernel=3, seed=3)
    eager, eager_rec = train_gppn(maps, config, checkpoint=tmp_path / "e.ckpt", progress=False)
    assert (eager_rec["n_train"], eager_rec["n_val"], eager_rec["steps"]) == (8, 1, 4)
    compiled_config = TrainConfig(**{**config.to_dict(), "compile": True})
    from torch._inductor import config as inductor  # noqa: PLC0415 (torch.compile's backend: the training loads it)

    with inductor.patch({"cpp.vec_isa_ok": True}):
        compiled, rec = train_gppn(maps, compiled_config, checkpoint=tmp_path / "c.ckpt", progress=False)
    assert rec["train_config"]["compile"] is True and eager_rec["train_config"]["compile"] is False
    torch.manual_seed(config.seed)  # the trainer's initial weights
    initial = GPPN(GPPNConfig(k=config.k, l_h=config.l_h, f=config.kernel)).state_dict()
    for k, v in eager.state_dict().items():  # fused kernels round differently, nothing more
        assert not torch.equal(v, initial[k]), k  # every parameter was trained
        torch.testing.assert_close(compiled.state_dict()[k], v, rtol=1e-4, atol=1e-5)
    for a, b in zip(eager_rec["epochs"], rec["epochs"], strict=True):
        assert b["train_loss"] == pytest.approx(a["train_loss"], rel=1e-4)
        assert b["val_loss"] == pytest.approx(a["val_loss"], rel=1e-4)
    # the checkpoint holds the model's own keys (not the compiled wrapper's), so eager training resumes it
    assert set(torch.load(tmp_path / "c.ckpt", weights_only=True)["model"]) == set(eager.state_dict())
    resumed, _ = train_gppn(maps, config, checkpoint=tmp_path / "c.ckpt", resume=True, progress=False)
    for k, v in compiled.state_dict().items():
        torch.testing.assert_close(resumed.state_dict()[k], v, rtol=0, atol=0)


def test_compile_is_refused_for_the_vin():
    with pytest.raises(InputError, match="compile is for torch planners") as err:
        TrainConfig(planner="vin", compile=True).validate()
    assert err.value.parameters == ("compile",)
    TrainConfig(planner="gppn", compile=True).validate()


@pytest.mark.parametrize(
    "field,value,message",
    [
        ("l_h", 10**7, r"l_h must be in \[1, 2048\], got 10000000"),
        ("l_h", 0, r"l_h must be in \[1, 2048\], got 0"),
        ("l_q", 2049, r"l_q must be in \[1, 2048\], got 2049"),
        ("kernel", 65, r"kernel must be odd and in \[1, 63\], got 65"),
        ("kernel", 4, r"kernel must be odd and in \[1, 63\], got 4"),
    ],
)
def test_a_model_too_wide_to_build_is_refused_with_the_options(field, value, message):
    # checked with the training options, before any map is made or any weight allocated
    with pytest.raises(InputError, match=message) as err:
        TrainConfig(planner="gppn", **{field: value}).validate()
    assert err.value.parameters == (field,)
    TrainConfig(planner="gppn", l_h=2048, kernel=63).validate()
