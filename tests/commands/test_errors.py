"""Library errors name parameters; the command line shows the flags instead."""

import pickle

from vinadv.cli import main
from vinadv.commands import cli_message, flag
from vinadv.errors import InputError


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
