"""`--json` and `--quiet` (`vinadv.commands.output`): one meaning in every command, and the result always printed."""

import argparse
import json

import pytest

from tests.cli_files import generated_maps_file
from vinadv.cli import build_parser, main
from vinadv.commands.output import (
    QUIET_HELP,
    add_output_options,
    emit,
    note,
    progress_bar,
    progress_lines,
    shows_progress,
)
from vinadv.grid import generate_maps


def parse(*argv: str, json_: str | None = "the summary", quiet: bool = True) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_output_options(parser, json=json_, quiet=quiet)
    return parser.parse_args(argv)


def test_the_options_are_added_as_asked():
    assert vars(parse()) == {"json": False, "quiet": False}
    assert vars(parse("--json", "--quiet")) == {"json": True, "quiet": True}
    assert vars(parse(json_=None)) == {"quiet": False}
    assert vars(parse(quiet=False)) == {"json": False}
    with pytest.raises(SystemExit):
        parse("--quiet", quiet=False)


@pytest.mark.parametrize("argv", [(), ("--quiet",)], ids=["plain", "quiet"])
def test_the_result_prints_as_text_quiet_or_not(argv, capsys):
    args = parse(*argv)
    assert emit(args, {"n": 3}, "three maps") == 0
    assert emit(args, {"n": 3}, lambda: print("three\nmaps")) == 0
    assert capsys.readouterr().out == "three maps\nthree\nmaps\n"


@pytest.mark.parametrize("argv", [("--json",), ("--json", "--quiet")], ids=["json", "json quiet"])
def test_the_result_prints_as_one_json_line_with_json(argv, capsys):
    args = parse(*argv)
    assert emit(args, {"n": 3, "out": "m.npz"}, lambda: print("text")) == 0
    assert emit(args, {"when": object}, "text", json_default=lambda value: "a class") == 0
    first, second = capsys.readouterr().out.splitlines()
    assert json.loads(first) == {"n": 3, "out": "m.npz"} and json.loads(second) == {"when": "a class"}


def test_a_command_without_the_options_prints_its_result_as_text(capsys):
    assert emit(argparse.Namespace(), {"n": 3}, "three maps") == 0
    assert capsys.readouterr().out == "three maps\n"
    assert shows_progress(argparse.Namespace())


def test_progress_shows_unless_quiet_or_json(capsys):
    assert shows_progress(parse())
    for argv in (("--quiet",), ("--json",), ("--json", "--quiet")):
        args = parse(*argv)
        assert not shows_progress(args) and progress_lines(args) is None
        with progress_bar(args, total=2) as bar:
            assert bar.disable
    log = progress_lines(parse())
    log("epoch 1")
    assert capsys.readouterr().out == "epoch 1\n"
    with progress_bar(parse(), total=2, hidden=True) as bar:
        assert bar.disable  # the command's own reason
    with progress_bar(parse(), total=2) as bar:
        assert not bar.disable


def test_notes_go_to_stderr_and_quiet_hides_them(capsys):
    note(parse(), "created indexes")
    note(parse("--json"), "a warning")
    assert capsys.readouterr() == ("", "created indexes\na warning\n")
    note(parse("--quiet"), "created indexes")
    assert capsys.readouterr() == ("", "")


def subcommands(parser: argparse.ArgumentParser, words: tuple[str, ...] = ()):
    """(words, parser) of every command and subcommand of `parser`."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*words, name), sub
                yield from subcommands(sub, (*words, name))


def test_every_command_says_the_same_of_quiet_and_json():
    seen = {"--quiet": 0, "--json": 0}
    for words, parser in subcommands(build_parser()):
        for action in parser._actions:
            if "--quiet" in action.option_strings:
                assert action.help == QUIET_HELP, words
                seen["--quiet"] += 1
            if "--json" in action.option_strings:
                assert action.help.startswith("print ") and action.help.endswith(" as JSON"), words
                seen["--json"] += 1
    assert seen["--quiet"] >= 15 and seen["--json"] >= 18


def test_help_of_quiet_says_the_result_still_prints(capsys):
    with pytest.raises(SystemExit):
        main(["attack", "--help"])
    assert "the result and errors still print" in " ".join(capsys.readouterr().out.split())


SIZE = 10


@pytest.fixture(scope="module")
def maps_file(tmp_path_factory):
    return generated_maps_file(tmp_path_factory.mktemp("m"), 6, SIZE, seed=2)


def test_attack_quiet_prints_its_summary_without_a_progress_bar(maps_file, tmp_path, capsys):
    line = ["attack", "--maps", maps_file, "--strategy", "exhaustive", "--planner", "optimal"]
    assert main([*line, "--out", str(tmp_path / "a.npz"), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert main([*line, "--out", str(tmp_path / "b.npz"), "--quiet"]) == 0
    quiet = capsys.readouterr()
    assert quiet.err == ""  # no progress bar
    assert quiet.out.startswith(f"exhaustive on planner optimal: {summary['pairs']} pairs from 6 maps")
    assert "attack success rate" in quiet.out and "planner calls" in quiet.out


def test_eval_quiet_prints_its_figures_without_a_progress_bar(maps_file, tmp_path, capsys):
    line = ["eval", "--planner", "optimal", "--data", maps_file, "--out", str(tmp_path / "f.json")]
    assert main([*line, "--quiet"]) == 0
    quiet = capsys.readouterr()
    assert quiet.err == ""
    assert quiet.out.startswith(f"planner optimal: 6 maps of {SIZE}x{SIZE}")
    assert "rollout success 100.00%" in quiet.out and "%Suc" in quiet.out
    assert json.loads((tmp_path / "f.json").read_text())["vinadv"]["success_rate"] == 1.0


#: a bring-your-own planner that prints to standard output while it is made and while it plans
PRINTING = """
import torch


class Chatty(torch.nn.Module):
    def forward(self, obstacles, goals):
        print("planning", obstacles.shape[0], "maps")
        return torch.zeros(obstacles.shape[0], 8, obstacles.shape[1], obstacles.shape[2])


def make(size):
    print("made for", size)
    return Chatty()
"""


def test_a_planner_that_prints_does_not_break_json(tmp_path, capsys):
    generate_maps(2, 8, seed=1, n_starts=1).save(tmp_path / "m.npz")
    (tmp_path / "chatty.py").write_text(PRINTING)
    argv = ["plan", "--maps", str(tmp_path / "m.npz"), "--out", str(tmp_path / "p.npz")]
    assert main([*argv, "--planner", f"{tmp_path / 'chatty.py'}:make", "--json"]) == 0
    out, err = capsys.readouterr()
    assert len(out.splitlines()) == 1 and json.loads(out)["paths"] == 2
    assert "made for 8" in err and "planning" in err
    # without --json the planner's prints stay where it printed them
    assert main([*argv, "--planner", f"{tmp_path / 'chatty.py'}:make", "--quiet"]) == 0
    assert "made for 8" in capsys.readouterr().out
