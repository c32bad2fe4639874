"""`--cluster` / `--workers`: a LocalCluster of 2 worker processes gives the same stored run, pairs file and labels
as the local commands, pair by pair; a worker killed mid-run still leaves every pair stored exactly once.

The oracle is the local, in-process computation (tests/test_pipeline.py pins that one against independent
oracles); one module-scoped cluster serves every test (its start-up is the slow part on 2 cores). The tests that
need a cluster are slow (`make test-fast` leaves them out); the ones that check what runs before or without one
are quick.
"""

import builtins
import json
import os
import signal
from pathlib import Path

import numpy as np
import pytest

from tests.needs import skip_or_fail

try:
    import distributed  # noqa: F401 (installed with the cluster extra, which `make test` and CI install)
except ImportError:
    skip_or_fail("Dask's distributed is not installed (pip install -e '.[cluster]')", module=True)

from distributed import Client  # noqa: E402

from tests.bench.two_maps import heldout_suite  # noqa: E402
from tests.cli_files import command_line, generate_and_attack  # noqa: E402
from vinadv.attacks.pairs import PairSet  # noqa: E402
from vinadv.bench import suites  # noqa: E402
from vinadv.bench.scoring import deterministic_part, entry_json, run_bench  # noqa: E402
from vinadv.bench.suites import AttackGroup  # noqa: E402
from vinadv.cli import main  # noqa: E402
from vinadv.cluster import DaskExecutor, start_local_cluster  # noqa: E402
from vinadv.cluster.worker import plugin_class  # noqa: E402
from vinadv.errors import InputError  # noqa: E402
from vinadv.executor import LOCAL, ByReference, LocalExecutor, resolve  # noqa: E402
from vinadv.grid import generate_maps  # noqa: E402
from vinadv.pipeline import RunConfig, compute_shard, maps_file_config, run_pipeline  # noqa: E402
from vinadv.planners.registry import PlannerRef, load_planner  # noqa: E402
from vinadv.planners.vin.weights import load_vin, save_vin  # noqa: E402
from vinadv.store import Store  # noqa: E402
from vinadv.testing.planners import planning_vin  # noqa: E402

SIZE = 12


@pytest.fixture(scope="module")
def weights(planning_weights):
    return planning_weights(SIZE)


@pytest.fixture(scope="module")
def cluster():
    with start_local_cluster(2) as local, Client(local) as client:
        client.register_plugin(plugin_class()())
        yield local, client


def config(weights, **kw):
    defaults = dict(n=200, size=SIZE, attack="near-path", seed=7, shard_size=20, weights=weights)
    return RunConfig(**{**defaults, **kw})


def stored(db, run_id):
    with Store.open(db) as store:
        return store.read_pairs(run_id)


@pytest.mark.slow
def test_run_on_the_cluster_stores_the_same_pairs_as_the_local_run(weights, cluster, tmp_path):
    _, client = cluster
    local_db, cluster_db = f"sqlite:///{tmp_path / 'local.db'}", f"sqlite:///{tmp_path / 'cluster.db'}"
    local = run_pipeline(config(weights), db=local_db, name="x", progress=False)
    on_cluster = run_pipeline(config(weights), db=cluster_db, name="x", progress=False, executor=DaskExecutor(client))
    assert on_cluster.stored == on_cluster.n_pairs == local.n_pairs > 150
    a, b = stored(local_db, local.run_id), stored(cluster_db, on_cluster.run_id)
    assert np.array_equal(a.pair_index, b.pair_index) and a.equals(b)
    assert on_cluster.counts == local.counts
    assert len(client.nthreads()) == 2


@pytest.mark.slow
def test_workers_are_single_threaded(cluster):
    _, client = cluster

    def threads():
        import torch  # noqa: PLC0415 (the worker's: what runs there imports there)

        from vinadv.cluster.worker import single_threaded  # noqa: PLC0415 (as above)

        single_threaded()
        import numba  # noqa: PLC0415 (as above, after single_threaded())

        from vinadv.planners import batching  # noqa: PLC0415 (as above)

        return (
            torch.get_num_threads(),
            numba.get_num_threads(),
            os.environ.get("NUMBA_NUM_THREADS"),
            batching.N_THREADS,
        )

    assert set(client.run(threads).values()) == {(1, 1, "1", 1)}


def test_a_worker_with_other_weights_refuses_them(weights):
    with pytest.raises(InputError, match="workers need the same planner files"):
        resolve(ByReference(PlannerRef("vin", weights, SIZE, True, "0" * 64)))


@pytest.mark.slow  # starts (and stops) a LocalCluster of its own: the path users take with --workers
def test_cli_run_with_a_local_cluster_of_its_own(weights, tmp_path):
    common = ["run", "--n", "20", "--size", str(SIZE), "--shard-size", "10", "--weights", weights, "--quiet"]
    assert main([*common, "--db", str(tmp_path / "a.db")]) == 0
    assert main([*common, "--db", str(tmp_path / "b.db"), "--workers", "1"]) == 0
    with Store.open(str(tmp_path / "a.db")) as a, Store.open(str(tmp_path / "b.db")) as b:
        assert a.read_pairs(a.list_runs()[0]["id"]).equals(b.read_pairs(b.list_runs()[0]["id"]))


@pytest.mark.slow
def test_cli_run_with_cluster_address_matches_the_local_cli_run(weights, cluster, tmp_path):
    local, _ = cluster
    common = [
        *command_line("run", n=60, size=SIZE, shard_size=20, weights=weights, seed=3, attack="key-points"),
        "--quiet",
    ]
    assert main([*common, "--db", str(tmp_path / "a.db")]) == 0
    assert main([*common, "--db", str(tmp_path / "b.db"), "--cluster", local.scheduler_address]) == 0
    with Store.open(str(tmp_path / "a.db")) as a, Store.open(str(tmp_path / "b.db")) as b:
        assert a.read_pairs(a.list_runs()[0]["id"]).equals(b.read_pairs(b.list_runs()[0]["id"]))


@pytest.mark.slow
def test_a_killed_worker_still_leaves_every_pair_exactly_once(weights, cluster, tmp_path):
    local, client = cluster
    pids_before = set(client.run(os.getpid).values())
    killed = []

    def kill_one_worker(result):
        # after the first shard arrives, SIGKILL a worker process while it holds queued and running shards;
        # its nanny starts a new one and the scheduler gives the lost shards to the workers again
        if not killed:
            pid = sorted(pids_before)[0]
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    db = f"sqlite:///{tmp_path / 'kill.db'}"
    cfg = config(weights, n=240, seed=11, shard_size=10)
    summary = run_pipeline(
        cfg, db=db, name="k", progress=False, executor=DaskExecutor(client, on_result=kill_one_worker)
    )
    assert killed
    got = stored(db, summary.run_id)
    assert len(np.unique(got.pair_index)) == len(got.pair_index) == summary.n_pairs == summary.stored
    # the same pairs as computing every shard here, once
    model = load_vin(weights, size=SIZE)
    expected = [compute_shard(cfg, k, model) for k in range(cfg.n_shards)]
    assert np.array_equal(np.sort(got.pair_index), np.concatenate([r.pair_index for r in expected]))
    client.wait_for_workers(2, timeout=60)
    assert killed[0] not in set(client.run(os.getpid).values())


def test_a_shard_delivered_twice_is_stored_once(weights, tmp_path):
    cfg = config(weights, n=40)

    class Twice(LocalExecutor):
        """A remote executor's worst case: every result delivered twice."""

        remote = True

        def map(self, task, chunks, *, ordered=True):
            for chunk in chunks:
                result = task(chunk)
                yield result
                yield result

    db = f"sqlite:///{tmp_path / 'twice.db'}"
    summary = run_pipeline(cfg, db=db, progress=False, executor=Twice())
    got = stored(db, summary.run_id)
    assert summary.stored == len(got) == summary.n_pairs // 2
    assert len(np.unique(got.pair_index)) == len(got)


@pytest.mark.slow
@pytest.mark.parametrize("strategy, obstacles", [("near-path", 1), ("random", 1), ("key-points", 1), ("random", 3)])
def test_attack_on_the_cluster_writes_the_same_pairs_file(weights, cluster, tmp_path, strategy, obstacles):
    local, _ = cluster
    maps = tmp_path / "maps.npz"
    assert (
        main(
            [
                "maps",
                "generate",
                "--n",
                "45",
                "--size",
                str(SIZE),
                "--starts",
                "1",
                "--out",
                str(maps),
                "--seed",
                "5",
                "--quiet",
            ]
        )
        == 0
    )
    args = [
        "attack",
        "--maps",
        str(maps),
        "--strategy",
        strategy,
        "--weights",
        weights,
        "--per-map",
        "2",
        "--seed",
        "3",
        "--obstacles",
        str(obstacles),
        "--quiet",
    ]
    assert main([*args, "--out", str(tmp_path / "local.npz")]) == 0
    # uneven shards (45 = 16 + 16 + 13): the random stream must continue across shard boundaries
    assert (
        main(
            [*args, "--out", str(tmp_path / "cluster.npz"), "--cluster", local.scheduler_address, "--shard-size", "16"]
        )
        == 0
    )
    a, b = PairSet.load(tmp_path / "local.npz"), PairSet.load(tmp_path / "cluster.npz")
    assert len(a) == len(b) > 40 and a.n_added == obstacles
    for name in ("obstacles_o", "obstacles_a", "starts", "goals", "added", "map_index", "term_o", "term_a"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.path_o == b.path_o and a.path_a == b.path_a
    assert (a.strategy, a.params, a.corner_cutting) == (b.strategy, b.params, b.corner_cutting)


@pytest.mark.slow
def test_identify_on_the_cluster_stores_the_same_labels(weights, cluster, tmp_path):
    local, _ = cluster
    _, pairs = generate_and_attack(tmp_path, weights, n=50, size=SIZE, strategy="key-points")
    other = tmp_path / "other.pt"
    save_vin(planning_vin(SIZE, seed=3, noise=0.3), other)  # re-plan with another planner on the workers
    for db, extra in (("a.db", []), ("b.db", ["--cluster", local.scheduler_address, "--shard-size", "7"])):
        assert (
            main(
                [
                    "identify",
                    "--pairs",
                    str(pairs),
                    "--db",
                    str(tmp_path / db),
                    "--weights",
                    str(other),
                    "--quiet",
                    *extra,
                ]
            )
            == 0
        )
    with Store.open(str(tmp_path / "a.db")) as a, Store.open(str(tmp_path / "b.db")) as b:
        assert a.read_pairs(a.list_runs()[0]["id"]).equals(b.read_pairs(b.list_runs()[0]["id"]))


def test_workers_without_dask_says_how_to_install_it(weights, tmp_path, monkeypatch, capsys):
    real_import = builtins.__import__

    def no_distributed(name, *args, **kwargs):
        if name == "distributed" or name.startswith("distributed."):
            raise ImportError("No module named 'distributed'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_distributed)
    assert (
        main(
            [
                "run",
                "--n",
                "5",
                "--size",
                str(SIZE),
                "--weights",
                weights,
                "--db",
                str(tmp_path / "x.db"),
                "--workers",
                "2",
                "--quiet",
            ]
        )
        == 2
    )
    assert "pip install 'vinadv[cluster]'" in capsys.readouterr().err


def test_bad_cluster_options_exit_2(weights, tmp_path, capsys):
    base = ["run", "--n", "5", "--size", str(SIZE), "--weights", weights, "--db", str(tmp_path / "x.db"), "--quiet"]
    assert main([*base, "--workers", "0"]) == 2
    assert "--workers must be >= 1, got 0" in capsys.readouterr().err
    assert main([*base, "--cluster", "tcp://127.0.0.1:1"]) == 2
    assert "cannot connect" in capsys.readouterr().err


@pytest.mark.slow
def test_a_search_planner_on_a_maps_file_runs_on_the_cluster_as_locally(cluster, tmp_path):
    """The Dask path with a bring-your-own search planner (workers load the file by its spec, checksummed) and a
    maps file (workers read it by path, checksummed): the same stored pairs as the local run."""

    _, client = cluster
    spec = f"{Path(__file__).resolve().parents[2] / 'examples' / 'my_search_planner.py'}:make"
    maps = tmp_path / "m.npz"
    generate_maps(30, SIZE, seed=5, n_starts=2).save(maps)
    settings = RunConfig(**maps_file_config(str(maps)), attack="key-points", seed=3, shard_size=10, planner=spec)
    local_db, cluster_db = f"sqlite:///{tmp_path / 'local.db'}", f"sqlite:///{tmp_path / 'cluster.db'}"
    local = run_pipeline(settings, db=local_db, name="s", progress=False)
    on_cluster = run_pipeline(settings, db=cluster_db, name="s", progress=False, executor=DaskExecutor(client))
    assert on_cluster.stored == local.stored == 30
    a, b = stored(local_db, local.run_id), stored(cluster_db, on_cluster.run_id)
    assert np.array_equal(a.pair_index, b.pair_index) and a.equals(b)


def tiny_bench_suite():
    attacks = (AttackGroup(("random", "key-points"), "add", 2), AttackGroup(("random",), "remove", 1))
    return heldout_suite("tiny-cluster", 12, SIZE, attacks, budget=3, chunk=4)


@pytest.mark.slow
def test_bench_run_on_the_cluster_gives_the_local_entry(weights, cluster, tmp_path, monkeypatch):
    """`vinadv bench run --cluster`: the chunks on the workers (in any order), stored and resumed by the client, give
    the local run's entry byte for byte but for time and machine; through the command line too."""
    local_cluster, client = cluster
    suite = tiny_bench_suite()
    planner = load_planner("vin", SIZE, weights=weights)
    local = entry_json(deterministic_part(run_bench(suite, planner)))
    ref = PlannerRef.of(planner, "vin", weights, True)
    db = f"sqlite:///{tmp_path / 'b.db'}"
    on_cluster = run_bench(suite, planner, db=db, executor=DaskExecutor(client), planner_ref=ref)
    assert entry_json(deterministic_part(on_cluster)) == local
    assert entry_json(deterministic_part(run_bench(suite, planner, db=db, resume=True))) == local  # all stored
    monkeypatch.setitem(suites.SUITES, suite.name, suite)  # the workers get the suite by value, not by name
    out = tmp_path / "e.json"
    argv = ["bench", "run", "--suite", suite.name, "--weights", weights, "--out", str(out), "--quiet"]
    assert main([*argv, "--cluster", local_cluster.scheduler_address]) == 0
    assert entry_json(deterministic_part(json.loads(out.read_text()))) == local


def test_bench_run_refuses_bad_cluster_options_in_one_line(tmp_path, capsys):
    base = ["bench", "run", "--suite", "vin28-quick-v1", "--planner", "optimal", "--out", str(tmp_path / "e.json")]
    assert main([*base, "--cluster", "tcp://127.0.0.1:1"]) == 2
    assert "cannot connect" in capsys.readouterr().err
    assert main([*base, "--workers", "0"]) == 2
    assert "--workers must be >= 1, got 0" in capsys.readouterr().err
    assert not (tmp_path / "e.json").exists()


@pytest.mark.slow
def test_the_dask_executor_maps_a_task_as_the_local_one(cluster):
    _, client = cluster
    executor = DaskExecutor(client, window=2)
    chunks = list(range(9))
    assert list(executor.map(abs, [-c for c in chunks])) == list(LOCAL.map(abs, [-c for c in chunks])) == chunks
    assert sorted(executor.map(abs, chunks, ordered=False)) == chunks
    assert executor.bounds(5, 2) == [(0, 2), (2, 4), (4, 5)] and LOCAL.bounds(5, 2) == [(0, 5)]


@pytest.mark.slow
def test_the_attack_job_on_the_dask_executor_makes_the_local_pairs(weights, cluster, tmp_path):
    from vinadv.jobs.attack import AttackConfig, run  # noqa: PLC0415 (the job under test)

    _, client = cluster
    generate_maps(25, SIZE, seed=4, n_starts=1).save(tmp_path / "m.npz")
    config = AttackConfig(str(tmp_path / "m.npz"), "random", per_map=2, seed=1, weights=weights, shard_size=7)
    local, remote = run(config), run(config, DaskExecutor(client))
    assert local.to_dict() | {"seconds": 0} == remote.to_dict() | {"seconds": 0}
    assert np.array_equal(local.pairs.added, remote.pairs.added) and local.pairs.path_a == remote.pairs.path_a
