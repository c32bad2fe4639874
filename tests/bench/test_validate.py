"""Entries that lie (issue 45): every entry is checked against the entry schema before the leaderboard uses it; a bad
one is one line naming its file and field, the rest still rendered; unreleased suite checksums are labelled unknown;
the Markdown escapes what the entries hold."""

from __future__ import annotations

import copy
import json
import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from vinadv.bench.leaderboard import markdown_text, read_entries_checked, render_markdown, rows
from vinadv.bench.validate import entry_problem
from vinadv.cli import main

COMMITTED = Path(__file__).resolve().parents[2] / "docs" / "results" / "bench"
GOOD = "vin28-quick-v1.vin.json"


def _entry() -> dict:
    return json.loads((COMMITTED / GOOD).read_text())


def _board(tmp_path: Path, bad: dict | str, capsys) -> tuple[int, list[str], str]:
    """`bench leaderboard` on a folder of one committed entry and `bad.json`: (status, error lines, the Markdown)."""
    folder = tmp_path / "entries"
    folder.mkdir()
    shutil.copy(COMMITTED / GOOD, folder / GOOD)
    (folder / "bad.json").write_text(bad if isinstance(bad, str) else json.dumps(bad))
    capsys.readouterr()
    code = main(["bench", "leaderboard", str(folder), "--out", str(tmp_path / "board"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    md = (tmp_path / "board" / "leaderboard.md").read_text() if (tmp_path / "board").exists() else ""
    return code, err, md


def _without(path: str) -> dict:
    e = _entry()
    *parents, last = path.split(".")
    node = e
    for p in parents:
        node = node[p]
    del node[last]
    return e


@pytest.mark.parametrize(
    ("entry", "field"),
    [
        (_without("worst_case"), "worst_case"),  # KeyError 'worst_case'
        ({**_entry(), "worst_case": []}, "worst_case"),  # IndexError
        ({**_entry(), "suite": ["vin28-quick-v1"]}, "suite"),  # TypeError
        ({**_entry(), "clean": {**_entry()["clean"], "success_rate": "0.9"}}, "clean.success_rate"),
        ({**_entry(), "flags": {"too_weak": {"raised": "no"}}}, "flags.too_weak.raised"),
        ({**_entry(), "planner": {"name": 7}}, "planner.name"),
        ({**_entry(), "time": {"chunks_s": ["a"]}}, "time.chunks_s[0]"),
        (_without("suite.checksum"), "suite.checksum"),
    ],
)
def test_a_malformed_entry_is_one_line_naming_file_and_field_and_the_rest_rendered(tmp_path, capsys, entry, field):
    code, err, md = _board(tmp_path, entry, capsys)
    assert code == 2
    assert len(err) == 1 and "bad.json" in err[0] and f"field '{field}'" in err[0], err
    assert f"({'../entries/' + GOOD})" in md  # the good entry is still rendered


def test_json_nested_too_deep_is_one_line(tmp_path, capsys):
    code, err, md = _board(tmp_path, "[" * 100_000 + "]" * 100_000, capsys)  # RecursionError in json
    assert code == 2 and len(err) == 1 and "bad.json" in err[0] and GOOD in md


@pytest.mark.parametrize("value", [float("inf"), float("nan"), 7.0, -5.0])
@pytest.mark.parametrize("where", ["clean.success_rate", "worst_case[0].harmful_rate"])
def test_rates_outside_zero_one_or_not_finite_are_refused(tmp_path, capsys, value, where):
    e = _entry()
    if where == "clean.success_rate":
        e["clean"]["success_rate"] = value
    else:
        e["worst_case"][0]["harmful_rate"] = value
    code, err, md = _board(tmp_path, e, capsys)
    assert code == 2 and len(err) == 1 and f"field '{where}'" in err[0], err
    assert "inf%" not in md and "700.0%" not in md and "nan%" not in md


def test_a_fake_suite_checksum_is_labelled_unknown_and_never_ranked_with_the_released_suite(tmp_path, capsys):
    e = _entry()
    e["suite"]["checksum"] = "0" * 64
    e["worst_case"][0]["harmful_rate"] = 0.0  # would rank first
    e["planner"]["name"] = "fake"
    code, err, md = _board(tmp_path, e, capsys)
    assert code == 0 and not err
    genuine, unknown = md.split("### ")[1:]
    assert "unknown" not in genuine and "[fake]" not in genuine and "[vin]" in genuine
    assert "unknown" in unknown and "[fake]" in unknown


def test_strings_from_entries_are_escaped_in_markdown(tmp_path, capsys):
    e = _entry()
    e["planner"]["name"] = "x\n| injected | row |<script>alert(1)</script>[l](http://e)"
    e["flags"]["too_weak"] = {"raised": True, "why": ""}
    e["flags"]["a_flag|<b>"] = {"raised": True, "why": ""}
    e["machine"]["device"] = "cpu</td>\n|"
    code, err, md = _board(tmp_path, e, capsys)
    assert code == 0 and not err
    assert "<script>" not in md and "\n| injected" not in md and "<b>" not in md
    assert "\\[l\\](http" in md  # the name's link markup escaped: no link of its own
    lines = [line for line in md.splitlines() if line.startswith("| ")]
    cells = [len(re.findall(r"(?<!\\)\|", line)) for line in lines]  # unescaped separators
    assert cells == [cells[0]] * len(cells)  # no cell and no row added
    html = (tmp_path / "board" / "leaderboard.html").read_text()
    assert "<script>" not in html and "&lt;script&gt;" in html


def test_markdown_text_leaves_plain_names_alone():
    assert markdown_text("vin-robust") == "vin-robust" and markdown_text("too_weak") == "too_weak"
    assert markdown_text("_x_") == "\\_x\\_" and markdown_text("a|b") == "a\\|b"


def test_every_committed_entry_satisfies_the_schema():
    for path in sorted(COMMITTED.glob("*.json")):
        assert entry_problem(json.loads(path.read_text())) is None, path
    entries, problems = read_entries_checked(COMMITTED)
    assert not problems and len(entries) == len(list(COMMITTED.glob("*.json")))


def test_a_fifo_named_like_an_entry_is_refused_by_type(tmp_path, capsys):
    folder = tmp_path / "entries"
    folder.mkdir()
    shutil.copy(COMMITTED / GOOD, folder / GOOD)
    os.mkfifo(folder / "pipe.json")
    assert main(["bench", "leaderboard", str(folder), "--out", str(tmp_path / "b"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pipe.json" in err[0] and "not a regular file" in err[0]


#: what a mutation puts in place of a field (or of the whole entry); `[]` empties a list
HOSTILE = [None, True, 0, -1, 7.0, -5.0, float("inf"), float("nan"), 10**30, "", "x" * 1000, "<b>|\n", [], {}, [1]]
#: the kinds of mutation: a field deleted, the whole entry replaced, or a field replaced by each hostile value
KINDS = ("delete", "whole", *range(len(HOSTILE)))


def _mutations(entry, rng, kinds):
    """A mutated copy of `entry` for each of `kinds` (`KINDS`), on a field drawn evenly among the entry's fields,
    where the items of a list count as one field (a -v2 entry's thousands of per-map items would otherwise take
    nearly every draw): the field deleted (a field of an object), the whole entry replaced by a hostile value, or the
    field replaced by the hostile value `HOSTILE[kind]`."""
    fields: dict[tuple, list[tuple]] = {}  # a field's path, list indices as "#" -> the paths of its values

    def walk(node, path, field):
        if path:
            fields.setdefault(field, []).append(path)
        if isinstance(node, dict):
            for k, v in node.items():
                walk(v, (*path, k), (*field, k))
        elif isinstance(node, list):
            for i, v in enumerate(node):
                walk(v, (*path, i), (*field, "#"))

    walk(entry, (), ())
    names = list(fields)
    for kind in kinds:
        if kind == "whole":
            yield HOSTILE[rng.integers(len(HOSTILE))]
            continue
        e = copy.deepcopy(entry)
        # only an object's field can be deleted; a list item is replaced
        choices = [f for f in names if isinstance(f[-1], str)] if kind == "delete" else names
        paths = fields[choices[rng.integers(len(choices))]]
        path = paths[rng.integers(len(paths))]
        node = e
        for p in path[:-1]:
            node = node[p]
        if kind == "delete":
            del node[path[-1]]
        else:
            node[path[-1]] = copy.deepcopy(HOSTILE[kind])
        yield e


@pytest.mark.slow
def test_fuzz_leaderboard_every_mutation_renders_or_is_one_line(tmp_path, capsys):
    """In-process fuzz of `bench leaderboard` and the entry reader: mutations of the committed entries either render
    or give one line naming the file and a field; never a traceback. Five mutations of each entry, their kinds taken
    in turn across the entries, so that every kind is tried on several entries (a `bench leaderboard` call each:
    most of the test's time)."""
    rng = np.random.default_rng(45)
    tried = []
    for i, source in enumerate(sorted(COMMITTED.glob("*.json"))):
        entry = json.loads(source.read_text())
        kinds = [KINDS[(5 * i + j) % len(KINDS)] for j in range(5)]
        tried += kinds
        for j, mutated in enumerate(_mutations(entry, rng, kinds)):
            folder = tmp_path / f"f{i}-{j}"
            folder.mkdir()
            (folder / "m.json").write_text(json.dumps(mutated))
            code = main(["bench", "leaderboard", str(folder), "--out", str(folder / "o"), "--quiet"])
            err = capsys.readouterr().err.strip().splitlines()
            assert code in (0, 2), (source.name, mutated)
            if code == 2:
                assert len(err) == 1 and "m.json" in err[0] and ("field '" in err[0] or "not a" in err[0]), err
            else:
                assert not err
                md = (folder / "o" / "leaderboard.md").read_text()
                assert "inf%" not in md and "nan%" not in md
                entries, problems = read_entries_checked(folder)
                render_markdown(rows(entries))
    assert all(tried.count(kind) >= 3 for kind in KINDS)  # each kind on three entries at least
