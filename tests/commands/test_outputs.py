"""An output that is one of the command's inputs is refused before any work, for every command, whether named by the
same path, another spelling of it, a symlink or a hard link (issue 45, item 2); outputs are checked writable before
the work (`vinadv.outfile.check_output_path`)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.fault_files import tmpfs
from vinadv.cli import main
from vinadv.errors import OutputError
from vinadv.outfile import check_output_folder, check_output_path, same_file

CONTENT = b"an input the command must not overwrite"

#: (command line with IN for the input and OUT for the output, the input's file name, the output's own name when it is
#: a link to the input). The input holds CONTENT, which no command can read: each is refused before it reads it.
CASES = {
    "plan": (["plan", "--maps", "IN", "--out", "OUT"], "m.npz", "p.npz"),
    "plan-planner-file": (["plan", "--maps", "m.npz", "--planner", "IN:make", "--out", "OUT"], "own.py", "p.py"),
    "plan-weights": (["plan", "--maps", "m.npz", "--weights", "IN", "--out", "OUT"], "w.pt", "p.npz"),
    "attack": (["attack", "--maps", "IN", "--strategy", "random", "--out", "OUT"], "m.npz", "p.npz"),
    "maps-concat": (["maps", "concat", "IN", "IN", "--out", "OUT"], "m.npz", "c.npz"),
    "maps-show": (["maps", "show", "IN", "--out", "OUT"], "m.png", "o.png"),
    "maps-import": (["maps", "import", "IN", "--format", "mpd", "--out", "OUT"], "m.npz", "o.npz"),
    "maps-export": (["maps", "export", "IN", "--format", "mpd", "--out", "OUT"], "m.npz", "o.npz"),
    "vin-train": (["vin", "train", "--data", "IN", "--out", "OUT"], "m.npz", "w.pt"),
    "vin-train-init": (["vin", "train", "--data", "m.npz", "--init", "IN", "--out", "OUT"], "w.pt", "v.pt"),
    "vin-train-record": (["vin", "train", "--data", "IN", "--out", "OUT.pt"], "m.json", "w.json"),
    "vin-eval": (["vin", "eval", "--data", "IN", "--out", "OUT"], "m.npz", "f.json"),
    "vin-eval-figure": (["vin", "eval", "--data", "IN", "--figure", "OUT"], "m.png", "f.png"),
    "vin-export-weights": (["vin", "export-weights", "IN", "--format", "state-dict", "--out", "OUT"], "w.pt", "o.pth"),
    "gppn-train": (["gppn", "train", "--data", "IN", "--out", "OUT"], "m.npz", "w.pt"),
    "gppn-eval": (["gppn", "eval", "--data", "IN", "--out", "OUT"], "m.npz", "f.json"),
    "gppn-widen": (["gppn", "widen", "IN", "--l-h", "4", "--out", "OUT"], "w.pt", "o.pt"),
    "gppn-import-weights": (["gppn", "import-weights", "IN", "--k", "5", "--out", "OUT"], "c.pth", "o.pt"),
    "neural-astar-import-weights": (["neural-astar", "import-weights", "IN", "--out", "OUT"], "c.ckpt", "o.pt"),
    "neural-astar-train": (["neural-astar", "train", "--data", "IN", "--out", "OUT"], "m.npz", "w.pt"),
    "eval": (["eval", "--data", "IN", "--out", "OUT"], "m.npz", "f.json"),
    "classify-train": (["classify", "train", "--pairs", "IN", "--model", "svm", "--out", "OUT"], "p.npz", "c.npz"),
    "bench-run": (["bench", "run", "--suite", "vin28-quick-v1", "--db", "IN", "--out", "OUT"], "c.db", "e.json"),
    "bench-leaderboard-index": (["bench", "leaderboard", ".", "--out", "lb", "--index", "OUT"], "a.json", "i.json"),
    "export": (["export", "--db", "IN", "--run", "1", "--out", "OUT"], "r.db", "x.csv"),
    "run": (["run", "--maps", "IN", "--db", "OUT"], "m.npz", "r.db"),
    "run-report": (["run", "--n", "2", "--db", "IN", "--report", "OUT"], "r.db", "rep"),
    "identify": (["identify", "--pairs", "IN", "--db", "OUT"], "p.npz", "r.db"),
    "robustness": (["robustness", "--maps", "IN", "--db", "OUT"], "m.npz", "r.db"),
    "robustness-report": (["robustness", "--n", "2", "--db", "IN", "--report", "OUT"], "r.db", "rep"),
    "report": (["report", "--db", "IN", "--out", "OUT"], "r.db", "rep"),
}


def _as_output(kind: str, source: Path, name: str) -> str:
    """How the output names the input `source`: the same path, another spelling of it, a symlink or a hard link."""
    if kind == "same":
        return str(source)
    if kind == "spelled":  # resolved to the same file: ./sub/../NAME
        (source.parent / "sub").mkdir(exist_ok=True)
        return str(source.parent / "sub" / ".." / source.name)
    link = source.parent / name
    if kind == "symlink":
        link.symlink_to(source.name)
    else:
        os.link(source, link)
    return str(link)


@pytest.mark.parametrize("kind", ["same", "spelled", "symlink", "hardlink"])
@pytest.mark.parametrize("case", list(CASES))
def test_an_output_that_is_an_input_is_refused_before_any_work(case, kind, tmp_path, monkeypatch, capsys):
    argv, in_name, out_name = CASES[case]
    monkeypatch.chdir(tmp_path)
    source = tmp_path / in_name
    source.write_bytes(CONTENT)
    out = _as_output(kind, source, out_name)
    if case == "vin-train-record":  # the record beside OUT.pt is OUT.json: the input
        out = out.removesuffix(".json")
    words = [w.replace("IN", str(source)).replace("OUT", out) for w in argv]
    assert main(words) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "it is the input" in err and "would destroy" in err, err
    assert source.read_bytes() == CONTENT
    assert not [p for p in tmp_path.rglob("*") if p.name.endswith(".tmp")]


def test_figure_and_out_naming_one_file_are_refused(tmp_path, capsys):
    out = str(tmp_path / "f.png")
    assert main(["vin", "eval", "--n", "1", "--out", out, "--figure", out]) == 2
    assert "--figure and --out name one file" in capsys.readouterr().err


# --------------------------------------------------------------------------------------- writable before the work


def test_bench_run_refuses_a_read_only_out_before_computing(tmp_path, monkeypatch, capsys):
    def computed(*args, **kwargs):
        raise AssertionError("the suite was computed before --out was checked")

    monkeypatch.setattr("vinadv.bench.job.run", computed)
    with tmpfs(tmp_path / "ro", "1M", ",ro") as folder:
        out = folder / "entry.json"
        assert main(["bench", "run", "--suite", "vin28-quick-v1", "--out", str(out), "--quiet"]) == 2
        line = capsys.readouterr().err
        assert "entry.json" in line and "read-only" in line and line.count("\n") == 1
        assert list(folder.iterdir()) == []


@pytest.mark.parametrize(
    "argv",
    [
        ["plan", "--maps", "m.npz", "--out", "RO/p.npz"],
        ["vin", "eval", "--n", "1", "--out", "RO/f.json"],
        ["vin", "train", "--data", "m.npz", "--out", "RO/w.pt"],
        ["export", "--db", "r.db", "--run", "1", "--out", "RO/x.csv"],
        ["report", "--db", "r.db", "--out", "RO"],
    ],
    ids=lambda argv: "-".join(argv[:2]),
)
def test_read_only_outputs_are_refused_before_the_work(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    with tmpfs(tmp_path / "ro", "1M", ",ro") as folder:
        assert main([w.replace("RO", str(folder)) for w in argv]) == 2
        line = capsys.readouterr().err
        assert "read-only" in line and line.count("\n") == 1 and "no such file" not in line


def test_check_output_path_probes_and_leaves_nothing(tmp_path):
    out = check_output_path(tmp_path / "new.npz")
    assert out == tmp_path / "new.npz" and list(tmp_path.iterdir()) == []
    (tmp_path / "locked").write_bytes(b"x")
    os.chmod(tmp_path / "locked", 0o444)
    if os.access(tmp_path / "locked", os.W_OK):  # root writes any file
        pytest.skip("a read-only file is writable here (root)")
    with pytest.raises(OutputError, match="locked: the file is read-only"):
        check_output_path(tmp_path / "locked")


def test_same_file_and_folder_checks(tmp_path):
    (tmp_path / "a").write_bytes(b"x")
    os.link(tmp_path / "a", tmp_path / "b")
    (tmp_path / "c").symlink_to("missing")
    assert same_file(tmp_path / "a", tmp_path / "b")
    assert same_file(tmp_path / "c", tmp_path / "missing")  # a dangling link: the file it would create
    assert not same_file(tmp_path / "a", tmp_path / "missing")
    with pytest.raises(OutputError, match="it is the input --db"):
        check_output_folder(tmp_path / "b", inputs={"--db": tmp_path / "a"})
    with pytest.raises(OutputError, match="it exists and is not a folder"):
        check_output_folder(tmp_path / "a")
    assert check_output_folder(tmp_path / "new") == tmp_path / "new" and not (tmp_path / "new").exists()
    check_output_path(tmp_path / "x", inputs={"--data": [None, tmp_path / "y"], "--init": None})


def test_a_report_folder_under_a_read_only_one_is_refused_before_the_work(tmp_path, capsys):
    with tmpfs(tmp_path / "ro", "1M", ",ro") as folder:
        assert main(["report", "--db", str(tmp_path / "r.db"), "--out", str(folder / "new" / "rep")]) == 2
        line = capsys.readouterr().err
        assert "read-only" in line and line.count("\n") == 1
    (tmp_path / "file").write_bytes(b"x")
    with pytest.raises(OutputError, match="is not a folder"):
        check_output_folder(tmp_path / "file" / "rep")
