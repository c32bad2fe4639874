"""Faults end to end (issue 21): runs (names, full disk, resume after a kill inside a transaction), output files
(read-only, full, a folder in the way, a broken pipe), `maps generate` limits, run references."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from tests.fault_files import killed_at_exit, tmpfs
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.executor import LocalExecutor
from vinadv.grid import generate_maps, generator
from vinadv.pipeline import RunConfig, run_pipeline
from vinadv.store import Store

SIZE = 12
ENV = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "src"), "PYTHONUNBUFFERED": "1"}


@pytest.fixture(scope="module")
def weights(planning_weights):
    return planning_weights(SIZE)


def _args(weights, db, *extra, n=60, shard=20):
    return [
        "run",
        "--n",
        str(n),
        "--size",
        str(SIZE),
        "--shard-size",
        str(shard),
        "--weights",
        weights,
        "--seed",
        "3",
        "--db",
        db,
        "--quiet",
        *extra,
    ]


def _one_line(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("vinadv: error: "), err
    assert "Traceback" not in err
    return lines[0]


# ----------------------------------------------------------------------------------------------------- runs


def test_run_name_taken_is_refused_without_resume(weights, tmp_path, capsys):
    db = str(tmp_path / "runs.db")
    assert main(_args(weights, db, "--name", "k")) == 0
    assert main(_args(weights, db, "--name", "k")) == 2
    line = _one_line(capsys.readouterr().err)
    assert "'k'" in line and "--resume" in line
    with Store.open(db) as store:
        assert len(store.list_runs()) == 1
    assert main(_args(weights, db, "--name", "k", "--resume")) == 0


@pytest.mark.slow
def test_full_disk_during_a_run_is_one_line_with_the_resume_hint(weights, tmp_path):
    with tmpfs(tmp_path / "full", "1M") as folder:
        db = str(folder / "full.db")
        done = subprocess.run(
            [sys.executable, "-m", "vinadv.cli", *_args(weights, db, "--name", "big", n=3000, shard=500)],
            capture_output=True,
            text=True,
            env=ENV,
            timeout=600,
            check=False,
        )
        assert done.returncode == 2, done.stderr[-2000:]
        line = _one_line(done.stderr)
        assert "full.db" in line and "full" in line and "--name big --resume" in line
        assert "INSERT" not in line and len(line) < 400


def test_resume_of_a_complete_run_recomputes_nothing(weights, tmp_path):
    db = str(tmp_path / "runs.db")
    config = RunConfig(n=60, size=SIZE, shard_size=20, seed=3, weights=weights)
    first = run_pipeline(config, db=db, name="done", progress=False)
    computed = []

    class Recording(LocalExecutor):
        def map(self, task, chunks, *, ordered=True):
            computed.extend(chunks)
            return iter(())

    again = run_pipeline(config, db=db, name="done", resume=True, progress=False, executor=Recording())
    assert computed == [] and again.skipped_shards == 3 and again.stored == 0
    with Store.open(db) as store:
        assert store.count_pairs(first.run_id) == first.stored


_KILLED_IN_A_TRANSACTION = textwrap.dedent("""
    import sys, time
    from vinadv.store.store import Store
    insert = Store._insert_sqlite
    calls = []

    def slow(self, *args):
        insert(self, *args)
        calls.append(1)
        if len(calls) == 3:  # the third shard's rows are inserted, its transaction is open: wait to be killed
            print("in transaction", flush=True)
            time.sleep(120)

    Store._insert_sqlite = slow
    from vinadv.cli import main
    sys.exit(main(sys.argv[1:]))
""")


@pytest.mark.slow
def test_kill_inside_a_transaction_then_resume_stores_every_pair_once(weights, tmp_path):
    db = str(tmp_path / "killed.db")
    args = _args(weights, db, "--name", "k", n=100, shard=20)
    argv = [sys.executable, "-c", _KILLED_IN_A_TRANSACTION, *args]
    with killed_at_exit(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV) as child:
        line = child.stdout.readline()
        assert line.strip() == "in transaction", child.stderr.read()
    with Store.open(db) as store:
        run_id = store.find_run("k")
        partial = store.stored_indices(run_id)
        assert store.shards_done(run_id) == 2
        assert 0 < len(partial) and partial.max() < 40  # shards 0 and 1 (maps 0-39); the open transaction left nothing
    assert main([*args, "--resume"]) == 0
    clean = str(tmp_path / "clean.db")
    assert main(_args(weights, clean, "--name", "k", n=100, shard=20)) == 0
    with Store.open(db) as resumed, Store.open(clean) as reference:
        got = resumed.read_pairs(resumed.find_run("k"))
        assert len(np.unique(got.pair_index)) == len(got)
        assert got.equals(reference.read_pairs(reference.find_run("k")))


def test_evaluate_and_export_read_run_names_alike(weights, tmp_path, capsys):
    db = str(tmp_path / "runs.db")
    assert main(_args(weights, db, "--name", "named")) == 0
    out = tmp_path / "x.csv"
    assert main(["export", "--db", db, "--run", "named", "--out", str(out), "--quiet"]) == 0
    with Store.open(db) as store:
        run_id = store.find_run("named")
    code = main(["evaluate", "--db", db, "--run", "named", "--classifiers", "rule", "--quiet", "--sizes", "1"])
    # the name is resolved to its run: evaluated, or (60 small maps) too few FP/DP pairs in that very run
    assert code == 0 or f"run {run_id} has" in _one_line(capsys.readouterr().err)
    for command in (["export"], ["evaluate", "--classifiers", "rule"], ["report", "--out", str(tmp_path / "r")]):
        assert main([*command, "--db", db, "--run", "nameless"]) == 2
        assert "--run: no run named 'nameless'" in _one_line(capsys.readouterr().err)


# ------------------------------------------------------------------------------------------------- outputs


def _maps(out: str, *extra) -> list[str]:
    return ["maps", "generate", "--n", "5", "--size", "10", "--out", out, "--quiet", *extra]


def test_a_directory_as_out_is_one_line(tmp_path, capsys):
    assert main(_maps(str(tmp_path))) == 2
    assert "is a directory" in _one_line(capsys.readouterr().err)
    assert main(_maps(str(tmp_path / "missing" / "m.npz"))) == 2
    assert "does not exist" in _one_line(capsys.readouterr().err)


def test_read_only_target_is_one_line_and_leaves_nothing(tmp_path, capsys):
    with tmpfs(tmp_path / "ro", "1M", ",ro") as folder:
        assert main(_maps(str(folder / "m.npz"))) == 2
        line = _one_line(capsys.readouterr().err)
        assert "m.npz" in line and "read-only" in line
        assert list(folder.iterdir()) == []


def test_full_disk_output_is_one_line_and_leaves_no_temp_file(tmp_path, capsys):
    with tmpfs(tmp_path / "full", "64k") as folder:
        (folder / "m.npz").write_bytes(b"old")
        assert main(["maps", "generate", "--n", "200", "--size", "16", "--out", str(folder / "m.npz"), "--quiet"]) == 2
        line = _one_line(capsys.readouterr().err)
        assert "m.npz" in line and "no space left" in line
        assert [p.name for p in folder.iterdir()] == ["m.npz"] and (folder / "m.npz").read_bytes() == b"old"


@pytest.mark.slow
def test_export_into_a_broken_pipe_ends_quietly(weights, tmp_path):
    db = str(tmp_path / "runs.db")
    assert main(_args(weights, db, "--name", "p", n=200, shard=200)) == 0
    done = subprocess.run(
        f"{sys.executable} -m vinadv.cli export --db {db} --run p --quiet | head -c 100 >/dev/null; "
        "echo ${PIPESTATUS[0]}",
        shell=True,
        executable="/bin/bash",
        capture_output=True,
        text=True,
        env=ENV,
        timeout=300,
        check=False,
    )
    assert done.stdout.strip() in ("0", "141"), done.stderr
    assert "Traceback" not in done.stderr and "BrokenPipe" not in done.stderr and "Exception" not in done.stderr


# ------------------------------------------------------------------------------------------- maps generate


@pytest.mark.parametrize("args, limit", [(["--size", "100000"], "--size"), (["--n", "1000000000000"], "--n")])
def test_maps_generate_refuses_what_cannot_fit_at_once(args, limit, tmp_path, capsys):
    t0 = time.perf_counter()
    assert main(["maps", "generate", "--n", "3", *args, "--out", str(tmp_path / "m.npz"), "--quiet"]) == 2
    line = _one_line(capsys.readouterr().err)
    assert line.startswith(f"vinadv: error: {limit} ") and "the limit here is about" in line and "GiB" in line
    assert time.perf_counter() - t0 < 5 and not (tmp_path / "m.npz").exists()


def test_generator_chunks_shrink_with_the_size_and_keep_memory_bounded():
    assert generator.chunk_maps(28) == generator.CHUNK  # the 28x28 stream is unchanged
    assert generator.chunk_maps(100) < 20
    tracemalloc.start()
    maps = generator.generate_maps(generator.chunk_maps(60) + 3, 60, seed=1, n_starts=2)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 2 * generator.CHUNK_BYTES
    # the stream does not depend on n: a shorter run is a prefix, across the chunk boundary
    shorter = generator.generate_maps(generator.chunk_maps(60) + 1, 60, seed=1, n_starts=2)
    assert np.array_equal(maps.obstacles[: len(shorter)], shorter.obstacles)
    assert np.array_equal(maps.expert.cells[: len(shorter.expert.cells)], shorter.expert.cells)


def test_generator_library_errors_name_parameters():
    with pytest.raises(InputError, match="^size 100000") as caught:  # the command line shows --size 100000
        generate_maps(1, 100000)
    assert "size" in caught.value.parameters
