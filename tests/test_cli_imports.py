"""`vinadv --help`, `--version` and the help of commands that need no heavy library import none of them: the parser
is built from light modules (behaviour, not timing: which modules a fresh interpreter loaded)."""

import json
import subprocess
import sys

import pytest

from tests.needs import MODELLED_CPU, cpu_vendor

HEAVY = ("torch", "numba", "sklearn", "sqlalchemy", "scipy", "matplotlib", "distributed", "flask")


def imported_modules(*argv: str) -> set[str]:
    """Top-level packages a fresh `python -X importtime -m vinadv.cli ARGV` imported (it exits 0)."""
    done = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "vinadv.cli", *argv], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-2000:]
    lines = [line.split("|")[-1] for line in done.stderr.splitlines() if line.startswith("import time:")]
    names = {line.strip().split(".")[0] for line in lines}
    assert "vinadv" in names  # the importtime report was read
    return names


@pytest.mark.parametrize(
    "argv",
    [
        ["--help"],
        ["--version"],
        ["maps", "generate", "--help"],
        ["plan", "--help"],
        ["export", "--help"],
        ["report", "--help"],
        ["serve", "--help"],
    ],
    ids=" ".join,
)
def test_parser_imports_no_heavy_library(argv):
    assert not imported_modules(*argv) & set(HEAVY)


@pytest.mark.parametrize("argv", [["--help"], ["--version"]], ids=" ".join)
def test_top_level_help_imports_no_numpy_either(argv):
    # NumPy alone is a third of a second to import: the bare parser does without it
    assert "numpy" not in imported_modules(*argv)


@pytest.mark.slow
def test_a_command_still_checks_its_choices():
    done = subprocess.run(
        [sys.executable, "-m", "vinadv.cli", "run", "--attack", "nope", "--n", "1"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 2 and "near-path" in done.stderr and "nope" in done.stderr


@pytest.mark.slow
def test_a_run_with_the_rule_labeller_does_without_scikit_learn(tmp_path):
    # every command imports only what it uses: the rule labeller is plain Numba, the classifiers bring scikit-learn
    names = imported_modules("run", "--n", "20", "--db", str(tmp_path / "r.db"), "--quiet")
    assert "sqlalchemy" in names and "numba" in names  # the run did happen
    assert "sklearn" not in names and "matplotlib" not in names and "flask" not in names


@pytest.mark.slow
def test_a_vin_run_needs_no_pytorch_once_the_replay_settings_are_kept(tmp_path, monkeypatch):
    # the first run measures PyTorch's arithmetic for the near-tie replay and keeps it; the next loads no PyTorch
    monkeypatch.setenv("VINADV_CACHE_DIR", str(tmp_path / "cache"))
    first = imported_modules("run", "--n", "2000", "--db", str(tmp_path / "a.db"), "--quiet")
    assert "torch" in first
    kept = json.loads((tmp_path / "cache" / "torch_replay.json").read_text())["machines"]
    (entries,) = kept.values()
    assert {"conv_modes", "sum_order", "fc_order", "default_threads"} <= set(entries)
    # where this CPU's BLAS order is not modelled (an Intel Xeon's MKL), nothing is verified and PyTorch stays in use
    replayed = {"q_verified", "fc_verified"} <= set(entries)
    assert replayed or not MODELLED_CPU, f"the replay was not verified on a modelled CPU ({cpu_vendor()})"
    second = imported_modules("run", "--n", "2000", "--seed", "1", "--db", str(tmp_path / "b.db"), "--quiet")
    assert "sqlalchemy" in second and ("torch" in second) == (not replayed)
