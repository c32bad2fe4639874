"""The main job end to end: maps -> attack -> identify -> store, on every database backend."""

import json
import os
import signal
import sys
import time

import numpy as np
import pytest
import sqlalchemy as sa

from tests.classify.oracle import rule_oracle
from tests.classify.test_harm import optimal_path, path_cost
from tests.cli_files import command_line, generate_and_attack
from tests.fault_files import killed_at_exit
from tests.planner_files import EXITING, NO_PARAMETERS
from vinadv.attacks.pairs import PairSet
from vinadv.attacks.strategies import make_attack
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.executor import LocalExecutor
from vinadv.grid import generate_maps
from vinadv.grid.mapset import MapSet
from vinadv.identify import objective_strength
from vinadv.pipeline import RunConfig, compute_shard, maps_file_config, run, run_pipeline, shard_maps
from vinadv.planners.interface import EMPTY_SHA256
from vinadv.planners.vin.weights import load_vin
from vinadv.records import VERSION_KEY
from vinadv.store import Store

SIZE = 12


@pytest.fixture(scope="module")
def weights(planning_weights):
    return planning_weights(SIZE)


def config(weights, **kw):
    defaults = dict(n=60, size=SIZE, attack="near-path", seed=4, shard_size=25, weights=weights)
    return RunConfig(**{**defaults, **kw})


def test_same_run_reads_back_identical_on_every_backend(weights, sqlite_url, mysql_url, postgres_url):
    stored = []
    for url in (sqlite_url, mysql_url, postgres_url):
        summary = run_pipeline(config(weights), db=url, name="x", progress=False)
        assert summary.stored == summary.n_pairs > 0
        with Store.open(url) as store:
            stored.append(store.read_pairs(summary.run_id))
            assert store.label_counts(summary.run_id) == summary.counts
    assert stored[0].equals(stored[1]) and stored[0].equals(stored[2])


@pytest.mark.slow
def test_stored_labels_agree_with_an_independent_recomputation(weights, sqlite_url):
    summary = run_pipeline(config(weights, attack="key-points"), db=sqlite_url, progress=False)
    engine = sa.create_engine(sqlite_url)
    with engine.connect() as conn:
        query = "SELECT path_o, path_a, goal, label, attack, dh, dv FROM map_pairs WHERE run_id = :r"
        rows = conn.execute(sa.text(query), {"r": summary.run_id}).all()
    assert len(rows) == summary.n_pairs
    seen = set()
    for path_o, path_a, goal, label, attack, dh, dv in rows:
        parse = lambda text: [tuple(int(v) for v in cell.split(",")) for cell in text.split(";")]  # noqa: E731
        expected, exp_dh, exp_dv = rule_oracle(parse(path_o), parse(path_a), parse(goal)[0], round(4 * SIZE / 28))
        assert label == expected
        if label in ("DP", "FP"):
            assert (dh, dv) == (exp_dh, exp_dv)
        else:
            assert dh is None and dv is None
        assert bool(attack) == (expected in ("UrP", "FP"))
        seen.add(label)
    assert len(seen) >= 3  # the run is not trivially one category


def test_stored_harm_agrees_with_an_independent_recomputation(weights, sqlite_url):
    summary = run_pipeline(config(weights, attack="key-points", per_map=2), db=sqlite_url, progress=False).to_dict()
    engine = sa.create_engine(sqlite_url)
    with engine.connect() as conn:
        rows = conn.execute(
            sa.text(
                "SELECT map_o, map_a, start, goal, path_o, path_a, label, opt_cost_o, opt_cost_a, cost_o, cost_a, "
                "regret_o, regret_a, expert_label, harm FROM map_pairs WHERE run_id = :r"
            ),
            {"r": summary["run_id"]},
        ).all()
    engine.dispose()
    parse = lambda text: [tuple(int(v) for v in cell.split(",")) for cell in text.split(";")]  # noqa: E731
    grid = lambda text: [[ch == "1" for ch in row] for row in text.split(";")]  # noqa: E731
    close = lambda a, b: (a is None and b is None) or (a is not None and b is not None and abs(a - b) < 1e-9)  # noqa: E731
    table = {}
    for map_o, map_a, start, goal, path_o, path_a, label, *stored in rows:
        start, goal, path_o, path_a = parse(start)[0], parse(goal)[0], parse(path_o), parse(path_a)
        expert_o, expert_a = optimal_path(grid(map_o), start, goal, True), optimal_path(grid(map_a), start, goal, True)
        opt_o, opt_a = path_cost(expert_o), path_cost(expert_a)
        cost_o = path_cost(path_o) if path_o[-1] == goal else None
        cost_a = path_cost(path_a) if path_a[-1] == goal else None
        regret_o = None if cost_o is None else cost_o - opt_o
        regret_a = None if cost_a is None else cost_a - opt_a
        for got, want in zip(stored[:6], (opt_o, opt_a, cost_o, cost_a, regret_o, regret_a)):
            assert close(got, want)
        assert stored[6] == rule_oracle(expert_o, expert_a, goal, round(4 * SIZE / 28))[0]
        if label == "invalid":
            harm = "invalid"
        else:
            harm = "harmful" if label == "UrP" or regret_a > regret_o + 1e-6 else "harmless"
        assert stored[7] == harm
        table.setdefault(label, {}).setdefault(harm, 0)
        table[label][harm] += 1
    assert {
        k: {h: n for h, n in row.items() if n} for k, row in summary["label_x_harm"].items() if any(row.values())
    } == table
    valid = sum(n for label, row in table.items() if label != "invalid" for n in row.values())
    harmful = sum(row.get("harmful", 0) for row in table.values())
    assert summary["harmful"] == harmful and summary["harmful_rate"] == pytest.approx(harmful / valid)
    assert {h for row in table.values() for h in row} >= {"harmful", "harmless"}


def test_result_does_not_depend_on_the_order_shards_finish(weights, sqlite_url, tmp_path):
    class Reversed(LocalExecutor):
        """An executor whose shards finish last first."""

        remote = True

        def map(self, task, chunks, *, ordered=True):
            return iter([task(chunk) for chunk in reversed(list(chunks))])

    other = f"sqlite:///{tmp_path / 'other.db'}"
    a = run_pipeline(config(weights), db=sqlite_url, progress=False)
    b = run(config(weights), Reversed(), db=other)
    with Store.open(sqlite_url) as s1, Store.open(other) as s2:
        assert s1.read_pairs(a.run_id).equals(s2.read_pairs(b.run_id))


#: maps of the killed run
N_KILLED = 1200


@pytest.mark.slow
def test_killed_run_resumes_with_every_pair_exactly_once(weights, tmp_path):
    db = f"sqlite:///{tmp_path / 'kill.db'}"
    # many small shards, polled often: the run must still be going when the first shard is seen stored (60 shards:
    # the run goes on for about a second after its first, which the poll sees within milliseconds; the resumed and
    # the clean run redo most of them in this process, so more maps cost the suite twice)
    common = command_line("run", n=N_KILLED, size=SIZE, shard_size=20, weights=weights, seed=9)
    args = [*common, "--db", db, "--name", "k", "--quiet"]
    argv = [sys.executable, "-m", "vinadv.cli", *args]
    engine = sa.create_engine(db)
    with killed_at_exit(argv, env={**os.environ, "PYTHONUNBUFFERED": "1"}) as proc:
        deadline = time.time() + 120
        count = 0
        while time.time() < deadline and proc.poll() is None:
            time.sleep(0.01)
            try:
                with engine.connect() as conn:
                    count = conn.execute(sa.text("SELECT COUNT(*) FROM map_pairs")).scalar()
            except sa.exc.OperationalError:
                continue
            if count > 0:
                break
        assert proc.poll() is None, "the run finished before it could be killed; make it longer"
    with engine.connect() as conn:
        partial = conn.execute(sa.text("SELECT COUNT(*) FROM map_pairs")).scalar()
    assert 0 < partial < N_KILLED
    assert main([*args, "--resume"]) == 0
    clean_db = f"sqlite:///{tmp_path / 'clean.db'}"
    assert main([*common, "--db", clean_db, "--quiet"]) == 0
    with Store.open(db) as resumed, Store.open(clean_db) as clean:
        rid = resumed.find_run("k")
        got = resumed.read_pairs(rid)
        assert len(np.unique(got.pair_index)) == len(got.pair_index)
        assert got.equals(clean.read_pairs(clean.list_runs()[0]["id"]))


def test_resume_refuses_other_settings(weights, sqlite_url, capsys):
    run_pipeline(config(weights), db=sqlite_url, name="r", progress=False)
    args = command_line("run", n=60, size=SIZE, weights=weights, db=sqlite_url, name="r", seed=5, shard_size=25)
    assert main([*args, "--resume", "--quiet"]) == 2
    assert "other settings (seed)" in capsys.readouterr().err


def test_bad_inputs_exit_2_and_leave_data_untouched(weights, sqlite_url, tmp_path, capsys):
    summary = run_pipeline(config(weights), db=sqlite_url, progress=False)
    with Store.open(sqlite_url) as store:
        before = store.read_pairs(summary.run_id)
    bad = tmp_path / "bad.npz"
    np.savez(bad, format=np.array("vinadv.pairs/1"), obstacles_o=np.zeros((2, 5, 5), bool))
    assert main(["identify", "--pairs", str(bad), "--db", sqlite_url, "--quiet"]) == 2
    assert "bad.npz: field 'obstacles_a' is missing" in capsys.readouterr().err
    assert (
        main(
            [
                "run",
                "--n",
                "5",
                "--db",
                "mysql+pymysql://root@127.0.0.1:1/none",
                "--weights",
                weights,
                "--size",
                str(SIZE),
                "--quiet",
            ]
        )
        == 2
    )
    assert "cannot connect" in capsys.readouterr().err
    other = tmp_path / "other.db"
    sa_engine = sa.create_engine(f"sqlite:///{other}")
    with sa_engine.begin() as conn:
        conn.execute(sa.text("CREATE TABLE map_pairs (x INTEGER)"))
    assert main(["run", "--n", "5", "--db", str(other), "--weights", weights, "--size", str(SIZE), "--quiet"]) == 2
    with Store.open(sqlite_url) as store:
        assert store.read_pairs(summary.run_id).equals(before)


def test_attack_and_identify_commands(weights, tmp_path, sqlite_url, capsys):
    _, pairs = generate_and_attack(tmp_path, weights, n=30, size=SIZE, strategy="key-points", options=("--json",))
    summary = json.loads(capsys.readouterr().out)
    assert summary["pairs"] == sum(summary["counts"].values())
    assert main(["identify", "--pairs", str(pairs), "--db", sqlite_url, "--json"]) == 0
    ident = json.loads(capsys.readouterr().out)
    assert ident["counts"] == summary["counts"]
    assert ident["label_x_harm"] == summary["label_x_harm"] and ident["harmful_rate"] == summary["harmful_rate"]
    assert sum(ident["harm_counts"].values()) == ident["pairs"]
    assert main(["identify", "--pairs", str(pairs), "--db", sqlite_url, "--harm-tolerance", "-1"]) == 2
    assert "--harm-tolerance" in capsys.readouterr().err
    # a tolerance above every regret: no pair is harmful but for UrP
    assert main(["identify", "--pairs", str(pairs), "--db", sqlite_url, "--harm-tolerance", "1000", "--json"]) == 0
    loose = json.loads(capsys.readouterr().out)
    assert loose["harmful"] == summary["counts"]["UrP"]
    assert main(["identify", "--pairs", str(pairs), "--db", sqlite_url, "--weights", weights, "--quiet"]) == 0


def test_run_of_several_obstacles_stores_every_added_cell_and_resume_compares_it(weights, sqlite_url, tmp_path, capsys):
    summary = run_pipeline(
        config(weights, n=30, attack="key-points", obstacles=2), db=sqlite_url, name="k2", progress=False
    )
    with Store.open(sqlite_url) as store:
        got = store.read_pairs(summary.run_id)
        assert store.run_info(summary.run_id)["config"]["obstacles"] == 2
    # the shards' own attacks, made again here: the stored pairs hold both cells of each
    model = load_vin(weights, size=SIZE)
    expected = []
    for shard, lo in enumerate((0, 25)):
        maps = generate_maps(min(25, 30 - lo), SIZE, seed=(4, shard), n_starts=1)
        pairs = (
            make_attack("key-points", seed=(4, shard), obstacles=2)
            .attack(maps.obstacles, maps.starts[:, 0], maps.goals, model, strength=objective_strength("paper"))
            .pairs
        )
        expected.append(pairs.added)
    assert got.added.shape == (summary.n_pairs, 2, 2) and np.array_equal(got.added, np.concatenate(expected))
    args = command_line(
        "run", n=30, size=SIZE, weights=weights, db=sqlite_url, name="k2", attack="key-points", seed=4, shard_size=25
    )
    assert main([*args, "--resume", "--quiet", "--obstacles", "3"]) == 2
    assert "other settings (obstacles)" in capsys.readouterr().err
    assert main([*args, "--resume", "--quiet", "--obstacles", "2"]) == 0
    assert main([*args, "--obstacles", "0"]) == 2
    assert "--obstacles must be >= 1" in capsys.readouterr().err


def test_a_run_stored_before_several_obstacles_resumes_as_one_obstacle(weights, sqlite_url):
    summary = run_pipeline(config(weights, n=30), db=sqlite_url, name="old", progress=False)
    with Store.open(sqlite_url) as store:
        stored = store.run_info(summary.run_id)["config"]
    stored.pop("obstacles")
    stored.pop(VERSION_KEY)
    engine = sa.create_engine(sqlite_url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:  # a config of version 0 (`vinadv.records`) of a one-obstacle run: no "obstacles"
        conn.execute(
            sa.text("UPDATE runs SET config = :c WHERE id = :i"), {"c": json.dumps(stored), "i": summary.run_id}
        )
    engine.dispose()
    again = run_pipeline(config(weights, n=30), db=sqlite_url, name="old", resume=True, progress=False)
    assert again.run_id == summary.run_id and again.stored == 0


def test_attack_and_identify_keep_every_added_obstacle(weights, tmp_path, sqlite_url, capsys):
    maps, pairs = generate_and_attack(
        tmp_path, weights, n=20, size=SIZE, strategy="near-path", options=("--obstacles", "3", "--quiet")
    )
    capsys.readouterr()  # the attack's summary
    made = PairSet.load(pairs)
    assert made.added.shape == (len(made), 3, 2) and made.params["obstacles"] == 3
    assert main(["identify", "--pairs", str(pairs), "--db", sqlite_url, "--weights", weights, "--json"]) == 0
    run_id = json.loads(capsys.readouterr().out)["run_id"]
    with Store.open(sqlite_url) as store:
        stored = store.read_pairs(run_id)
    assert np.array_equal(stored.added, made.added) and np.array_equal(stored.obstacles_a, made.obstacles_a)
    assert (
        main(
            [
                "attack",
                "--maps",
                str(maps),
                "--strategy",
                "random",
                "--obstacles",
                "0",
                "--out",
                str(pairs),
                "--weights",
                weights,
            ]
        )
        == 2
    )
    assert "--obstacles must be >= 1" in capsys.readouterr().err


def test_a_planner_without_weights_is_stored_without_a_checksum_and_old_runs_resume(tmp_path, db_url):
    (tmp_path / "none.py").write_text(NO_PARAMETERS)
    settings = RunConfig(n=4, size=8, seed=1, shard_size=2, planner=f"{tmp_path / 'none.py'}:make")
    summary = run_pipeline(settings, db=db_url, name="no weights", progress=False)
    with Store.open(db_url) as store:
        info = store.run_info(summary.run_id)
    assert info["weights_checksum"] is None and info["config"]["planner_spec"]["weights_sha256"] is None
    # a run an older vinadv stored recorded the SHA-256 of no bytes: it is the same planner, and resumes
    engine = sa.create_engine(db_url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        conn.execute(sa.text("UPDATE runs SET weights_checksum = :c"), {"c": EMPTY_SHA256})
    engine.dispose()
    again = run_pipeline(settings, db=db_url, name="no weights", resume=True, progress=False)
    assert again.run_id == summary.run_id and again.stored == 0


def test_resume_refuses_a_planner_file_edited_since(tmp_path, db_url, capsys):
    planner = tmp_path / "none.py"
    planner.write_text(NO_PARAMETERS)
    run = ["run", "--n", "4", "--size", "8", "--shard-size", "2", "--planner", f"{planner}:make", "--db", db_url]
    assert main([*run, "--name", "mine", "--quiet"]) == 0
    capsys.readouterr()
    planner.write_text(NO_PARAMETERS + "\n# edited: the planner may plan otherwise now\n")
    assert main([*run, "--name", "mine", "--resume", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("vinadv: error: --resume: run 'mine' was made with another source of --planner")
    assert len(err.strip().splitlines()) == 1
    planner.write_text(NO_PARAMETERS)  # the file as it was: the run resumes
    assert main([*run, "--name", "mine", "--resume", "--quiet"]) == 0


# a run of two shards that is stopped in its second (the first is stored): Ctrl-C, SIGTERM, a planner that exits
STOPPED = ["run", "--n", "4", "--size", "8", "--shard-size", "2", "--planner", "optimal", "--name", "k", "--quiet"]


def stop_in_second_shard(monkeypatch, stop):
    """Make `vinadv run` call `stop()` when it starts computing shard 1."""

    def stopping(config, shard, *args, **kw):
        if shard == 1:
            stop()
        return compute_shard(config, shard, *args, **kw)

    monkeypatch.setattr("vinadv.pipeline.compute_shard", stopping)


def run_status(url: str) -> str:
    with Store.open(url, readonly=True) as store:
        (run,) = store.list_runs(with_counts=False)
    return run["status"]


def test_ctrl_c_marks_the_run_interrupted_and_says_how_to_resume(db_url, monkeypatch, capsys):
    def ctrl_c():
        raise KeyboardInterrupt

    stop_in_second_shard(monkeypatch, ctrl_c)
    assert main([*STOPPED, "--db", db_url]) == 130
    err = capsys.readouterr().err
    assert err.startswith("vinadv: interrupted: run 1 stopped with ") and len(err.strip().splitlines()) == 1
    assert err.strip().endswith("pairs stored this time: resume it with the same options and --name k --resume")
    assert run_status(db_url) == "interrupted"
    monkeypatch.undo()
    assert main([*STOPPED, "--db", db_url, "--resume", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["skipped_shards"] == 1
    assert run_status(db_url) == "done"


# a run of three shards, every setting but the name and database other than the defaults
MADE = ["run", "--n", "6", "--size", "8", "--shard-size", "2", "--planner", "optimal", "--seed", "3", "--name", "k"]
#: what a summary says of this time only: the time, the pairs written and shards skipped, the planner calls
THIS_TIME = {"seconds", "wall_seconds", "pairs_per_second", "stored", "skipped_shards", "planner_calls"}


def whole_run(summary: dict) -> dict:
    return {k: v for k, v in summary.items() if k not in {*THIS_TIME, "planner_calls_per_success", "db"}}


def test_resume_with_the_name_alone_finishes_the_run_and_sums_it_up_whole(tmp_path, monkeypatch, capsys):
    db, clean_db = f"sqlite:///{tmp_path / 'k.db'}", f"sqlite:///{tmp_path / 'clean.db'}"
    stop_in_second_shard(monkeypatch, lambda: (_ for _ in ()).throw(KeyboardInterrupt))
    assert main([*MADE, "--db", db, "--quiet"]) == 130
    monkeypatch.undo()
    capsys.readouterr()
    assert main(["run", "--db", db, "--name", "k", "--resume", "--json"]) == 0
    resumed = json.loads(capsys.readouterr().out)
    assert main([*MADE, "--db", clean_db, "--json"]) == 0
    clean = json.loads(capsys.readouterr().out)
    assert resumed["skipped_shards"] == 1 and resumed["pairs"] > resumed["stored"] > 0
    assert whole_run(resumed) == whole_run(clean)  # every shard's pairs, not only this time's
    with Store.open(db) as a, Store.open(clean_db) as b:
        assert a.read_pairs(a.find_run("k")).equals(b.read_pairs(b.find_run("k")))


def test_resume_by_name_refuses_a_given_option_that_differs_naming_it(sqlite_url, capsys):
    assert main([*MADE, "--db", sqlite_url, "--quiet"]) == 0
    resume = ["run", "--db", sqlite_url, "--name", "k", "--resume", "--quiet"]
    assert main([*resume, "--seed", "5"]) == 2
    assert "was made with other settings (seed); use the same options" in capsys.readouterr().err
    assert main([*resume, "--size", "8", "--seed", "3", "--planner", "optimal"]) == 0  # options that agree: taken
    assert main(["run", "--db", sqlite_url, "--resume", "--quiet"]) == 2  # without --name: refused, as before
    assert capsys.readouterr().err.strip() == "vinadv: error: --resume needs --name (the run to resume)"


def test_resuming_a_finished_run_prints_its_totals(sqlite_url, capsys):
    assert main([*MADE, "--db", sqlite_url]) == 0
    first = capsys.readouterr().out
    with Store.open(sqlite_url) as store:
        timings = store.run_info(store.find_run("k"))["timings"]
    assert main([*MADE, "--db", sqlite_url, "--resume"]) == 0  # all the options: the totals alone are tested here
    again = capsys.readouterr().out
    assert "resumed: 3 complete shards skipped" in again

    def totals(text: str) -> list[str]:
        return [line for line in text.splitlines() if not line.startswith(("run ", "resumed:", "time per stage"))]

    assert totals(again) == totals(first) and "n/a" not in first
    assert first.splitlines()[0].split(" on planner")[0] == again.splitlines()[0].split(" on planner")[0]
    with Store.open(sqlite_url) as store:
        assert store.run_info(store.find_run("k"))["timings"] == timings  # nothing computed: the run's timings stay


def test_sigterm_marks_the_run_interrupted_and_exits_143(sqlite_url, monkeypatch, capsys):
    class Unhandled(Exception):
        pass

    def unhandled(signum, frame):  # what the test's own process does with a SIGTERM vinadv does not handle
        raise Unhandled

    previous = signal.signal(signal.SIGTERM, unhandled)
    try:
        stop_in_second_shard(monkeypatch, lambda: os.kill(os.getpid(), signal.SIGTERM))
        assert main([*STOPPED, "--db", sqlite_url]) == 143
        assert signal.getsignal(signal.SIGTERM) is unhandled  # the command gave the handler back
    finally:
        signal.signal(signal.SIGTERM, previous)
    err = capsys.readouterr().err
    assert err.startswith("vinadv: terminated: run 1 stopped with ") and err.strip().endswith("--name k --resume")
    assert run_status(sqlite_url) == "interrupted"


def test_a_planner_that_exits_is_one_line_and_the_run_is_marked_failed(tmp_path, db_url, capsys):
    (tmp_path / "exits.py").write_text(EXITING)
    planner = f"{tmp_path / 'exits.py'}:make"
    run = ["run", "--n", "2", "--size", "8", "--planner", planner, "--name", "x", "--db", db_url, "--quiet"]
    assert main(run) == 2
    line = f"vinadv: error: planner {planner!r}: forward failed: SystemExit: 0; run 1 marked failed"
    assert capsys.readouterr().err.strip() == line
    assert run_status(db_url) == "failed"
    maps = tmp_path / "m.npz"
    generate_maps(1, 8, seed=1, n_starts=1).save(maps)
    assert main(["plan", "--maps", str(maps), "--planner", planner, "--out", str(tmp_path / "p.npz"), "--quiet"]) == 2
    assert capsys.readouterr().err.strip() == f"vinadv: error: planner {planner!r}: forward failed: SystemExit: 0"


@pytest.mark.parametrize("moves", ["moore", "news"])
def test_a_run_follows_its_movement_model_from_maps_to_the_stored_harm(moves, sqlite_url):
    """`--moves`: the maps, the expert costs, the harm and the run row are the model's; `optimal` is never harmful;
    the stored optimal costs match a plain-Python Dijkstra of the model (tests.classify.test_harm)."""
    kw = dict(n=16, size=9, seed=2, shard_size=8, planner="optimal", attack="random", per_map=3, moves=moves)
    summary = run_pipeline(RunConfig(**kw), db=sqlite_url, name=f"r-{moves}", progress=False)
    assert summary.n_pairs > 0
    with Store.open(sqlite_url) as store:
        info = store.run_info(summary.run_id)
        records = store.read_pairs(summary.run_id)
    assert info["moves"] == moves and info["config"]["moves"] == moves
    assert set(records.harm) <= {"harmless", "invalid"}  # the control is never harmful
    for i in range(len(records)):
        start, goal = tuple(records.starts[i]), tuple(records.goals[i])
        for obstacles, stored in (
            (records.obstacles_o[i], records.opt_cost_o[i]),
            (records.obstacles_a[i], records.opt_cost_a[i]),
        ):
            expert = optimal_path(obstacles.tolist(), start, goal, True, moves)
            assert stored == pytest.approx(path_cost(expert, moves), abs=1e-9)
    # the same settings resume it; every run's config holds its moves, as `runs.moves` does
    again = run_pipeline(RunConfig(**kw), db=sqlite_url, name=f"r-{moves}", resume=True, progress=False)
    assert again.skipped_shards == 2
    octile = run_pipeline(RunConfig(**{**kw, "moves": "octile", "n": 2}), db=sqlite_url, progress=False)
    with Store.open(sqlite_url) as store:
        assert store.run_info(octile.run_id)["config"]["moves"] == "octile"
        assert store.run_moves(octile.run_id) == "octile"


def test_a_planner_of_another_model_is_refused_before_the_run_is_made(sqlite_url, capsys):
    line = ["run", "--n", "2", "--size", "28", "--moves", "moore", "--db", sqlite_url, "--quiet"]
    assert main(line) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "plans octile moves" in err and "'moore'" in err
    assert not os.path.exists(sqlite_url.removeprefix("sqlite:///"))  # refused before the database was made


def test_a_maps_file_run_takes_the_file_s_maps_in_shards_and_refuses_a_changed_file(tmp_path):
    """`maps_file_config` + `compute_shard`: shard k holds the file's maps k * shard_size .., first start each (the
    oracle: the file's own arrays); a file changed under the recorded path is refused by its checksum."""
    path = tmp_path / "m.npz"
    generate_maps(7, 8, seed=2, n_starts=3).save(path)
    config = RunConfig(**maps_file_config(str(path)), planner="optimal", shard_size=3)
    assert (config.n, config.size, config.n_shards) == (7, 8, 3)
    assert config.to_dict()["maps_sha256"] == config.maps_sha256 and RunConfig().to_dict()["maps"] is None
    maps = MapSet.load(path)
    last = shard_maps(config, 2)
    assert len(last) == 1 and np.array_equal(last.obstacles, maps.obstacles[6:])
    assert np.array_equal(last.starts[:, 0], maps.starts[6:, 0]) and last.n_starts == 1
    assert last.expert[0].tolist() == maps.expert_path(6, 0).tolist()
    generate_maps(7, 8, seed=3, n_starts=3).save(tmp_path / "other.npz")
    changed = RunConfig(**{**config.to_dict(), "maps": str(tmp_path / "other.npz")})
    with pytest.raises(InputError, match="its SHA-256 is not the one the run recorded"):
        shard_maps(changed, 0)


def test_a_maps_file_of_another_model_runs_as_that_model(tmp_path, sqlite_url):
    """`--maps FILE` takes the file's movement model (a moore MP import, say): the config, the shards' maps and the
    stored run are the file's model; `--moves` beside `--maps` is refused (the file says it)."""
    path = tmp_path / "moore.npz"
    generate_maps(4, 8, seed=2, n_starts=2, moves="moore").save(path)
    config = RunConfig(**maps_file_config(str(path)), planner="optimal", attack="random", shard_size=2)
    assert config.moves == "moore" and shard_maps(config, 1).moves == "moore"
    summary = run_pipeline(config, db=sqlite_url, progress=False)
    with Store.open(sqlite_url) as store:
        assert store.run_moves(summary.run_id) == "moore"
    line = ["run", "--maps", str(path), "--planner", "optimal", "--db", sqlite_url, "--quiet"]
    assert main([*line, "--moves", "moore"]) == 2
