"""Fuzzing the command line itself (issue 37): for every command the parser has (`serve` aside: it starts a server),
option values drawn by hypothesis from each option's type and choices (in range and out of it, empty, huge,
negative, NaN, unicode, junk), with files among the values (valid files of every kind, a missing file, a folder,
a file in a missing folder), run in process. Every call ends in exit status 0 or 2, never a traceback.

The work after the checks is stubbed out (`WORK`): each function a command calls once its options passed is
replaced by one that stops the command (`WorkReached`, counted as status 0), so a huge `--n` costs nothing and the
fuzz is about what the commands accept, not about training or attacking. Seeded (`derandomize`), a fixed number
of examples per command; in the slow tier (about a minute on the 2-core machine)."""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import os
import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.fault_files import write_classifier, write_database, write_maps, write_pairs, write_paths, write_weights
from vinadv.cli import SHIPPED_WEIGHTS_DIR, build_parser, main

pytestmark = [pytest.mark.slow, pytest.mark.filterwarnings("ignore::UserWarning")]


class WorkReached(BaseException):  # noqa: N818 - not an error: the command reached its (stubbed) work
    """A command got through its checks to its work; a BaseException, so no `except Exception` of vinadv's takes
    it for a failure of the work."""


#: the work each command starts once its options passed, `module:attribute` (a function, or a class's method)
WORK = (
    "vinadv.grid.generator:_generate_chunk",  # maps generate, robustness's maps, training maps
    "vinadv.planners.vin.training:train_vin",
    "vinadv.planners.gppn.training:train_gppn",
    "vinadv.evaluation.protocols:evaluate_protocol",
    "vinadv.evaluation.protocols:gppn_protocol",
    "vinadv.evaluation.planner_metrics:evaluate_planner",
    "vinadv.attacks.strategies:Attack.attack",
    "vinadv.classify.train_eval:train_classifier",
    "vinadv.pipeline:compute_shard",
    "vinadv.identify:identify_pairs",
    "vinadv.robustness:robustness",
    "vinadv.evaluation.job:evaluate_run",
    "vinadv.evaluation.job:evaluate_planner_quality",
    "vinadv.evaluation.job:evaluate_timing",
    "vinadv.report.build:gather_report",  # the figures and tables of the report
    "vinadv.cluster:start_local_cluster",  # --workers: no Dask cluster is started
    "vinadv.cluster:_check_reachable",  # --cluster: no scheduler is dialled
)

#: commands left aside: `serve` runs a web server until stopped
LEFT_ASIDE = {("serve",)}

EDGE_INTS = [0, 1, -1, 2, 3, 7, 8, 9, 16, 28, 255, 256, 2**31, 2**53 + 1, 2**63 - 1, 2**63, 2**64, 2**70, -(2**70)]
EDGE_FLOATS = ["nan", "inf", "-inf", "-0.0", "1e308", "1e-320", "0.5", "-0.5", "1.5", "0", "1", "100"]
ODD_TEXT = ["", " ", "-", "--", "x", "é", "\N{GRINNING FACE}", "a\tb", "1,2", ",", "0x10", "1e3", "٣", "²", "null"]
#: file names the values draw from, relative to the folder each example runs in (a copy of `FILES`)
FILE_NAMES = [
    "maps.npz",
    "paths.npz",
    "pairs.npz",
    "weights.pt",
    "gppn.pt",
    "model.joblib",
    "vinadv.db",
    "absent.npz",
    "absent.db",
    ".",
    "folder",
    "missing/out.npz",
    "out.npz",
    "out.png",
    "out.pt",
    "out.csv",
    "out",
    "sqlite://",
    "mysql+pymysql://root@127.0.0.1:1/x",
    "postgresql://[::1",
]


def _commands(parser: argparse.ArgumentParser, words: tuple[str, ...] = ()) -> list[tuple[tuple[str, ...], object]]:
    """Every command of `parser`: (its words, its parser), subcommands followed down."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            found = []
            for name, sub in action.choices.items():
                found += _commands(sub, (*words, name))
            return found
    return [(words, parser)]


COMMANDS = [(words, sub) for words, sub in _commands(build_parser()) if words not in LEFT_ASIDE]


def _odd_text(values) -> st.SearchStrategy[str]:
    return st.one_of(
        st.sampled_from(values),
        st.sampled_from(ODD_TEXT),
        st.text(max_size=8),
        st.sampled_from(["x" * 300, "9" * 400, "é" * 5000]),
    )


#: words a text option may plausibly be given besides files: planners, classifiers, strategies, run names, lists
WORDS = ["rule", "svm", "cnn", "vin", "gppn", "optimal", "random", "1", "fuzz", "harmful", "svm,cnn", "0.5,1"]


def _value(action: argparse.Action, odd: bool) -> st.SearchStrategy[str]:
    """Values for one option: plausible ones (its choices, small numbers of its type, files), or with `odd` numbers
    at and past every edge, NaN and infinities, and odd text of any kind."""
    if action.choices is not None:
        choices = [str(c) for c in action.choices]
        return _odd_text(choices) if odd else st.sampled_from(choices)
    if action.type is int:
        if not odd:
            return st.integers(0, 12).map(str)
        return st.one_of(st.integers(-3, 40).map(str), st.sampled_from([str(v) for v in EDGE_INTS]), _odd_text(["1"]))
    if action.type is float:
        if not odd:
            return st.sampled_from(["0", "0.1", "0.5", "1", "2"])
        numbers = st.floats(-1e6, 1e6, allow_nan=False).map(repr)
        return st.one_of(numbers, st.sampled_from(EDGE_FLOATS), _odd_text(["0.1"]))
    return _odd_text(FILE_NAMES + WORDS) if odd else st.sampled_from(FILE_NAMES + WORDS)


@st.composite
def _argv(draw, words: tuple[str, ...], parser: argparse.ArgumentParser) -> list[str]:
    """A command line of `parser`: each option present or not (required ones always), in a drawn order, with a
    drawn value, plausible but for a few odd ones; positionals in place."""
    actions = [a for a in parser._actions if not isinstance(a, argparse._HelpAction) and a.dest != "func"]
    odd = draw(st.sets(st.sampled_from(range(len(actions))), max_size=2))
    options: list[list[str]] = []
    positionals: list[str] = []
    for i, action in enumerate(actions):
        value = _value(action, i in odd)
        if not action.option_strings:
            positionals.append(draw(value))
            continue
        if not action.required and not draw(st.booleans()):
            continue
        flag = draw(st.sampled_from(action.option_strings))
        if action.nargs == 0:
            options.append([flag])
        else:
            count = {None: 1, "?": draw(st.integers(0, 1)), "+": draw(st.integers(1, 2)), "*": draw(st.integers(0, 2))}
            count = action.nargs if isinstance(action.nargs, int) else count[action.nargs]
            options.append([flag, *(draw(value) for _ in range(count))])
    options = draw(st.permutations(options))
    return [*words, *(word for option in options for word in option), *positionals]


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> Path:
    """One valid file of each kind the commands read (as `FILE_NAMES` names them), a folder, and nothing else."""
    folder = tmp_path_factory.mktemp("fuzz-files")
    write_maps(folder / "maps.npz")
    write_paths(folder / "paths.npz")
    write_pairs(folder / "pairs.npz")
    write_weights(folder / "weights.pt")
    shutil.copy(SHIPPED_WEIGHTS_DIR / "gppn28.pt", folder / "gppn.pt")  # a GPPN (the shipped one, 28x28)
    write_classifier(folder / "model.joblib")
    write_database(folder / "vinadv.db")
    (folder / "folder").mkdir()
    return folder


@pytest.fixture
def stubbed_work(monkeypatch):
    """Every function of `WORK` stops the command that reaches it."""

    def reached(*args, **kwargs):
        raise WorkReached()

    for target in WORK:
        module, attribute = target.split(":")
        owner = importlib.import_module(module)
        *path, name = attribute.split(".")
        for part in path:
            owner = getattr(owner, part)
        assert callable(getattr(owner, name)), target  # a renamed function fails here, not silently
        monkeypatch.setattr(owner, name, reached)
    monkeypatch.delenv("VINADV_DB", raising=False)


def outcome(argv: list[str], folder: Path) -> tuple[int, str]:
    """Run `argv` in `folder`: its exit status (0 where it reached its stubbed work) and what it wrote to stderr.
    Anything but a status or `WorkReached` escapes: the test fails on it with the traceback."""
    err = io.StringIO()
    here = os.getcwd()
    os.chdir(folder)
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except WorkReached:
                code = 0
            except SystemExit as exc:  # argparse's own refusals (status 2)
                code = exc.code
    finally:
        os.chdir(here)
    return code, err.getvalue()


FUZZ = settings(
    max_examples=25,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow, HealthCheck.data_too_large],
)


@pytest.mark.parametrize("words,parser", COMMANDS, ids=[" ".join(w) for w, _ in COMMANDS])
def test_every_command_exits_0_or_2(words, parser, files, stubbed_work, tmp_path):
    runs = iter(range(10**6))

    @FUZZ
    @given(argv=_argv(words, parser))
    def check(argv):
        folder = tmp_path / str(next(runs))
        shutil.copytree(files, folder)  # an example may overwrite a file: the next one gets fresh ones
        code, err = outcome(argv, folder)
        assert code in (0, 2), (argv, code, err[-2000:])
        assert "Traceback" not in err, (argv, err[-2000:])
        if code == 2:  # vinadv's one line ("vinadv: error: ..."), or argparse's usage and its error line
            assert ": error: " in err.strip().split("\n")[-1], (argv, err[-2000:])
        shutil.rmtree(folder)

    check()


def test_the_fuzz_covers_every_command_but_serve():
    names = {" ".join(words) for words, _ in COMMANDS}
    assert "serve" not in names and {"run", "maps generate", "export", "gppn train", "report"} <= names
    assert len(names) == len(_commands(build_parser())) - len(LEFT_ASIDE)
