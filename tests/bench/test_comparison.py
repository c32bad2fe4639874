"""What per-map outcomes allow (`vinadv.bench.comparison`): McNemar's exact test against a plain-Python binomial sum,
paired counts and the test per k on hand-made outcomes, per-family rows against a per-map count of a committed quick
entry, bootstrap intervals that reproduce, the leaderboard's column and `vinadv bench compare`."""

from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from vinadv.bench.comparison import (
    compare_entries,
    family_rows,
    family_spans,
    mcnemar,
    mean_intervals,
    paired_counts,
    verdict,
)
from vinadv.bench.leaderboard import read_entries, render_markdown, rows
from vinadv.bench.suites import ENTRY_FORMAT_2, SUITES
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.robustness import MapOutcomes

COMMITTED = Path(__file__).resolve().parents[2] / "docs" / "results" / "bench"


def exact_two_sided(a: int, b: int) -> float:
    """Plain Python: the probability, under binomial(a + b, 1/2), of an outcome at most as likely as `a`."""
    n = a + b
    if n == 0:
        return 1.0
    prob = [Fraction(math.comb(n, i), 2**n) for i in range(n + 1)]
    return float(sum(p for p in prob if p <= prob[a]))


@pytest.mark.parametrize("a", [0, 1, 2, 5, 9, 14])
@pytest.mark.parametrize("b", [0, 1, 3, 6, 14, 30])
def test_mcnemar_is_the_exact_binomial_test(a, b):
    assert mcnemar(a, b) == pytest.approx(exact_two_sided(a, b), rel=1e-9, abs=1e-15)
    assert mcnemar(a, b) == mcnemar(b, a)  # two-sided: symmetric


def test_mcnemar_refuses_a_negative_count():
    with pytest.raises(InputError, match="discordant"):
        mcnemar(-1, 3)


def _o(valid, harmful) -> MapOutcomes:
    valid, harmful = np.array(valid, dtype=bool), np.array(harmful, dtype=bool)
    return MapOutcomes(
        pair=valid,
        valid=valid,
        broken=harmful,
        harmful=harmful & valid,
        regret=np.zeros(len(valid)),
        label=np.full(len(valid), "FN"),
    )


def test_paired_counts_only_count_the_maps_valid_for_both():
    # maps: A harmful only, B harmful only x2, both, neither, A harmful but invalid for B, B invalid for A
    a = _o([1, 1, 1, 1, 1, 1, 0], [1, 0, 0, 1, 0, 1, 0])
    b = _o([1, 1, 1, 1, 1, 0, 1], [0, 1, 1, 1, 0, 0, 1])
    test = paired_counts(a, b)
    assert {k: test[k] for k in ("maps", "a_only", "b_only", "both", "neither")} == {
        "maps": 5,
        "a_only": 1,
        "b_only": 2,
        "both": 1,
        "neither": 1,
    }
    assert test["p_value"] == pytest.approx(exact_two_sided(1, 2))
    with pytest.raises(InputError, match="not the same maps"):
        paired_counts(a, _o([1], [0]))


def test_verdict():
    assert verdict({"p_value": 0.01, "a_only": 0, "b_only": 9}) == "more robust"
    assert verdict({"p_value": 0.01, "a_only": 9, "b_only": 0}) == "less robust"
    assert verdict({"p_value": 0.05, "a_only": 0, "b_only": 9}) == "not distinguishable"


def _record(k, label, harmful, regret=None):
    return {"k": k, "label": label, "harmful": harmful, "regret": regret or [0.0] * len(label)}


def _entry(attacks: dict, suite=None, reached=None) -> dict:
    n = len(next(iter(attacks.values()))[0]["label"])
    return {
        "format": ENTRY_FORMAT_2,
        "suite": suite or {"name": "hand", "checksum": "0" * 64},
        "per_map": {"clean": {"reached": reached or [True] * n, "regret": [0.0] * n}, "attacks": attacks},
    }


def test_compare_entries_tests_each_budget_on_the_worst_case_within_k():
    # 10 maps; A harmed at k = 1 on map 0 only, B on maps 0..7 at k = 1; at k = 2 A's random attack harms map 1 too
    a = _entry(
        {
            "add:random": [
                _record(1, ["FN"] * 10, [True] + [False] * 9),
                _record(2, ["FN"] * 10, [False, True] + [False] * 8),
            ],
            "remove:random": [_record(1, ["FN"] * 10, [False] * 10)],
        }
    )
    b = _entry(
        {
            "add:random": [_record(1, ["FN"] * 10, [True] * 8 + [False] * 2), _record(2, ["FN"] * 10, [False] * 10)],
            "remove:random": [_record(1, [""] * 10, [False] * 10)],
        }
    )
    tests = compare_entries(a, b)
    assert [(t["k"], t["maps"], t["a_only"], t["b_only"], t["both"]) for t in tests] == [
        (1, 10, 0, 7, 1),
        (2, 10, 0, 6, 2),
    ]
    assert tests[0]["p_value"] == pytest.approx(exact_two_sided(0, 7))
    assert tests[0]["verdict"] == "more robust"  # 2 * 2**-7 = 0.016
    assert tests[1]["verdict"] == "more robust"  # 2 * 2**-6 = 0.031
    with pytest.raises(InputError, match="two suites"):
        compare_entries(a, _entry(b["per_map"]["attacks"], suite={"name": "other", "checksum": "1" * 64}))
    with pytest.raises(InputError, match="needs a format 2 entry"):
        compare_entries(a, {**b, "format": "vinadv.bench_entry/1"})


def test_mean_intervals_of_hand_made_regrets():
    regrets = [0.0, 1.0, 2.0, 4.0]
    e = _entry({"add:random": [_record(1, ["FN", "FN", "", "FP"], [False] * 4, [0.5, 1.5, None, 3.0])]})
    e["per_map"]["clean"]["regret"] = regrets
    e["per_map"]["clean"]["reached"] = [True, True, True, False]  # map 3's regret is not a clean path's
    means = mean_intervals(e)
    assert means == mean_intervals(e)  # seeded
    assert means["clean_regret"]["mean"] == 1.0 and means["clean_regret"]["maps"] == 3
    assert 0.0 <= means["clean_regret"]["low"] <= 1.0 <= means["clean_regret"]["high"] <= 2.0
    # the worst case: map 2 has no pair, map 3's clean path does not reach (its pair is not valid: label FP counts)
    worst = means["worst_regret"][0]
    assert worst["maps"] == 3 and worst["mean"] == pytest.approx((0.5 + 1.5 + 3.0) / 3)
    assert mean_intervals({**e, "format": "vinadv.bench_entry/1"}) == {}


def test_family_rows_of_a_committed_quick_entry_count_each_familys_maps():
    entry = json.loads((COMMITTED / "mpd32-quick-v2.wastar-w2.json").read_text())
    suite = SUITES["mpd32-quick-v2"]
    spans = family_spans(suite)
    assert [(f, hi - lo) for f, lo, hi in spans] == [
        ("alternating_gaps", 17),
        ("forest", 17),
        ("mazes", 17),
        ("multiple_bugtraps", 17),
        ("shifting_gaps", 16),
        ("single_bugtrap", 16),
    ]
    records = [r for rs in entry["per_map"]["attacks"].values() for r in rs]
    valid = [any(r["label"][i] not in ("", "invalid") for r in records) for i in range(suite.n)]
    got = family_rows(entry)
    for row, (family, lo, hi) in zip(got, spans):
        assert row["family"] == family and row["maps"] == hi - lo
        assert row["reached"] == sum(entry["per_map"]["clean"]["reached"][lo:hi])
        for k, figures in enumerate(row["worst_case"], start=1):
            harmful = sum(any(r["harmful"][i] for r in records if r["k"] <= k) for i in range(lo, hi))
            assert (figures["harmful"], figures["valid"]) == (harmful, sum(valid[lo:hi]))
            assert figures["harmful_rate_low"] <= figures["harmful_rate"] <= figures["harmful_rate_high"]
    # the families add up to the entry's worst case
    for k, total in enumerate(entry["worst_case"]):
        assert sum(row["worst_case"][k]["harmful"] for row in got) == total["harmful"]
    assert family_spans(SUITES["vin28-quick-v2"]) == []


def test_leaderboard_says_which_planner_is_more_robust_than_the_next():
    files = [COMMITTED / f"vin28-quick-v2.{name}.json" for name in ("optimal", "wastar-w2")]
    table = rows(read_entries([*files, COMMITTED / "vin28-quick-v1.vin.json"]))
    v2 = table["vin28-quick-v2"]
    wastar = json.loads(files[1].read_text())
    assert v2[0]["vs_next"]["b_only"] == wastar["worst_case"][0]["harmful"] and v2[0]["vs_next"]["a_only"] == 0
    assert v2[1]["vs_next"] is None  # the last row
    assert all(r["vs_next"] is None and r["families"] == [] for r in table["vin28-quick-v1"])  # v1: no outcomes
    text = render_markdown(table)
    assert "more robust than the next (p < 0.001)".replace("<", "\\<") in text


def test_bench_compare_prints_the_test_per_k(tmp_path, capsys):
    a, b = (str(COMMITTED / f"vin28-quick-v2.{name}.json") for name in ("wastar-w2", "vin"))
    assert main(["bench", "compare", a, b, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [t["k"] for t in out["tests"]] == [1, 2, 3]
    assert all(t["maps"] == t["a_only"] + t["b_only"] + t["both"] + t["neither"] for t in out["tests"])
    assert (
        out["a"]["means"]["worst_regret"][0]["mean"] == json.loads(Path(a).read_text())["worst_case"][0]["mean_regret"]
    )
    assert main(["bench", "compare", a, b]) == 0
    assert "k = 3:" in capsys.readouterr().out
    assert main(["bench", "compare", a, str(COMMITTED / "vin28-quick-v1.vin.json")]) == 2
    assert "needs a format 2 entry" in capsys.readouterr().err
