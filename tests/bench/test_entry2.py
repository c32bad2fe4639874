"""Entries of format 2 (`vinadv.bench_entry/2`): budgets of at most k edits (a k curve that cannot fall, against a
brute force over per-map outcomes), chains started from the exhaustive one-cell optimum, every figure recomputed from
the per-map outcomes, `bench verify` (a tampered entry names the field), the submission fields, and the released
`-v2` suites."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.bench.two_maps import heldout_suite, register
from vinadv.bench import suites
from vinadv.bench.leaderboard import read_entries
from vinadv.bench.outcomes import entry_figures, worst_case_within
from vinadv.bench.scoring import entry_json, run_bench
from vinadv.bench.suites import FROZEN, AttackGroup, Suite, get_suite
from vinadv.bench.validate import entry_problem
from vinadv.bench.verify import pick_chunks, read_entry, verify_entry
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.planners.registry import load_planner
from vinadv.planners.vin.planner import as_planner
from vinadv.robustness import MapOutcomes, heldout_maps, robustness
from vinadv.testing.planners import planning_vin
from vinadv.vocabulary import SUCCESS_LABELS

SIZE = 10
LABELS = ("", "invalid", "UrP", "FP", "DP", "UcP")


def _outcome(draw, n: int) -> MapOutcomes:
    label = np.array(draw(st.lists(st.sampled_from(LABELS), min_size=n, max_size=n)), dtype="<U7")
    valid = (label != "") & (label != "invalid")
    harmful = np.array(draw(st.lists(st.booleans(), min_size=n, max_size=n))) & valid
    harmful |= valid & (label == "UrP")
    regret = np.array(draw(st.lists(st.floats(0, 5), min_size=n, max_size=n)))
    regret[~valid | (label == "UrP")] = np.nan
    return MapOutcomes(
        pair=label != "",
        valid=valid,
        broken=valid & np.isin(label, SUCCESS_LABELS),
        harmful=harmful,
        regret=regret,
        label=label,
    )


@st.composite
def per_k_outcomes(draw):
    n = draw(st.integers(1, 6))
    k = draw(st.integers(1, 4))
    return [[_outcome(draw, n) for _ in range(draw(st.integers(0 if i else 1, 3)))] for i in range(k)]


@settings(max_examples=30, deadline=None)
@given(per_k_outcomes())
def test_the_worst_case_within_k_edits_cannot_fall_and_is_the_brute_force_one(per_k):
    worst = worst_case_within(per_k)
    every = [o for outs in per_k for o in outs]
    n = len(every[0].pair)
    valid = [any(o.valid[m] for o in every) for m in range(n)]
    for k, w in enumerate(worst):
        within = [o for outs in per_k[: k + 1] for o in outs]
        for m in range(n):  # the brute force, map by map
            assert w.valid[m] == valid[m]  # a fixed denominator
            assert w.harmful[m] == any(o.harmful[m] for o in within)
            assert w.broken[m] == any(o.broken[m] for o in within)
            unreached = any(o.valid[m] and o.label[m] == "UrP" for o in within)
            regrets = [o.regret[m] for o in within if not np.isnan(o.regret[m])]
            if unreached or not regrets or not any(o.valid[m] for o in within):
                assert np.isnan(w.regret[m])
            else:
                assert w.regret[m] == max(regrets)
        if k:  # the k curve: never below the one at k - 1
            assert w.harmful.sum() >= worst[k - 1].harmful.sum() and w.broken.sum() >= worst[k - 1].broken.sum()
            assert w.valid.sum() == worst[k - 1].valid.sum()


def tiny_suite(**change) -> Suite:
    attacks = (
        AttackGroup(("random",), "add", 2),
        AttackGroup(("exhaustive",), "add", 1),
        AttackGroup(("random", "near-path"), "add", 3, start="exhaustive"),
        AttackGroup(("random",), "remove", 1),
    )
    suite = heldout_suite("tiny2", 3, SIZE, attacks, "a test suite of definitions 2", budget=3, chunk=2, definitions=2)
    return dataclasses.replace(suite, **change)


@pytest.fixture(scope="module")
def planner():
    return as_planner(planning_vin(SIZE, seed=1, noise=0.2), SIZE)


@pytest.fixture(scope="module")
def entry(planner):
    return run_bench(tiny_suite(), planner, submission={"display_name": "Noisy VIN", "paper": "https://e.org/p"})


@pytest.fixture
def registered(monkeypatch):
    return register(monkeypatch, tiny_suite())


def test_chains_start_from_the_exhaustive_one_cell_optimum(planner):
    maps = heldout_maps(3, SIZE, seed=1000)
    best = robustness(planner, maps, ["exhaustive"], 1, budget=3).strategies["exhaustive"]
    chained = robustness(planner, maps, ["random"], 3, budget=3, start=best.cells[0]).strategies["random"]
    assert [f.k for f in chained.by_k] == [2, 3]
    has = best.outcomes[0].pair
    np.testing.assert_array_equal(chained.cells[0][has, 0], best.cells[0][has, 0])  # the first cell: the optimum's
    np.testing.assert_array_equal(
        chained.cells[1][:, :2][chained.outcomes[1].pair], chained.cells[0][chained.outcomes[1].pair]
    )
    none = robustness(planner, maps, ["random"], 2, budget=3, start=np.full((3, 1, 2), -1))
    assert not none.strategies["random"].outcomes[0].pair.any()  # a map without a start cell gets no pair


def test_an_entry_of_format_2_holds_what_gives_its_figures(entry):
    assert entry["format"] == "vinadv.bench_entry/2" and entry_problem(entry) is None
    assert entry["submission"] == {
        "display_name": "Noisy VIN",
        "authors": [],
        "paper": "https://e.org/p",
        "code": None,
        "external": False,
    }
    assert [f["k"] for f in entry["attacks"]["add:exhaustive+random"]["by_obstacles"]] == [2, 3]
    assert [r["k"] for r in entry["per_map"]["attacks"]["add:exhaustive+near-path"]] == [2, 3]
    figures = entry_figures(tiny_suite(), entry["per_map"])
    assert {name: entry[name] for name in figures} == figures
    worst = entry["worst_case"]
    assert [w["attacks"] for w in worst] == [3, 6, 8]  # every attack of at most k edits
    assert all(a["harmful"] <= b["harmful"] and a["valid"] == b["valid"] for a, b in zip(worst, worst[1:]))
    assert len(json.loads(entry_json(entry))["per_map"]["clean"]["reached"]) == 3
    assert '"reached": [' in entry_json(entry)  # a per-map list on one line


def test_verify_passes_on_the_entry_and_its_recomputed_chunks(entry, planner, registered):
    assert verify_entry(entry, chunks=2, seed=0, planner=planner) == {"differences": [], "chunks": [0, 1]}


@pytest.mark.parametrize(
    ("tamper", "field"),
    [
        (lambda e: e["worst_case"][1].update(harmful_rate=0.0), "field 'worst_case[1].harmful_rate'"),
        (lambda e: e["clean"].update(success_rate=0.5), "field 'clean.success_rate'"),
        (lambda e: e["flags"]["too_weak"].update(raised=True), "field 'flags.too_weak.raised'"),
    ],
)
def test_verify_names_the_field_of_a_tampered_figure(entry, registered, tamper, field):
    bad = json.loads(json.dumps(entry))
    tamper(bad)
    lines = verify_entry(bad)["differences"]
    assert lines and lines[0].startswith(field) and "in the entry" in lines[0]


def test_verify_names_the_map_of_tampered_outcomes_against_a_recomputed_chunk(entry, planner, registered):
    bad = json.loads(json.dumps(entry))
    record = bad["per_map"]["attacks"]["add:random"][0]
    record["label"][2] = "UcP" if record["label"][2] != "UcP" else "DP"  # map 2: in chunk 1 (maps 2..)
    record["regret"][2] = 0.0
    seed = next(s for s in range(100) if pick_chunks(2, 1, s) == [1])
    lines = verify_entry(bad, chunks=1, seed=seed, planner=planner)["differences"]
    assert "field 'per_map.attacks.add:random[0].label[2]'" in "\n".join(lines)
    assert any("the recomputed chunk 1" in line for line in lines)


def test_verify_refuses_another_planner(entry, registered):
    other = as_planner(planning_vin(SIZE, seed=2, noise=0.2), SIZE)
    if other.spec() == entry["planner"]:
        pytest.skip("the two test planners share a spec")
    with pytest.raises(InputError, match="is not the entry's"):
        verify_entry(entry, chunks=1, planner=other)


@pytest.mark.parametrize(
    ("submission", "message"),
    [
        ({"paper": "javascript:alert(1)"}, "paper: is 'javascript:alert(1)', expected an http or https URL"),
        ({"code": "file:///etc/passwd"}, "code: is 'file:///etc/passwd', expected an http or https URL"),
        ({"code": "https://"}, "expected an http or https URL"),
        ({"authors": ["A", ""]}, "authors: is a string of 0 characters"),
        ({"display_name": "x" * 201}, "display_name: is a string of 201 characters"),
    ],
)
def test_a_bad_submission_field_is_one_line_naming_it(planner, submission, message):
    with pytest.raises(InputError) as err:
        run_bench(tiny_suite(), planner, submission=submission)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_bench_run_takes_the_sharing_options_and_refuses_a_link_before_the_work(tmp_path, capsys, registered):
    out = tmp_path / "e.json"
    base = ["bench", "run", "--suite", "tiny2", "--planner", "optimal", "--quiet", "--out", str(out)]
    assert main([*base, "--paper", "ftp://e.org/p"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--paper" in err and "http or https" in err and not out.exists()
    argv = [*base, "--display-name", "Dijkstra", "--author", "A One", "--author", "B Two", "--code", "http://e.org"]
    assert main([*argv, "--external"]) == 0
    entry = json.loads(out.read_text())
    assert entry["submission"]["authors"] == ["A One", "B Two"] and entry["submission"]["external"] is True
    assert main(["bench", "verify", str(out), "--quiet"]) == 0
    board = tmp_path / "board"
    v1 = tmp_path / "v1"
    v1.mkdir()
    committed = get_suite("vin28-quick-v1")
    (v1 / "old.json").write_text(_committed_v1().read_text())
    assert main(["bench", "leaderboard", str(v1), str(out), "--out", str(board), "--quiet"]) == 0
    md = (board / "leaderboard.md").read_text()
    assert "[Dijkstra (optimal)](../e.json)" in md and "(../v1/old.json)" in md
    assert f"{committed.name} ({committed.checksum[:12]}), v1 entries" in md


def test_bench_verify_of_a_v1_entry_or_a_missing_file_is_bad_input(tmp_path, capsys):
    assert main(["bench", "verify", str(_committed_v1())]) == 2
    assert "holds no per-map outcomes" in capsys.readouterr().err
    assert main(["bench", "verify", str(tmp_path / "none.json")]) == 2
    assert "none.json" in capsys.readouterr().err


def test_a_group_must_start_from_an_earlier_one_cell_group():
    groups = (AttackGroup(("random",), "add", 3, start="exhaustive"), AttackGroup(("exhaustive",), "add", 1))
    with pytest.raises(InputError, match="group 0 starts from 'exhaustive', which no earlier group"):
        suites.register(tiny_suite(name="bad-start", attacks=groups))
    assert "bad-start" not in suites.SUITES


def test_a_v1_suite_refuses_the_sharing_options_and_keeps_its_checksum(capsys):
    assert main(["bench", "run", "--suite", "vin28-quick-v1", "--planner", "optimal", "--display-name", "x"]) == 2
    assert "--display-name: suite vin28-quick-v1's entries" in capsys.readouterr().err
    assert {name: suites.SUITES[name].checksum for name in FROZEN} == FROZEN
    for name in ("vin28", "vin28-quick", "mpd32", "mpd32-quick"):
        v1, v2 = get_suite(f"{name}-v1"), get_suite(f"{name}-v2")
        assert v2.definitions == 2 and v2.entry_format == "vinadv.bench_entry/2"
        assert (v2.n, v2.maps_sha256, v2.chunk) == (v1.n, v1.maps_sha256, v1.chunk)
        exhaustive = any("exhaustive" in g.strategies and g.edit == "add" for g in v1.attacks)
        assert any(g.start == "exhaustive" for g in v2.attacks) == exhaustive


def _committed_v1() -> Path:
    return Path(__file__).resolve().parents[2] / "docs" / "results" / "bench" / "vin28-quick-v1.optimal.json"


COMMITTED = Path(__file__).resolve().parents[2] / "docs" / "results" / "bench"


def test_every_committed_v2_entry_follows_from_its_outcomes_with_a_monotone_k_curve():
    paths = sorted(COMMITTED.glob("*-v2.*.json"))
    assert paths, "no committed -v2 entry"
    for path in paths:
        entry = read_entry(path)
        assert verify_entry(entry)["differences"] == [], path.name
        worst = entry["worst_case"]
        for a, b in zip(worst, worst[1:]):
            assert a["harmful"] <= b["harmful"] and a["broken"] <= b["broken"] and a["valid"] == b["valid"], path.name


def test_bench_verify_names_the_field_of_a_tampered_committed_entry(tmp_path, capsys):
    source = COMMITTED / "vin28-quick-v2.wastar-w2.json"
    assert main(["bench", "verify", str(source)]) == 0
    assert "every figure follows from its per-map outcomes" in capsys.readouterr().out
    entry = json.loads(source.read_text())
    record = entry["per_map"]["attacks"]["remove:saliency"][0]
    m = record["label"].index("UcP")
    record["label"][m], record["harmful"][m], record["regret"][m] = "UrP", True, None
    tampered = tmp_path / "t.json"
    tampered.write_text(json.dumps(entry))
    assert main(["bench", "verify", str(tampered), "--json"]) == 1
    lines = json.loads(capsys.readouterr().out)["differences"]
    assert "field 'attacks.remove:saliency.by_obstacles[0].harmful': " in "\n".join(lines)
    assert all(line.startswith("field '") for line in lines)


@pytest.mark.slow
def test_a_chunk_of_a_committed_v2_entry_recomputes_byte_for_byte():
    entry = read_entry(COMMITTED / "vin28-quick-v2.astar.json")
    planner = load_planner("astar", 28)
    assert verify_entry(entry, chunks=1, seed=0, planner=planner)["differences"] == []


def _with_efforts(efforts: list) -> MapOutcomes:
    """An attack whose three maps each got a valid pair, with the effort ratios `efforts` (None: none)."""
    valid = np.ones(len(efforts), dtype=bool)
    return MapOutcomes(
        pair=valid,
        valid=valid,
        broken=~valid,
        harmful=~valid,
        regret=np.zeros(len(efforts)),
        label=np.full(len(efforts), "DP"),
        effort=np.array([np.nan if e is None else e for e in efforts]),
    )


def test_worst_efforts_are_the_largest_over_at_most_k_edits_and_verify_checks_them(entry, registered):
    assert "worst_effort" not in entry["per_map"]  # a VIN reports no expansions: no efforts, no worst efforts
    per_k = [[[1.0, None, 2.0]], [[0.5, 3.0, None], [None, None, 4.0]], []]  # per k, each attack's efforts per map
    outcomes = [[_with_efforts(efforts) for efforts in attacks] for attacks in per_k]
    assert [[None if np.isnan(v) else v for v in o.effort.tolist()] for o in worst_case_within(outcomes)] == [
        [1.0, None, 2.0],
        [1.0, 3.0, 4.0],
        [1.0, 3.0, 4.0],
    ]
    bad = json.loads(json.dumps(entry))
    for records in bad["per_map"]["attacks"].values():
        for record in records:
            record["effort"] = [float(record["k"])] * 3
    (line,) = verify_entry(bad)["differences"]  # the efforts give worst efforts the entry does not hold
    assert line.startswith("field 'per_map.worst_effort': null in the entry, [[1.0, 1.0, 1.0], [2.0, 2.0, 2.0], ")


def test_the_leaderboard_reads_a_file_named_twice_once(tmp_path):
    source = COMMITTED / "vin28-quick-v2.astar.json"
    entries = read_entries([source, COMMITTED, source.parent / ".." / "bench" / source.name])
    assert [p.name for p, _ in entries].count(source.name) == 1
    assert len(entries) == len(list(COMMITTED.glob("*.json")))
    with pytest.raises(InputError, match="no such folder or file"):
        read_entries([tmp_path / "none"])
