"""`vinadv --version`: the version and the SHA-256 of every shipped weights file, checked against hashlib."""

import hashlib
import json
from pathlib import Path

import pytest

import vinadv
from vinadv import cli

WEIGHTS = Path(vinadv.__file__).resolve().parent / "weights"


def test_version_prints_every_shipped_weights_file_with_its_sha256(capsys):
    with pytest.raises(SystemExit) as done:
        cli.main(["--version"])
    assert done.value.code == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == f"vinadv {vinadv.__version__}"
    printed = dict(line.split() for line in lines[2:])
    files = sorted(WEIGHTS.glob("*.pt"))
    assert {"vin28.pt", "vin28_robust.pt", "gppn28.pt"} <= {f.name for f in files}
    assert printed == {f.name: hashlib.sha256(f.read_bytes()).hexdigest() for f in files}
    assert list(printed) == sorted(printed)


def test_the_printed_checksums_are_the_ones_the_metrics_files_record():
    # a figure in the docs is traced to its weights by this checksum
    sums = cli.shipped_weights_checksums()
    for metrics in WEIGHTS.glob("*.metrics.json"):
        data = json.loads(metrics.read_text())
        recorded = data.get("weights_sha256") or data["planner"]["weights_sha256"]
        assert recorded == sums[metrics.name.replace(".metrics.json", ".pt")], metrics.name


def test_checksums_of_another_folder(tmp_path):
    (tmp_path / "b.pt").write_bytes(b"two")
    (tmp_path / "a.pt").write_bytes(b"")
    (tmp_path / "a.json").write_text("{}")  # only weights files count
    assert cli.shipped_weights_checksums(tmp_path) == {
        "a.pt": hashlib.sha256(b"").hexdigest(),
        "b.pt": hashlib.sha256(b"two").hexdigest(),
    }
    assert cli.shipped_weights_checksums(tmp_path / "none") == {}
