"""`vinadv serve`: refuses non-loopback addresses without --allow-remote, bad ports and missing databases (exit
2, a message naming the problem); serves the app on a loopback address."""

from __future__ import annotations

import socket
import threading
import urllib.request

import pytest
import sqlalchemy as sa
import werkzeug.serving

from vinadv.cli import main
from vinadv.store import Store
from vinadv.viewer.app import is_loopback


@pytest.mark.parametrize(
    "host,expected",
    [
        ("127.0.0.1", True),
        ("127.4.5.6", True),
        ("localhost", True),
        ("::1", True),
        ("[::1]", True),
        ("0.0.0.0", False),
        ("::", False),
        ("192.168.1.10", False),
        ("example.org", False),
        ("10.0.0.1", False),
    ],
)
def test_is_loopback(host, expected):
    assert is_loopback(host) is expected


@pytest.mark.parametrize("host", ["0.0.0.0", "192.168.1.10", "example.org"])
def test_serve_refuses_remote_address_without_flag(db, capsys, host):
    assert main(["serve", "--db", db[0], "--host", host]) == 2
    err = capsys.readouterr().err
    assert f"--host {host}" in err and "--allow-remote" in err


@pytest.mark.parametrize("port", ["0", "70000", "-1"])
def test_serve_refuses_bad_port(db, capsys, port):
    assert main(["serve", "--db", db[0], "--port", port]) == 2
    assert "--port" in capsys.readouterr().err


def test_serve_refuses_a_bench_folder_that_is_not_there(db, tmp_path, capsys):
    assert main(["serve", "--db", db[0], "--bench", str(tmp_path / "nope")]) == 2
    assert f"--bench {tmp_path / 'nope'}: no such folder" in capsys.readouterr().err


def test_serve_refuses_missing_database(tmp_path, capsys):
    assert main(["serve", "--db", str(tmp_path / "missing.db")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert not (tmp_path / "missing.db").exists()


def test_serve_port_in_use(db, capsys):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["serve", "--db", db[0], "--port", str(port), "--quiet"]) == 2
    assert "cannot listen" in capsys.readouterr().err


def test_serve_runs_on_loopback(db, monkeypatch, capsys):
    """The command builds the app and serves it on 127.0.0.1 (the test stops it through the server object)."""
    made = {}
    real_make_server = werkzeug.serving.make_server

    def make_server(*args, **kwargs):
        made["server"] = server = real_make_server(*args, **kwargs)
        return server

    monkeypatch.setattr(werkzeug.serving, "make_server", make_server)
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    thread = threading.Thread(
        target=main, args=(["serve", "--db", db[0], "--port", str(port), "--quiet"],), daemon=True
    )
    thread.start()
    for _ in range(400):
        if "server" in made or not thread.is_alive():
            break
        threading.Event().wait(0.05)
    try:
        assert "server" in made, "serve did not build its server"
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/runs", timeout=10) as response:
            assert response.status == 200 and b'"random"' in response.read()
    finally:
        if thread.is_alive() and "server" in made:
            made["server"].shutdown()
        thread.join(10)
    assert not thread.is_alive()
    assert "vinadv viewer on http://127.0.0.1:" in capsys.readouterr().out


def test_ensure_indexes_adds_missing(tmp_path):
    url = f"sqlite:///{tmp_path / 'old.db'}"
    with Store.open(url) as store:
        with store.engine.begin() as conn:
            conn.execute(sa.text("DROP INDEX ix_map_pairs_run_source"))
        assert store.ensure_indexes() == ["ix_map_pairs_run_source"]
        assert store.ensure_indexes() == []
