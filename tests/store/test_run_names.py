"""Run names are found again exactly as given: what could not be (leading or trailing whitespace, control characters,
more characters than a backend's column holds) is refused before anything is written, on every backend. And a
database that would not outlast the command (in memory) or that is no database (an empty URL) is refused."""

from __future__ import annotations

import pytest

from vinadv.errors import InputError
from vinadv.store import Store, resolve_url
from vinadv.store.runs import MAX_NAME_LENGTH, check_run_name


@pytest.mark.parametrize(
    "name,message",
    [
        (" x", "starts or ends with whitespace"),
        ("x ", "starts or ends with whitespace"),
        ("x\n", "starts or ends with whitespace"),
        ("a\x00b", "U+0000 (a control character)"),
        ("a\x1bb", "U+001B (a control character)"),
        ("a\udcffb", "U+DCFF (a lone surrogate"),
        ("a\u2029b", "U+2029 (a paragraph separator)"),
        ("  ", "a name needs a letter"),
        ("42", "a name needs a letter"),
        ("x" * (MAX_NAME_LENGTH + 1), f"is longer than {MAX_NAME_LENGTH} characters"),
    ],
)
def test_names_that_cannot_be_found_again_are_refused(name, message):
    with pytest.raises(InputError) as caught:
        check_run_name(name)
    assert str(caught.value).startswith("name: ") and message in str(caught.value)
    assert caught.value.parameters == ("name",)
    assert "\n" not in str(caught.value)  # one line, whatever the name holds


def test_the_length_limit_is_the_columns():
    assert MAX_NAME_LENGTH == 255
    assert check_run_name("é" * MAX_NAME_LENGTH) == "é" * MAX_NAME_LENGTH


def test_names_at_the_limit_are_stored_and_found_on_every_backend(db_url):
    names = ["a" * MAX_NAME_LENGTH, "\N{GRINNING FACE}" * MAX_NAME_LENGTH, "x\u00a0y inner space"]
    with Store.open(db_url) as store:
        ids = [store.create_run(name) for name in names]
        assert [store.find_run(name) for name in names] == ids
        assert [store.run_info(i)["name"] for i in ids] == names
        with pytest.raises(InputError, match="longer than 255 characters"):
            store.create_run("a" * 5000)
        with pytest.raises(InputError, match="starts or ends with whitespace"):
            store.create_run(names[0][:-1] + " ")
        assert len(store.list_runs(with_counts=False)) == len(names)


@pytest.mark.parametrize("url", ["sqlite://", "sqlite:///:memory:", "sqlite:///file:x?mode=memory&uri=true"])
def test_an_in_memory_database_is_refused_where_tables_would_be_made(url):
    with pytest.raises(InputError, match="in-memory SQLite database") as caught:
        Store.open(url)
    assert caught.value.parameters == ("db",)


def test_an_empty_url_is_refused_and_none_is_the_default(monkeypatch, tmp_path):
    monkeypatch.delenv("VINADV_DB", raising=False)
    monkeypatch.chdir(tmp_path)
    for empty in ("", " "):
        with pytest.raises(InputError, match="names no database"):
            resolve_url(empty)
    assert resolve_url(None) == f"sqlite:///{tmp_path / 'vinadv.db'}"
