"""`vinadv robustness`: the worst-case figures against a plain-Python computation from the attacks' own pairs, the
exhaustive harmful rate against a brute-force search of every cell, the optimal control, determinism, the command."""

from __future__ import annotations

import json
import math
import re
import sqlite3

import numpy as np
import pytest

from tests.classify.oracle import rule_oracle
from tests.classify.test_harm import optimal_path, path_cost
from vinadv import checksums
from vinadv.attacks.strategies import make_attack
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.identify import objective_strength
from vinadv.intervals import rate_interval
from vinadv.planners.registry import load_planner
from vinadv.planners.vin.reference import plan_reference
from vinadv.planners.vin.weights import save_vin
from vinadv.robustness import (
    MapOutcomes,
    check_strategies,
    heldout_maps,
    robustness,
    worst_case,
)
from vinadv.store import Store
from vinadv.testing.planners import planning_vin

SIZE = 10
TOL = 1e-6
T = round(4 * SIZE / 28)
#: maps of the exhaustive oracle test (the first three: harmed and unharmed ones among them, as it asserts; each
#: costs a planner call per cell)
EXHAUSTIVE_MAPS = 3


@pytest.fixture(scope="module")
def model():
    return planning_vin(SIZE, seed=1, noise=0.1)


@pytest.fixture(scope="module")
def maps():
    return heldout_maps(14, SIZE, seed=5)


@pytest.fixture(scope="module")
def weights(tmp_path_factory, model):
    path = tmp_path_factory.mktemp("w") / f"vin{SIZE}.pt"
    save_vin(model, path)
    return str(path)


def _verdict(obstacles_o, obstacles_a, start, goal, path_o, path_a):
    """(label, harmful, regret_a or None) of one pair, from DESIGN.md in plain Python."""
    label = rule_oracle(path_o, path_a, goal, T)[0]
    if label == "invalid":
        return label, False, None
    if label == "UrP":
        return label, True, None
    regret = {}
    for side, obstacles, path in (("o", obstacles_o, path_o), ("a", obstacles_a, path_a)):
        expert = optimal_path(obstacles.tolist(), tuple(start), tuple(goal), True)
        regret[side] = path_cost(path) - path_cost(expert)
    return label, regret["a"] > regret["o"] + TOL, regret["a"]


def _plain_figures(per_map: dict, n: int) -> dict:
    """Figures from {map: (label, harmful, regret)} of one strategy, or a list of such dicts (the worst case)."""
    rows = per_map if isinstance(per_map, list) else [per_map]
    valid = broken = harmful = 0
    regrets = []
    for m in range(n):
        got = [r[m] for r in rows if m in r and r[m][0] != "invalid"]
        if not got:
            continue
        valid += 1
        broken += any(label in ("UrP", "FP") for label, _, _ in got)
        harmful += any(h for _, h, _ in got)
        if not any(label == "UrP" for label, _, _ in got):
            regrets.append(max(regret for _, _, regret in got))
    return {
        "valid": valid,
        "broken": broken,
        "harmful": harmful,
        "mean_regret": sum(regrets) / len(regrets) if regrets else None,
    }


def test_figures_per_strategy_and_worst_case_agree_with_a_plain_python_computation(model, maps):
    names = ("key-points", "saliency", "near-path", "random", "exhaustive")
    result = robustness(model, maps, names, max_obstacles=2, seed=3, budget=4)
    n = len(maps)
    for k in (1, 2):
        per_strategy = []
        for name in names:
            # the strategy alone with k obstacles, each pair judged by the plain-Python rule, costs and harm
            pairs = (
                make_attack(name, per_map=1, seed=3, budget=4, obstacles=k)
                .attack(maps.obstacles, maps.starts[:, 0], maps.goals, model, strength=objective_strength("harm"))
                .pairs
            )
            verdicts = {}
            for i in range(len(pairs)):
                verdicts[int(pairs.map_index[i])] = _verdict(
                    pairs.obstacles_o[i],
                    pairs.obstacles_a[i],
                    pairs.starts[i],
                    pairs.goals[i],
                    pairs.path_o[i].tolist(),
                    pairs.path_a[i].tolist(),
                )
            per_strategy.append(verdicts)
            expected, got = _plain_figures(verdicts, n), result.figures(name, k)
            assert (got.valid, got.broken, got.harmful) == (
                expected["valid"],
                expected["broken"],
                expected["harmful"],
            ), (name, k)
            assert got.mean_regret == pytest.approx(expected["mean_regret"], abs=1e-9)
            assert got.attacked == len(pairs) and sum(got.counts.values()) == len(pairs)
        expected, got = _plain_figures(per_strategy, n), result.figures(k=k)
        assert (got.valid, got.broken, got.harmful) == (expected["valid"], expected["broken"], expected["harmful"])
        assert got.mean_regret == pytest.approx(expected["mean_regret"], abs=1e-9)
    worst = result.figures(k=1)
    assert worst.harmful >= max(result.figures(name, 1).harmful for name in names) and worst.harmful > 0


@pytest.mark.slow
def test_exhaustive_harmful_rate_is_the_share_of_maps_some_single_cell_harms(model, maps):
    # the first EXHAUSTIVE_MAPS maps: the oracle plans every cell of every map step by step (the suite's time)
    maps = maps.take(slice(0, EXHAUSTIVE_MAPS))
    result = robustness(model, maps, ["exhaustive"], max_obstacles=1)
    harmed = valid = 0
    for i in range(len(maps)):  # every cell of every map, the slow way
        obstacles, start, goal = maps.obstacles[i], maps.starts[i, 0], maps.goals[i]
        original = plan_reference(obstacles[None], start[None], goal[None], model).paths[0].tolist()
        if rule_oracle(original, original, goal, T)[0] == "invalid":
            continue
        any_cell, any_harm = False, False
        for r in range(SIZE):
            for c in range(SIZE):
                if obstacles[r, c] or (r, c) in (tuple(start), tuple(goal)):
                    continue
                adv = obstacles.copy()
                adv[r, c] = True
                if optimal_path(adv.tolist(), tuple(start), tuple(goal), True) is None:
                    continue
                any_cell = True
                path = plan_reference(adv[None], start[None], goal[None], model).paths[0].tolist()
                any_harm |= _verdict(obstacles, adv, start, goal, original, path)[1]
        valid += any_cell
        harmed += any_harm
    figures = result.figures(k=1)
    assert (figures.valid, figures.harmful) == (valid, harmed) and 0 < harmed < valid


def test_the_optimal_planner_is_never_harmed(maps):
    planner = load_planner("optimal", SIZE)
    result = robustness(planner, maps, max_obstacles=3, seed=2)
    assert result.clean["success_rate"] == 1.0 and result.clean["mean_regret"] == pytest.approx(0, abs=1e-9)
    for k in (1, 2, 3):
        for name in (*result.strategies, "worst case"):
            figures = result.figures(name, k)
            assert figures.harmful == 0 and figures.mean_regret == pytest.approx(0, abs=1e-9)
            assert figures.valid == figures.attacked  # the clean path always reaches the goal


def test_worst_case_per_map_by_hand():
    def outcome(labels, harmful, regret):
        labels = np.array(labels, dtype="<U7")
        pair = labels != ""
        valid = pair & (labels != "invalid")
        return MapOutcomes(
            pair=pair,
            valid=valid,
            broken=valid & np.isin(labels, ("UrP", "FP")),
            harmful=np.array(harmful) & valid,
            regret=np.array(regret, dtype=float),
            label=labels,
        )

    nan = math.nan
    a = outcome(["UrP", "DP", "", "FP", "invalid"], [True, True, False, False, False], [nan, 2.0, nan, 0.0, nan])
    b = outcome(["DP", "UcP", "DP", "", "invalid"], [True, False, False, False, False], [1.5, 0.0, 0.5, nan, nan])
    worst = worst_case([a, b])
    assert worst.valid.tolist() == [True, True, True, True, False]
    assert worst.broken.tolist() == [True, False, False, True, False]
    assert worst.harmful.tolist() == [True, True, False, False, False]
    # map 0: one strategy left the planner unreached, so no regret; the others: the largest
    assert np.array_equal(worst.regret, [nan, 2.0, 0.5, 0.0, nan], equal_nan=True)


def test_same_seed_same_figures_other_seed_other_maps(model):
    def run(seed):
        return robustness(
            model,
            heldout_maps(10, SIZE, seed=seed),
            ["random", "near-path", "key-points"],
            max_obstacles=2,
            seed=seed,
        ).to_dict()

    first, again, other = run(7), run(7), run(8)
    for d in (first, again, other):
        d.pop("seconds")
        for s in d["strategies"].values():
            s.pop("seconds")
    assert first == again
    assert first["settings"]["maps_seed"] == 7 and other != first


def test_bad_inputs_are_refused(model, maps):
    with pytest.raises(InputError, match="max_obstacles must be >= 1"):
        robustness(model, maps, max_obstacles=0)
    with pytest.raises(InputError, match="unknown strategy 'fast'"):
        robustness(model, maps, ["fast"])
    with pytest.raises(InputError, match="objective"):
        robustness(model, maps, objective="speed")
    assert check_strategies("all") == ("key-points", "saliency", "near-path", "random")
    assert check_strategies("exhaustive,all", exhaustive=True) == (
        "exhaustive",
        "key-points",
        "saliency",
        "near-path",
        "random",
    )
    with pytest.raises(InputError, match="named twice"):
        check_strategies("random,all")
    with pytest.raises(InputError, match="add exhaustive"):
        check_strategies("exhaustive")
    assert check_strategies("exhaustive,random", exhaustive=True) == ("exhaustive", "random")
    assert check_strategies("random", exhaustive=True) == ("random", "exhaustive")


@pytest.mark.parametrize(
    "args, message",
    [
        (["--max-obstacles", "0"], "--max-obstacles must be >= 1"),
        (["--strategies", "random,nope"], "--strategies: unknown strategy 'nope'"),
        (["--strategies", "exhaustive"], "--strategies: add --exhaustive to run the exhaustive strategy"),
        (["--n", "0"], "--n must be >= 1"),
        (["--budget", "0"], "--budget must be >= 1"),
        (["--harm-tolerance", "-1"], "--harm-tolerance"),
        (["--planner", "nope"], "nope"),
    ],
)
def test_cli_bad_input_exits_2_with_one_line(weights, capsys, args, message):
    assert main(["robustness", "--size", str(SIZE), "--weights", weights, "--n", "3", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_cli_refuses_a_foreign_database_or_a_file_as_report_folder_before_the_work(weights, tmp_path, capsys):
    foreign = tmp_path / "other.db"
    with sqlite3.connect(foreign) as conn:
        conn.execute("CREATE TABLE runs (who TEXT)")
    args = ["robustness", "--size", str(SIZE), "--weights", weights, "--n", "2"]
    assert main([*args, "--db", str(foreign)]) == 2
    assert "not a vinadv database" in capsys.readouterr().err
    (tmp_path / "page").write_text("x")
    assert main([*args, "--report", str(tmp_path / "page")]) == 2
    assert "not a folder" in capsys.readouterr().err


def test_cli_json_db_and_report(weights, tmp_path, capsys):
    db = tmp_path / "r.db"
    args = [
        "robustness",
        "--size",
        str(SIZE),
        "--weights",
        weights,
        "--n",
        "12",
        "--seed",
        "4",
        "--max-obstacles",
        "2",
        "--strategies",
        "random,key-points",
        "--db",
        str(db),
    ]
    assert main([*args, "--json", "--report", str(tmp_path / "page")]) == 0
    out = json.loads(capsys.readouterr().out)
    assert list(out["strategies"]) == ["random", "key-points"] and len(out["overall"]) == 2
    assert out["settings"]["n"] == 12 and out["planner"]["name"] == "vin"
    # every rate with its Wilson 95% interval, from its counts (vinadv.intervals)
    for f in [*out["overall"], *(g for s in out["strategies"].values() for g in s["by_obstacles"])]:
        for rate, count in (("harmful_rate", "harmful"), ("paper_success_rate", "broken")):
            assert (f[f"{rate}_low"], f[f"{rate}_high"]) == rate_interval(f[count], f["valid"])
            assert f[rate] is None or f[f"{rate}_low"] <= f[rate] <= f[f"{rate}_high"]
    clean = out["clean"]
    assert (clean["success_rate_low"], clean["success_rate_high"]) == rate_interval(clean["reached"], clean["maps"])
    with Store.open(str(db), readonly=True) as store:
        (row,) = store.read_robustness()
    assert row["id"] == out["id"] and row["result"]["overall"] == out["overall"]
    page = (tmp_path / "page" / "index.html").read_text()
    assert 'id="robustness-table"' in page and "fig_robustness.png" in page
    assert (tmp_path / "page" / "robustness.csv").exists()
    assert main([*args, "--quiet"]) == 0
    quiet = capsys.readouterr()  # the result, and no progress bar
    assert "harmful rate by obstacles added" in quiet.out and quiet.err == ""
    assert main(args) == 0
    text = capsys.readouterr().out
    assert (
        "worst case" in text
        and "harmful rate by obstacles added" in text
        and "stored as robustness benchmark 3" in text
    )


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("n", 0, "n must be >= 1, got 0"),
        ("max_obstacles", 0, "max_obstacles must be >= 1, got 0"),
        ("radius", -1, "radius must be >= 0, got -1"),
        ("harm_tolerance", -1.0, "harm_tolerance: must be a finite number >= 0"),
        ("objective", "fast", "objective: 'fast' is not one of"),
        ("strategies", "random,nope", "strategies: unknown strategy 'nope'"),
        ("moves", "hex", "hex"),
    ],
)
def test_a_config_refuses_a_bad_value_naming_the_field(field, value, message):
    from vinadv.robustness import RobustnessConfig  # noqa: PLC0415 (the config under test)

    with pytest.raises(InputError, match=re.escape(message)) as info:
        RobustnessConfig(**{field: value})
    assert field in info.value.parameters
    assert RobustnessConfig(strategies="random, near-path").strategies == ("random", "near-path")


def test_the_job_gives_the_engines_result(tmp_path):
    from vinadv.robustness import RobustnessConfig, run  # noqa: PLC0415 (the job under test)

    config = RobustnessConfig(planner="optimal", n=6, size=10, strategies=("random",), max_obstacles=2, seed=3)
    maps = heldout_maps(6, 10, seed=3)
    engine = robustness(load_planner("optimal", 10), maps, ("random",), 2, seed=3).to_dict()

    job = run(config).to_dict()
    for out in (job, engine):
        out["seconds"] = out["strategies"]["random"]["seconds"] = 0
    assert json.dumps(job, sort_keys=True) == json.dumps(engine, sort_keys=True)


def test_a_curve_past_the_cells_left_ends_the_search_and_past_a_maps_cells_is_refused(model, maps):
    """`--max-obstacles` huge kept the greedy search planning after no cell was left (issue 45): past a map's cells
    it is refused before any work, naming the field; up to them, the search stops where the cells run out and the
    curve's later points are maps without a pair."""
    cells = SIZE * SIZE
    for k in (cells + 1, 10**9):
        with pytest.raises(InputError, match=f"max_obstacles {k}: more than the {cells} cells of a {SIZE}x{SIZE} map"):
            robustness(model, maps.take(np.arange(2)), ["random"], max_obstacles=k)
    result = robustness(model, maps.take(np.arange(2)), ["random"], max_obstacles=cells, edit="remove")
    by_k = result.strategies["random"].by_k
    assert [f.k for f in by_k] == list(range(1, cells + 1)) and len(result.overall) == cells
    made = [f.attacked for f in by_k]
    last = made.index(0)  # the step where no map had a cell left; every later one the same
    assert last < cells // 2 and not any(made[last:]) and all(made[:last])
    # 2 maps: the clean plans, then per step a plan of each map (but the first step's) and at most one candidate each
    assert result.strategies["random"].planner_calls <= 2 + 4 * last


def test_the_text_output_names_the_maps_and_gives_each_rate_its_interval(tmp_path, capsys):
    # the generated maps are named by their seed (every record names `maps`, None here), a maps file by its path;
    # the one-obstacle rates print with their Wilson intervals
    argv = ["robustness", "--planner", "optimal", "--n", "5", "--max-obstacles", "1", "--quiet"]
    assert main([*argv, "--size", "10", "--strategies", "random"]) == 0
    text = capsys.readouterr().out
    assert "(seed 1000)" in text and "None" not in text
    (line,) = [row for row in text.splitlines() if row.startswith("worst case") and "[" in row]
    assert line.count("[0.0, ") == 2  # no pair harms the optimal planner: 0% with an interval from 0
    maps = tmp_path / "m.npz"
    assert main(["maps", "generate", "--n", "5", "--size", "10", "--out", str(maps), "--quiet"]) == 0
    capsys.readouterr()
    assert main([*argv, "--strategies", "random", "--maps", str(maps)]) == 0
    assert f"(from {maps}, sha256 {checksums.file_sha256(maps)[:12]})" in capsys.readouterr().out
