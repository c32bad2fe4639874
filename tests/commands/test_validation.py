"""Options are checked before the first write: a refused value exits 2 with one line naming it, and nothing is stored
(no run row, no database file, no output file). Issue 37's cases: options `run` used to check only once a run row
existed, seeds out of range, run names that could not be found again, the in-memory and the empty database, a URL
that is no URL, and sets of no maps."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest
import sqlalchemy as sa

import vinadv.cli
from vinadv.cli import build_parser, main
from vinadv.grid import generate_maps
from vinadv.grid.mapset import MAPS_FORMAT
from vinadv.npzfile import save_npz
from vinadv.seeds import SEED_LIMIT

#: a run small and quick enough to be the control of every refusal below
RUN = ["run", "--n", "2", "--size", "8", "--planner", "optimal", "--shard-size", "2", "--quiet"]


def stored_runs(url: str) -> int | None:
    """The rows of the `runs` table at `url`: None when there is no database file (SQLite) or no `runs` table."""
    parsed = sa.make_url(url)
    if parsed.get_backend_name() == "sqlite" and not Path(parsed.database).exists():
        return None
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    try:
        with engine.connect() as conn:
            if "runs" not in sa.inspect(conn).get_table_names():
                return None
            return conn.execute(sa.text("SELECT count(*) FROM runs")).scalar_one()
    finally:
        engine.dispose()


def error_line(capsys) -> str:
    """The one line the command printed to stderr (asserted to be one, and an error)."""
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vinadv: error: "), err
    return lines[0]


REFUSED_RUN_OPTIONS = [
    (["--per-map", "-1"], "--per-map must be >= 0, got -1"),
    (["--radius", "-1"], "--radius must be >= 0, got -1"),
    (["--budget", "0"], "--budget must be >= 1, got 0"),  # near-path does not use it, but the run records it
    (["--attack", "key-points", "--budget", "0"], "--budget must be >= 1, got 0"),
    (["--seed", "-1"], "--seed must be an integer from 0 to 2**63 - 1, got -1"),
    (["--seed", str(2**70)], f"got {2**70}"),
    (["--size", "4"], "--size must be >= 8, got 4"),
    (["--resume"], "--resume needs --name"),
    (["--name", " padded"], "' padded' starts or ends with whitespace"),
    (["--name", "padded "], "'padded ' starts or ends with whitespace"),
    (["--name", "tab\there"], "U+0009"),
    (["--name", "line\u2028break"], "U+2028"),
    (["--name", "a" * 5000], "is longer than 255 characters"),
]


@pytest.mark.parametrize("options,message", REFUSED_RUN_OPTIONS, ids=lambda v: str(v)[:30])
def test_a_refused_run_option_stores_nothing(db_url, capsys, options, message):
    assert main([*RUN, "--db", db_url, *options]) == 2
    assert message in error_line(capsys)
    assert stored_runs(db_url) is None  # not even the tables: the options are checked before the database opens


def test_the_control_run_is_stored(db_url, capsys):
    # the same command with valid options stores its run: what the refusals above are measured against
    assert main([*RUN, "--db", db_url, "--name", "a name with inner spaces", "--seed", str(SEED_LIMIT - 1)]) == 0
    assert stored_runs(db_url) == 1


def leaf_parsers(parser: argparse.ArgumentParser, words=()):
    """`(command words, parser)` of every command the parser runs (`maps generate`, `run`, ...)."""
    subparsers = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subparsers:
        yield words, parser
        return
    for name, sub in subparsers[0].choices.items():
        yield from leaf_parsers(sub, (*words, name))


def minimal_arguments(parser: argparse.ArgumentParser) -> list[str]:
    """Values for the parser's required options and positionals that argparse accepts (not that the command would)."""
    argv = []
    one_of_each_group = [group._group_actions[0] for group in parser._mutually_exclusive_groups if group.required]
    for action in parser._actions:
        needed = action.required or not action.option_strings or action in one_of_each_group
        if not needed or action.nargs == 0:
            continue
        value = next(iter(action.choices)) if action.choices else "1" if action.type in (int, float) else "x.npz"
        argv += [*action.option_strings[:1], value]
    return argv


SEEDED = [
    (words, parser) for words, parser in leaf_parsers(build_parser()) if "--seed" in parser._option_string_actions
]


def test_every_seeded_command_is_found():
    # the check below covers what the parser has: at least the commands of the issue
    names = {" ".join(words) for words, _ in SEEDED}
    assert {"run", "maps generate", "attack", "robustness", "evaluate"} <= names


@pytest.mark.parametrize("words,parser", SEEDED, ids=[" ".join(w) for w, _ in SEEDED])
def test_every_command_refuses_a_seed_out_of_range(monkeypatch, capsys, words, parser):
    called = []
    built = build_parser()
    for leaf_words, leaf in leaf_parsers(built):
        leaf.set_defaults(func=lambda args, w=leaf_words: called.append(w) or 0)
    monkeypatch.setattr(vinadv.cli, "build_parser", lambda: built)
    argv = [*words, *minimal_arguments(parser)]
    for seed in (-1, SEED_LIMIT, 2**70):
        assert main([*argv, "--seed", str(seed)]) == 2
        assert f"--seed must be an integer from 0 to 2**63 - 1, got {seed}" in error_line(capsys)
    assert not called  # refused before the command ran
    for seed in (0, SEED_LIMIT - 1):
        assert main([*argv, "--seed", str(seed)]) == 0
    assert called == [words, words]


@pytest.mark.parametrize("db", ["sqlite://", "sqlite:///:memory:", "sqlite:///file::memory:?cache=shared"])
def test_the_in_memory_database_is_refused_for_commands_that_store(tmp_path, monkeypatch, capsys, db):
    monkeypatch.chdir(tmp_path)
    assert main([*RUN, "--db", db]) == 2
    assert "in-memory SQLite database" in error_line(capsys)
    robustness = ["robustness", "--n", "1", "--size", "8", "--planner", "optimal", "--quiet", "--db", db]
    assert main(robustness) == 2
    assert "in-memory SQLite database" in error_line(capsys)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("db", ["", "  "])
def test_an_empty_database_url_is_refused_not_taken_for_the_default(tmp_path, monkeypatch, capsys, db):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("VINADV_DB", raising=False)
    assert main([*RUN, "--db", db]) == 2
    assert f"--db: {db!r} names no database" in error_line(capsys)
    assert not (tmp_path / "vinadv.db").exists()


def test_a_url_that_is_no_url_is_one_line_naming_it_without_the_password(capsys):
    assert main([*RUN, "--db", "postgresql://[::1"]) == 2
    assert "--db: not a database URL: postgresql://[::1" in error_line(capsys)
    assert main([*RUN, "--db", "postgresql://me:secret@[::1/x"]) == 2
    line = error_line(capsys)
    assert "postgresql://me:***@[::1/x" in line and "secret" not in line


def test_maps_generate_refuses_no_maps(tmp_path, capsys):
    out = tmp_path / "none.npz"
    assert main(["maps", "generate", "--n", "0", "--size", "8", "--out", str(out), "--quiet"]) == 2
    assert "--n must be >= 1, got 0" in error_line(capsys)
    assert not out.exists()


def test_importing_a_file_of_no_maps_writes_nothing(tmp_path, capsys):
    # a kentsommer file whose maps are all in the train split: its test split holds none
    source = tmp_path / "k.npz"
    assert main(["maps", "generate", "--n", "2", "--size", "8", "--starts", "1", "--out", str(tmp_path / "m.npz")]) == 0
    assert (
        main(
            ["maps", "export", str(tmp_path / "m.npz"), "--format", "kentsommer", "--split", "train"]
            + [
                "--out",
                str(source),
            ]
        )
        == 0
    )
    capsys.readouterr()
    out = tmp_path / "none.npz"
    assert main(["maps", "import", str(source), "--format", "kentsommer", "--out", str(out), "--quiet"]) == 2
    assert f"{source}: no maps to import (split test)" in error_line(capsys)
    assert not out.exists()


def test_plan_and_attack_refuse_a_maps_file_of_no_maps(tmp_path, capsys):
    # as an older vinadv wrote it: every field of a maps file, none of them holding a map
    maps = generate_maps(1, 8, seed=1, n_starts=1)
    empty = tmp_path / "empty.npz"
    save_npz(
        empty,
        MAPS_FORMAT,
        {
            "obstacles": maps.obstacles[:0],
            "goals": maps.goals[:0],
            "starts": maps.starts[:0],
            "expert_costs": maps.expert_costs[:0],
            "expert_cells": np.zeros((0, 2), np.int16),
            "expert_offsets": np.zeros(1, np.int64),
            "corner_cutting": np.array(True),
            "moves": np.array("octile"),
            "seed": np.array(1),
        },
    )
    out = tmp_path / "out.npz"
    assert main(["plan", "--maps", str(empty), "--planner", "optimal", "--out", str(out), "--quiet"]) == 2
    assert f"{empty}: field 'obstacles' holds no maps" in error_line(capsys)
    attack = ["attack", "--maps", str(empty), "--strategy", "near-path", "--planner", "optimal", "--out", str(out)]
    assert main([*attack, "--quiet"]) == 2
    assert f"{empty}: field 'obstacles' holds no maps" in error_line(capsys)
    assert not out.exists()
