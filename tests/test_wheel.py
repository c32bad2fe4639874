"""The release shape: the wheel carries the code, templates and shipped weights, and runs the main job outside the
repository (issue 35). Built with `pip wheel --no-deps`, installed with `--no-deps` into a fresh venv in a temporary
folder; the dependencies come from the test's own environment through a `.pth` line (the machine's system Python
has none), after the wheel's own site-packages, so `import vinadv` can only find the installed wheel.

The installed copy starts with the checkout's compiled Numba kernels (`seed_numba_cache`): compiling a run's kernels
cold takes half a minute or more on the 2-core machine, for the very code the rest of the suite compiles and runs,
and it is not what this test checks (the wheel's files, the install, the main job outside the repository)."""

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]


def seed_numba_cache(checkout: Path, installed: Path) -> int:
    """Copy the checkout's Numba cache (`__pycache__/*.nbi`, `*.nbc`: `cache=True` kernels) into the installed package
    `installed`, for the modules whose installed file is byte for byte the checkout's, and give those files the
    checkout's modification time; returns how many cache files it copied. Numba keys its in-tree cache by the source
    file's folder, modification time and size, and each kernel by its bytecode; a module the wheel changed, or one
    missing, finds no entry and compiles (or fails) as it would without this."""
    copied = 0
    for source in checkout.rglob("*.py"):
        target = installed / source.relative_to(checkout)
        if not target.is_file() or target.read_bytes() != source.read_bytes():
            continue
        stat = source.stat()
        os.utime(target, ns=(stat.st_atime_ns, stat.st_mtime_ns))
        caches = sorted(source.parent.glob(f"__pycache__/{source.stem}.*.nb[ic]"))
        for cache in caches:
            (target.parent / "__pycache__").mkdir(exist_ok=True)
            shutil.copy2(cache, target.parent / "__pycache__" / cache.name)
        copied += len(caches)
    return copied


def test_the_wheel_installs_outside_the_repository_and_runs_the_main_job(tmp_path):
    # no PYTHONPATH anywhere: with the checkout's src/ on it, pip would take the build's src/vinadv.egg-info for an
    # installed vinadv and skip the wheel
    clean_env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    dist = tmp_path / "dist"
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(dist), str(ROOT)],
        check=True,
        capture_output=True,
        env=clean_env,
    )
    (wheel,) = dist.glob("vinadv-*.whl")
    env_dir = tmp_path / "env"
    venv.EnvBuilder(system_site_packages=True, with_pip=False).create(env_dir)
    python = env_dir / "bin" / "python"
    site = Path(
        subprocess.run(
            [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
            check=True,
            capture_output=True,
            text=True,
        ).stdout.strip()
    )
    subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps", "--no-index", "-q", str(wheel)],
        check=True,
        capture_output=True,
        env=clean_env,
    )
    (site / "zz_test_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    seed_numba_cache(ROOT / "src" / "vinadv", site / "vinadv")
    work = tmp_path / "elsewhere"
    work.mkdir()
    where = subprocess.run(
        [str(python), "-c", "import vinadv.planners.weights as w; print(w.WEIGHTS_DIR)"],
        cwd=work,
        env=clean_env,
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    assert Path(where).is_relative_to(env_dir), where  # the wheel's copy, not the checkout's
    assert (Path(where) / "vin28.pt").is_file()
    ran = subprocess.run(
        [str(env_dir / "bin" / "vinadv"), "run", "--n", "50", "--db", "out.db", "--name", "w", "--json", "--quiet"],
        cwd=work,
        env=clean_env,
        capture_output=True,
        text=True,
    )
    assert ran.returncode == 0, ran.stderr
    summary = json.loads(ran.stdout)
    assert (summary["maps"], summary["pairs"], summary["stored"]) == (50, 50, 50), summary
    assert (work / "out.db").is_file()
    # the model zoo and its bench entries come with the wheel (package data), not from the repository's docs
    listed = subprocess.run(
        [str(env_dir / "bin" / "vinadv"), "planners", "--json"], cwd=work, env=clean_env, capture_output=True, text=True
    )
    assert listed.returncode == 0, listed.stderr
    by_name = {p["name"]: p for p in json.loads(listed.stdout)["planners"]}
    assert by_name["vin"]["zoo"] == "vin28" and by_name["vin"]["bench_entries"], by_name["vin"]
