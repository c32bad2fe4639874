"""Library errors name parameters; the command line shows the flags instead."""

import importlib
import os
import pickle

from vinadv.cli import main
from vinadv.commands import cli_message, flag
from vinadv.errors import InputError
from vinadv.grid import generate_maps


def test_flags_of_parameters():
    assert [flag(p) for p in ("n", "shard_size", "per_map", "n_starts", "run_id")] == [
        "--n",
        "--shard-size",
        "--per-map",
        "--starts",
        "--run",
    ]


def test_cli_message_replaces_the_first_mention_of_each_parameter():
    exc = InputError("resume needs name (the run to resume); name a run", "resume", "name")
    assert cli_message(exc) == "--resume needs --name (the run to resume); name a run"
    # whole words only: 'n' inside 'n_starts' or 'run' is left alone
    assert cli_message(InputError("could not run: n must be >= 1", "n")) == "could not run: --n must be >= 1"
    assert cli_message(InputError("a plain message")) == "a plain message"


def test_parameters_survive_pickling():
    # errors raised on Dask workers come back pickled
    back = pickle.loads(pickle.dumps(InputError("n must be >= 1", "n")))
    assert back.parameters == ("n",) and str(back) == "n must be >= 1"


def test_commands_show_flags(tmp_path, capsys):
    assert main(["run", "--n", "0", "--db", str(tmp_path / "x.db"), "--quiet"]) == 2
    assert "vinadv: error: --n must be >= 1, got 0" in capsys.readouterr().err
    assert main(["run", "--n", "5", "--resume", "--db", str(tmp_path / "x.db"), "--quiet"]) == 2
    assert "vinadv: error: --resume needs --name (the run to resume)" in capsys.readouterr().err
    assert (
        main(["identify", "--pairs", str(tmp_path / "none.npz"), "--db", str(tmp_path / "x.db"), "--workers", "0"]) == 2
    )
    err = capsys.readouterr().err
    assert "vinadv: error:" in err and "Traceback" not in err


def test_cli_message_leaves_a_parameter_inside_a_path_alone():
    exc = InputError("/tmp/data/a_032.npz: no such file (suite s reads it from data)", "data")
    assert cli_message(exc) == "/tmp/data/a_032.npz: no such file (suite s reads it from --data)"
    exc = InputError("data/a.npz and data.npz and C:\\\\data\\\\x: no such file in data.", "data")
    assert cli_message(exc) == "data/a.npz and data.npz and C:\\\\data\\\\x: no such file in --data."


def test_bench_run_names_the_missing_file_of_data_as_it_is(tmp_path, monkeypatch, capsys):
    (tmp_path / "data").mkdir()
    monkeypatch.chdir(tmp_path)
    assert main(["bench", "run", "--suite", "mpd32-quick-v1", "--planner", "optimal", "--data", "data", "--quiet"]) == 2
    line = capsys.readouterr().err
    assert line.startswith("vinadv: error: data/") and "no such file" in line and line.rstrip().endswith("--data)")


def test_bench_leaderboard_names_its_source_argument(tmp_path, capsys):
    assert main(["bench", "leaderboard", str(tmp_path / "nonexist"), "--out", str(tmp_path / "lb")]) == 2
    line = capsys.readouterr().err
    assert "--sources" not in line and f"SOURCE {tmp_path / 'nonexist'}: no such folder or file" in line
    assert not (tmp_path / "lb").exists()


def test_workers_past_four_per_core_are_refused_before_any_process_starts(tmp_path, capsys, monkeypatch):
    """`--workers 100000` started a LocalCluster that then ignored Ctrl-C: more than 4 per core is refused, one
    line naming the flag and pointing to --cluster (checked before Dask is imported or a process spawned)."""

    def no_cluster(*args, **kwargs):
        raise AssertionError("a local cluster was started")

    try:
        distributed = importlib.import_module("distributed")
    except ImportError:
        pass
    else:
        monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    generate_maps(2, 10, seed=1, n_starts=1).save(tmp_path / "m.npz")
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    line = ["attack", "--maps", str(tmp_path / "m.npz"), "--strategy", "random", "--planner", "optimal"]
    line += ["--out", str(tmp_path / "p.npz")]
    assert main([*line, "--workers", "100000", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "--workers 100000: at most 4 local worker processes per core, 8 on this machine's 2 cores" in err
    assert "(--cluster tcp://HOST:PORT)" in err and err.count("\n") == 1 and not (tmp_path / "p.npz").exists()
    assert main([*line, "--workers", "9", "--quiet"]) == 2
    assert "--workers 9: at most 4" in capsys.readouterr().err
