"""Provenance and search effort of robustness benchmarks, on the three backends: two runs of one planner on two maps
files are told apart in `vinadv.open(...).robustness()` and in the report, `wastar:w=2` and `wastar:w=3` keep their
parameters, and a search planner's figures carry the effort-harmful rate with its interval; `--objective effort`
runs on `astar` and `neural-astar` (tiny maps)."""

from __future__ import annotations

import pytest

import vinadv
from vinadv import checksums
from vinadv.cli import main
from vinadv.grid import generate_maps
from vinadv.intervals import rate_interval
from vinadv.planners.registry import load_planner
from vinadv.report.build import robustness_report
from vinadv.robustness import robustness


@pytest.mark.slow  # four benchmarks and the report's curves per backend: seconds each
def test_two_maps_files_and_two_weights_are_told_apart(db_url, tmp_path):
    files = []
    for seed in (1, 2):
        path = tmp_path / f"maps{seed}.npz"
        generate_maps(3, 8, seed=seed, n_starts=1).save(path)
        files.append(path)
    base = ["robustness", "--n", "3", "--max-obstacles", "1", "--strategies", "random", "--db", db_url, "--quiet"]
    for i, path in enumerate(files):
        assert main([*base, "--planner", "astar", "--maps", str(path), "--name", f"run {i}"]) == 0
    for w in (2, 3):
        assert main([*base, "--planner", f"wastar:w={w}", "--maps", str(files[0])]) == 0
    with vinadv.open(db_url) as db:
        frame = db.robustness()
    worst = frame[frame.strategy == "worst case"]
    assert list(worst.planner) == ["astar", "astar", "wastar:w=2", "wastar:w=3"]
    assert list(worst.name)[:2] == ["run 0", "run 1"]
    assert list(worst.maps_file)[:2] == [str(p) for p in files]
    assert list(worst.maps_sha256)[:2] == [checksums.file_sha256(p) for p in files]
    # a search planner's figures: the effort-harmful count and its rate's Wilson interval
    for _, row in worst.iterrows():
        assert 0 <= row.effort_harmful <= row.valid
        assert (row.effort_harmful_rate_low, row.effort_harmful_rate_high) == rate_interval(
            int(row.effort_harmful), int(row.valid)
        )
    page = robustness_report(tmp_path / "report", db_url).read_text()
    for text in ("run 0: <code>astar</code>", "run 1: <code>astar</code>", "maps1.npz", "maps2.npz"):
        assert text in page
    assert "<code>wastar:w=2</code>" in page and "<code>wastar:w=3</code>" in page


def test_a_planner_without_expansions_has_no_effort_figures_and_refuses_the_effort_objective():
    maps = generate_maps(2, 8, seed=3, n_starts=1)
    result = robustness(load_planner("optimal", 8), maps, ["random"], 1)
    assert "effort_harmful" not in result.to_dict()["overall"][0] and result.settings["effort_tolerance"] is None
    with pytest.raises(vinadv.errors.InputError, match="reports no expansions"):
        robustness(load_planner("optimal", 8), maps, ["random"], 1, objective="effort")


@pytest.mark.slow
def test_objective_effort_on_neural_astar():
    maps = generate_maps(2, 10, seed=5, n_starts=1, moves="moore")
    planner = load_planner("neural-astar", 10, moves="moore")
    result = robustness(planner, maps, ["near-path"], 1, objective="effort", budget=2)
    figures = result.to_dict()["overall"][0]
    assert result.settings["objective"] == "effort" and result.settings["planner"] == "neural-astar"
    assert 0 <= figures["effort_harmful"] <= figures["valid"] and "effort_harmful_rate_low" in figures
