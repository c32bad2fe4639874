"""Search effort and a search planner's per-map clean protocol in entries of format 2 (issue 46, items 2 and 4): each
attack record's effort ratio and effort-harmful verdict, the effort-harmful rate of every figure (hand-computed), the
worst effort per map at each k, the bootstrap intervals of the mean worst effort, Exp and cost ratio, and the schema
and `bench verify` refusing a malformed or tampered field in one line."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tests.bench.two_maps import heldout_suite, register
from vinadv.bench.comparison import mean_intervals
from vinadv.bench.leaderboard import _cells, rows
from vinadv.bench.outcomes import entry_figures
from vinadv.bench.scoring import run_bench, suite_maps
from vinadv.bench.suites import ENTRY_FORMAT_2, AttackGroup
from vinadv.bench.validate import entry_problem
from vinadv.bench.verify import verify_entry
from vinadv.cli import main
from vinadv.grid.paths import path_costs
from vinadv.planners.registry import load_planner

SIZE = 10


def _wilson(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """The Wilson score interval, written out (the reference for the readers' intervals)."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (0.0 if k == 0 else centre - half), (1.0 if k == n else centre + half)


def small_suite():
    return heldout_suite("tiny-effort", 3, SIZE, (AttackGroup(("random",), "add", 2),), budget=3, definitions=2)


def hand_per_map() -> dict:
    """Three maps, one attack at k = 1 and 2; map 2's clean path does not reach (its pairs are invalid)."""
    search = {
        "rows": 3,
        "opt": 2 / 3,
        "exp": 0.25,
        "success": 2 / 3,
        "cost_ratio": 1.25,
        "expansions": 10.0,
        "astar_expansions": 12.0,
    }
    return {
        "clean": {
            "reached": [True, True, False],
            "regret": [0.0, 1.0, None],
            "exp": [0.25, 0.5, 0.0],
            "cost_ratio": [1.0, 1.5, None],
        },
        "chunks": [{"maps": 3, "search": search}],
        "attacks": {
            "add:random": [
                {
                    "k": 1,
                    "label": ["DP", "UcP", "invalid"],
                    "harmful": [False, False, False],
                    "regret": [1.0, 0.0, None],
                    "effort": [3.0, 0.5, None],
                    "effort_harmful": [True, False, False],
                },
                {
                    "k": 2,
                    "label": ["DP", "UrP", "invalid"],
                    "harmful": [False, True, False],
                    "regret": [1.0, None, None],
                    "effort": [1.0, 4.0, None],
                    "effort_harmful": [False, True, False],
                },
            ]
        },
    }


def test_the_effort_harmful_rates_and_worst_efforts_are_the_hand_computed_ones():
    figures = entry_figures(small_suite(), hand_per_map())
    by_k = figures["attacks"]["add:random"]["by_obstacles"]
    # the attack's own pairs: map 0 effort-harmful at k = 1, map 1 at k = 2, of the 2 valid maps
    assert [(f["effort_harmful"], f["valid"], f["effort_harmful_rate"]) for f in by_k] == [(1, 2, 0.5), (1, 2, 0.5)]
    # the worst case within k edits: map 0 stays effort-harmful at k = 2, so both maps are
    worst = figures["worst_case"]
    assert [(f["effort_harmful"], f["effort_harmful_rate"]) for f in worst] == [(1, 0.5), (2, 1.0)]
    assert figures["worst_effort"] == [[3.0, 0.5, None], [3.0, 4.0, None]]
    from vinadv.intervals import figure_intervals  # noqa: PLC0415 (what every reader computes from the counts)

    low, high = _wilson(1, 2)
    got = figure_intervals(worst[0])
    assert got["effort_harmful_rate_low"] == pytest.approx(low, abs=1e-12)
    assert got["effort_harmful_rate_high"] == pytest.approx(high, abs=1e-12)
    assert figure_intervals(worst[1])["effort_harmful_rate_high"] == 1.0


def test_the_means_of_effort_exp_and_cost_ratio_are_bootstrapped_over_the_maps():
    means = mean_intervals(
        {"format": ENTRY_FORMAT_2, "per_map": {**hand_per_map(), "worst_effort": [[3.0, 0.5, None], [3.0, 4.0, None]]}}
    )
    # two or three values: every resample's mean lies between the smallest and the largest, both drawn far more than
    # 2.5% of the time (1/4 and 1/27 of the resamples): the percentile interval is [min, max]
    assert means["worst_effort"][1] == {"k": 2, "mean": 3.5, "low": 3.0, "high": 4.0, "maps": 2}
    assert means["clean_exp"] == {"mean": 0.25, "low": 0.0, "high": 0.5, "maps": 3}
    assert means["clean_cost_ratio"] == {"mean": 1.25, "low": 1.0, "high": 1.5, "maps": 2}
    plain = {"format": ENTRY_FORMAT_2, "per_map": {k: v for k, v in hand_per_map().items()}}
    plain["per_map"]["clean"] = {"reached": [True, True, False], "regret": [0.0, 1.0, None]}
    assert set(mean_intervals(plain)) == {"clean_regret", "worst_regret"}  # an entry computed before: no new means


@pytest.fixture(scope="module")
def wastar_entry():
    return run_bench(small_suite(), load_planner("wastar:w=2", SIZE))


@pytest.fixture
def registered(monkeypatch):
    return register(monkeypatch, small_suite())


def test_a_search_planners_entry_holds_its_efforts_and_the_rates_follow_from_them(wastar_entry):
    e = wastar_entry
    assert entry_problem(e) is None
    records = e["per_map"]["attacks"]["add:random"]
    for record, figure in zip(records, e["attacks"]["add:random"]["by_obstacles"]):
        valid = [label not in ("", "invalid") for label in record["label"]]
        assert [v is not None for v in record["effort"]] == valid  # a ratio exactly where the pair is valid
        assert all(v > 0 for v in record["effort"] if v is not None)
        assert not any(h and not ok for h, ok in zip(record["effort_harmful"], valid))
        assert figure["effort_harmful"] == sum(record["effort_harmful"])
        assert figure["effort_harmful_rate"] == sum(record["effort_harmful"]) / sum(valid)
    for k, worst in enumerate(e["worst_case"], start=1):  # a map effort-harmful for any pair of at most k edits
        within = [r for r in records if r["k"] <= k]
        assert worst["effort_harmful"] == sum(any(r["effort_harmful"][m] for r in within) for m in range(3))
        expected = [max((r["effort"][m] for r in within if r["effort"][m] is not None), default=None) for m in range(3)]
        assert e["per_map"]["worst_effort"][k - 1] == expected


def test_a_search_planners_per_map_exp_and_cost_ratio_are_its_own_counts(wastar_entry):
    # the oracle: the two searches planned here, Exp and the cost ratio written out per map
    maps = suite_maps(small_suite())
    args = (maps.obstacles, maps.starts[:, 0], maps.goals, maps.corner_cutting, maps.moves)
    mine, astar = load_planner("wastar:w=2", SIZE).plan(*args), load_planner("astar", SIZE).plan(*args)
    costs = path_costs(mine.paths, maps.moves)
    exp = [max(0.0, (float(a) - float(m)) / float(a)) for m, a in zip(mine.expansions, astar.expansions)]
    ratio = [
        (float(c) / float(o) if o > 0 else 1.0) if ok else None
        for c, o, ok in zip(costs, maps.expert_costs[:, 0], mine.reached)
    ]
    clean = wastar_entry["per_map"]["clean"]
    assert clean["exp"] == pytest.approx(exp, abs=1e-15)
    assert clean["cost_ratio"] == pytest.approx(ratio, abs=1e-15)
    assert "exp" not in wastar_entry["per_map"]["chunks"][0]  # per map, not a chunk's mean
    assert wastar_entry["clean"]["search"]["exp"] == pytest.approx(sum(exp) / 3, abs=1e-12)


def test_an_entry_of_a_planner_without_expansions_has_no_efforts():
    e = run_bench(small_suite(), load_planner("optimal", SIZE))
    assert "worst_effort" not in e["per_map"] and "exp" not in e["per_map"]["clean"]
    assert all("effort" not in r for rs in e["per_map"]["attacks"].values() for r in rs)
    assert all("effort_harmful" not in f for f in e["worst_case"])
    ((row,),) = rows([(Path("o.json"), e)]).values()
    assert row["effort"] is None


def _first_valid(record) -> int:
    return next(m for m, label in enumerate(record["label"]) if label not in ("", "invalid"))


def _tamper(entry, change) -> dict:
    bad = json.loads(json.dumps(entry))
    change(bad)
    return bad


def _no_valid_pair(e):
    r = e["per_map"]["attacks"]["add:random"][0]  # map 0 without a pair, yet effort-harmful
    r["label"][0], r["harmful"][0], r["regret"][0], r["effort"][0], r["effort_harmful"][0] = "", False, None, None, True


def _negative(e):
    r = e["per_map"]["attacks"]["add:random"][0]
    r["effort"][_first_valid(r)] = -1.0


def _mixed(e):
    r = e["per_map"]["attacks"]["add:random"][1]
    del r["effort"], r["effort_harmful"]


def _exp_above_one(e):
    e["per_map"]["clean"]["exp"][0] = 1.5


def _null_ratio(e):
    e["per_map"]["clean"]["cost_ratio"][0] = None


def _rate(e):
    e["worst_case"][0]["effort_harmful_rate"] = 2.0


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (_no_valid_pair, "per_map.attacks.add:random[0].effort_harmful[0]' is True on a map without a valid pair"),
        (_negative, "per_map.attacks.add:random[0].effort["),
        (_mixed, "per_map.attacks.add:random[1].effort_harmful' is missing, where per_map.attacks.add:random[0]"),
        (_exp_above_one, "per_map.clean.exp[0]' is 1.5"),
        (_null_ratio, "per_map.clean.cost_ratio[0]' is null where the clean path reaches the goal"),
        (_rate, "worst_case[0].effort_harmful_rate' is 2.0"),
    ],
)
def test_the_schema_refuses_a_malformed_effort_or_protocol_field_naming_it(wastar_entry, change, field):
    problem = entry_problem(_tamper(wastar_entry, change))
    assert problem is not None and problem.startswith(f"field '{field}"), problem


def test_bench_verify_refuses_a_malformed_field_in_one_line(wastar_entry, registered, tmp_path, capsys):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(_tamper(wastar_entry, _exp_above_one)))
    assert main(["bench", "verify", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "field 'per_map.clean.exp[0]'" in err


def test_bench_verify_names_a_tampered_verdict_and_a_tampered_map_value(wastar_entry, registered):
    assert verify_entry(wastar_entry)["differences"] == []

    def flip(e):
        r = e["per_map"]["attacks"]["add:random"][0]
        m = _first_valid(r)
        r["effort_harmful"][m] = not r["effort_harmful"][m]

    lines = verify_entry(_tamper(wastar_entry, flip))["differences"]
    assert "field 'attacks.add:random.by_obstacles[0].effort_harmful': " in "\n".join(lines)
    assert "field 'worst_case[0].effort_harmful': " in "\n".join(lines)

    def shift(e):
        e["per_map"]["clean"]["exp"][1] = min(1.0, e["per_map"]["clean"]["exp"][1] + 0.25)

    (line,) = verify_entry(_tamper(wastar_entry, shift))["differences"]
    assert line.startswith("field 'per_map.chunks[0].search.exp': ")


def test_the_leaderboard_shows_the_effort_harmful_rate_and_exp_with_their_intervals(wastar_entry):
    ((row,),) = rows([(Path("w.json"), wastar_entry)]).values()
    worst = wastar_entry["worst_case"][0]
    low, high = _wilson(worst["effort_harmful"], worst["valid"])
    assert row["effort"] == worst["effort_harmful_rate"]
    assert row["effort_low"] == pytest.approx(low, abs=1e-12) and row["effort_high"] == pytest.approx(high, abs=1e-12)
    exp = row["means"]["clean_exp"]
    values = wastar_entry["per_map"]["clean"]["exp"]
    assert exp["mean"] == pytest.approx(sum(values) / len(values), abs=1e-15)
    assert min(values) <= exp["low"] <= exp["high"] <= max(values)
    cells = _cells(row)
    assert f"[{round(100 * exp['low'], 1):.1f}, {round(100 * exp['high'], 1):.1f}]" in cells[4]
    assert np.isclose(float(cells[8].split("%")[0]), 100 * row["effort"], atol=0.051)
