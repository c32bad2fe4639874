"""`--device` on every command that plans (plan, attack, run, identify, robustness, eval): with `--device cpu` a torch
planner (a GPPN, a bring-your-own file) gives the default's results, and the VIN its exact engine's (the oracle: its
PyTorch forward is another computation); the record names the device type; a device the machine lacks is one line,
exit status 2, before anything is written."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

from tests.cli_files import command_line, generated_maps_file
from tests.planner_files import write_gppn
from vinadv.attacks.pairs import PairSet
from vinadv.cli import main
from vinadv.identify import PLANNER_SPEC
from vinadv.planners.pathset import PathSet
from vinadv.store import Store

SIZE = 10
EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "my_planner.py"


@pytest.fixture(scope="module")
def gppn_file(tmp_path_factory):
    return write_gppn(tmp_path_factory.mktemp("g") / "gppn.pt", SIZE, seed=5)


@pytest.fixture(scope="module")
def maps_file(tmp_path_factory):
    return generated_maps_file(tmp_path_factory.mktemp("m"), 8, SIZE, seed=9, n_starts=2)


@pytest.fixture
def planner(request, gppn_file, planning_weights):
    """The planner options of a parametrised planner: `gppn` (a small GPPN file), `file` (the shipped example of a
    bring-your-own planner), `vin` (a VIN file: engine by default, its PyTorch forward with --device)."""
    return {
        "gppn": ["--planner", "gppn", "--weights", gppn_file],
        "file": ["--planner", f"{EXAMPLE}:make"],
        "vin": ["--weights", planning_weights(SIZE)],
    }[request.param]


def _json(capsys) -> dict:
    return json.loads(capsys.readouterr().out)


def _both(argv: list[str], capsys, out: dict[str, Path] | None = None) -> tuple[dict, dict]:
    """Run `argv` as it is and with `--device cpu` (each `{name}` in it formatted from `out`, the second time with a
    `.cpu` suffix): the two JSON summaries."""
    got = []
    for suffix, extra in (("", []), (".cpu", ["--device", "cpu"])):
        paths = {k: f"{v}{suffix}" for k, v in (out or {}).items()}
        assert main([*(a.format(**paths) for a in argv), *extra, "--json", "--quiet"]) == 0
        got.append(_json(capsys))
    return got[0], got[1]


def _same_record(default: dict, on_cpu: dict) -> None:
    assert "device" not in default and on_cpu == {**default, "device": "cpu"}


@pytest.mark.slow
@pytest.mark.parametrize("planner", ["gppn", "file", "vin"], indirect=True)
def test_plan_and_attack_on_the_cpu_give_the_defaults_paths_and_pairs(planner, maps_file, tmp_path, capsys):
    paths = tmp_path / "paths.npz"
    a, b = _both(["plan", "--maps", maps_file, "--out", "{paths}", *planner], capsys, {"paths": paths})
    _same_record(a["planner"], b["planner"])
    one, two = PathSet.load(f"{paths}"), PathSet.load(f"{paths}.cpu")
    assert len(one.paths) == 16 and one.paths == two.paths and np.array_equal(one.termination, two.termination)

    pairs = tmp_path / "pairs.npz"
    argv = ["attack", "--maps", maps_file, "--strategy", "saliency", "--budget", "4", "--out", "{pairs}", *planner]
    a, b = _both(argv, capsys, {"pairs": pairs})
    _same_record(a["planner"], b["planner"])
    assert a["counts"] == b["counts"] and a["pairs"] > 0
    one, two = PairSet.load(f"{pairs}"), PairSet.load(f"{pairs}.cpu")
    assert np.array_equal(one.added, two.added) and np.array_equal(one.obstacles_a, two.obstacles_a)
    assert one.path_a == two.path_a and one.path_o == two.path_o
    assert two.params["planner"]["device"] == "cpu"


@pytest.mark.slow
@pytest.mark.parametrize("planner", ["gppn", "file"], indirect=True)
def test_run_identify_robustness_and_eval_on_the_cpu_give_the_defaults_figures(planner, maps_file, tmp_path, capsys):
    db = tmp_path / "r.db"
    run = [*command_line("run", n=8, size=SIZE, shard_size=4, attack="key-points", budget=4), "--db", "{db}"]
    a, b = _both([*run, *planner], capsys, {"db": db})
    _same_record(a["planner"], b["planner"])
    assert a["counts"] == b["counts"] and a["pairs"] > 0
    stored = []
    for path, run_id in ((f"{db}", a["run_id"]), (f"{db}.cpu", b["run_id"])):
        with Store.open(path, readonly=True) as store:
            stored.append((store.read_pairs(run_id), store.run_info(run_id)["config"]))
    (one, config_one), (two, config_two) = stored
    assert one.path_a == two.path_a and one.path_o == two.path_o and np.array_equal(one.label, two.label)
    assert config_two[PLANNER_SPEC]["device"] == "cpu" and "device" not in config_one[PLANNER_SPEC]
    assert "device" not in config_two  # not a setting of the run: it may be resumed on another device

    pairs = tmp_path / "pairs.npz"
    attack = command_line("attack", maps=maps_file, strategy="random", out=pairs, per_map=3, planner="optimal")
    assert main([*attack, "--quiet"]) == 0
    capsys.readouterr()
    ident_db = tmp_path / "i.db"
    a, b = _both(["identify", "--pairs", str(pairs), "--db", "{db}", *planner], capsys, {"db": ident_db})
    assert a["counts"] == b["counts"]
    with Store.open(f"{ident_db}", readonly=True) as s1, Store.open(f"{ident_db}.cpu", readonly=True) as s2:
        one, two = s1.read_pairs(a["run_id"]), s2.read_pairs(b["run_id"])
        assert s2.run_info(b["run_id"])["config"][PLANNER_SPEC]["device"] == "cpu"
    assert one.path_a == two.path_a and one.path_o == two.path_o

    bench = [*command_line("robustness", n=6, size=SIZE, strategies="key-points,saliency", max_obstacles=2)]
    a, b = _both([*bench, *planner], capsys)
    _same_record(a["planner"], b["planner"])
    assert a["clean"] == b["clean"] and a["overall"] == b["overall"]
    assert [s["by_obstacles"] for s in a["strategies"].values()] == [
        s["by_obstacles"] for s in b["strategies"].values()
    ]

    a, b = _both(["eval", "--data", maps_file, *planner], capsys)
    _same_record(a["planner"], b["planner"])
    assert a["vinadv"] == b["vinadv"] and a["gppn"] == b["gppn"]


@pytest.mark.parametrize(
    "argv",
    [
        ["plan", "--maps", "{maps}", "--out", "{tmp}/out.npz"],
        ["attack", "--maps", "{maps}", "--strategy", "random", "--out", "{tmp}/out.npz"],
        ["run", "--n", "4", "--size", "10", "--db", "{tmp}/out.db"],
        ["identify", "--pairs", "{tmp}/none.npz", "--planner", "gppn", "--db", "{tmp}/out.db"],
        ["robustness", "--n", "4", "--size", "10", "--db", "{tmp}/out.db", "--report", "{tmp}/out"],
        ["eval", "--data", "{maps}", "--out", "{tmp}/out.json"],
    ],
    ids=["plan", "attack", "run", "identify", "robustness", "eval"],
)
def test_a_device_the_machine_lacks_is_one_line_and_nothing_is_written(argv, maps_file, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    for device in ("cuda", "cuda:1", "gpu"):
        args = [a.format(maps=maps_file, tmp=tmp_path) for a in argv]
        assert main([*args, "--planner", "gppn", "--device", device]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and f"--device '{device}'" in err and "Traceback" not in err, err
        assert not any(p.name.startswith("out") for p in tmp_path.iterdir())


def test_identify_refuses_a_device_without_a_planner(tmp_path, capsys):
    argv = ["identify", "--pairs", str(tmp_path / "p.npz"), "--db", str(tmp_path / "x.db")]
    assert main([*argv, "--device", "cpu"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--device: only with --planner or --weights" in err, err
    assert not (tmp_path / "x.db").exists()


def test_auto_runs_where_it_can_and_the_record_says_where(maps_file, tmp_path, capsys):
    out = tmp_path / "p.npz"
    argv = ["plan", "--maps", maps_file, "--out", str(out), "--json"]
    assert main([*argv, "--planner", f"{EXAMPLE}:make", "--device", "auto"]) == 0
    assert _json(capsys)["planner"]["device"] == ("cuda" if torch.cuda.is_available() else "cpu")
    # `optimal` has no forward: a device changes nothing for it, and nothing is recorded
    assert main([*argv, "--planner", "optimal", "--device", "auto"]) == 0
    assert "device" not in _json(capsys)["planner"]
