"""The measured pages cannot go stale: each table and sentence of `docs/measured.py` is read from the JSON the
benchmark scripts commit, and another JSON gives another text (nothing is copied by hand)."""

import importlib.util
import json
import re
from pathlib import Path

import pytest
import torch
from torch.utils.flop_counter import FlopCounterMode

from tests.docs_hooks import DOCS, ROOT, WEIGHTS, docs_module, filled_page
from vinadv.planners.vin.arrays import VINConfig
from vinadv.planners.vin.model import VIN


def _mpd_record(opt: float) -> dict:
    search = {"rows": 100, "opt": opt, "exp": None, "hmean": None, "success": 0.5, "expansions": None}
    by_k = {"k": 1, "maps": 20, "valid": 19, "harmful_rate": 0.25, "paper_success_rate": 0.1, "mean_regret": 0.5}
    k2 = {**by_k, "k": 2, "harmful_rate": 0.5, "paper_success_rate": 0.2, "mean_regret": 1.25}
    return {
        "families": [
            {
                "family": "forest",
                "import": "vinadv maps import F",
                "planners": [{"planner": "optimal", "command": "vinadv eval --planner optimal", "search": search}],
            }
        ],
        "robustness": [
            {
                "family": "forest",
                "planner": "vin",
                "command": "vinadv robustness --planner vin --weights <weights>/vin32.pt",
                "weights_sha256": "ab12",
                "figures": {
                    "clean": {"success_rate": 1.0},
                    "strategies": {"random": {"by_obstacles": [by_k, k2]}},
                    "overall": [by_k, k2],
                },
            }
        ],
    }


def test_the_mp_benchmark_page_is_read_from_its_json(tmp_path):
    measured = docs_module("measured")
    filled = filled_page("results/mpd.md")
    data = json.loads(measured.MPD_JSON.read_text())
    assert len(data["families"]) == 6 and "a982a04" in data["source"]
    for family in data["families"]:
        assert family["import"] in filled
        for entry in family["planners"]:
            assert entry["command"] in filled and "shared" not in entry["command"]
            fig = entry["search"]
            assert f"| {family['family']} | `{entry['planner']}` | {fig['rows']} | {fig['opt']:.3f} |" in filled
    assert {"wastar:w=2", "neural-astar", "astar", "optimal"} <= {run["planner"] for run in data["robustness"]}
    assert {run["family"] for run in data["robustness"]} == {family["family"] for family in data["families"]}
    assert all(len(run["figures"]["overall"]) == 3 for run in data["robustness"])
    # another JSON gives another table: nothing is copied by hand
    path = tmp_path / "mpd.json"
    path.write_text(json.dumps(_mpd_record(0.125)))
    assert measured.mpd_table(path).splitlines()[2] == "| forest | `optimal` | 100 | 0.125 | — | — | 50.0% | — |"
    row = "| forest | `vin` | 19 of 20 | 100.0% | 25.0% / 50.0% | 10.0% / 20.0% | 1.250 |"
    assert measured.mpd_robustness(path).splitlines()[2] == row
    assert measured.mpd_robustness_strategies(path).splitlines()[2] == "| forest | `vin` | 25.0% / 50.0% |"
    commands = measured.mpd_commands(path)
    assert "vinadv robustness --planner vin --weights <weights>/vin32.pt" in commands
    assert "vin: weights with SHA-256 ab12" in commands


def _map_size_record() -> dict:
    fma = {"h_conv": 1, "r_conv": 1, "q_conv_of_r": 1, "value_iteration": 1, "forward": 4_500_000, "engine": 2_000_000}
    row = {
        "size": 28,
        "weights": "w.pt",
        "k": 36,
        "maps": 500,
        "value_maps_per_s": 4321.0,
        "value_maps_share_of_fma_peak": 0.125,
        "engine_plans_per_s": 12345.6,
        "near_tie_maps": 3,
        "attack_share_of_fma_peak": 0.5,
        "attack_s_per_map": 0.0456,
        "candidates_per_map": 401.2,
        "fma_per_map": fma,
        "fma_limit_plans_per_s": 50000.0,
        "engine_share_of_fma_peak": 0.25,
        "growth_from_first": {
            "value_map_time_per_map": 1.0,
            "engine_time_per_map": 1.0,
            "fma_per_map": 1.0,
            "attack_time_per_map": 1.0,
            "attack_fma_per_map": 1.0,
        },
    }
    machine = {"cpu": "C", "cores": 2, "engine_threads": 2, "fma_peak_per_s": 1e11}
    return {
        "command": "python perf/map_size.py --sizes 28",
        "machine": {**machine, "load_average_before": 1.5, "load_average_after": 2.5},
        "sizes": [row],
    }


def test_the_map_size_table_is_read_from_its_json(tmp_path):
    measured = docs_module("measured")
    assert "<!-- vinadv:map-size-table -->" in (DOCS / "guide" / "gpu.md").read_text()
    filled = filled_page("guide/gpu.md")
    data = json.loads(measured.MAP_SIZE_JSON.read_text())
    assert data["command"] in filled
    assert [row["size"] for row in data["sizes"]] == [28, 32, 64]
    for row in data["sizes"]:
        assert f"| {row['size']}x{row['size']} | {row['k']} | {row['fma_per_map']['engine'] / 1e6:.1f} M" in filled
        assert f"| {row['engine_plans_per_s']:,.0f} ({row['near_tie_maps']} of {row['maps']:,}) |" in filled
    # another JSON gives another table: nothing is copied by hand
    path = tmp_path / "map_size.json"
    path.write_text(json.dumps(_map_size_record()))
    table = measured.map_size_table(path)
    assert table.splitlines()[2] == (
        "| 28x28 | 36 | 2.0 M (4.5 M) | 50,000 | 4,321 (12.5%) | 12,346 (3 of 500) | 401 | 0.0456 s (50.0%) "
        "| 1.0x / 1.0x / 1.0x | 1x / 1x |"
    )
    assert "load average 1.5 before and 2.5 after" in table


def _neural_astar_record() -> dict:
    same = {"searches": 100, "identical_paths": 99, "identical_expansions": 98}
    search = {"rows": 100, "opt": 0.8, "exp": 0.5, "hmean": 0.6, "success": 1.0, "expansions": 60.0}
    search["astar_expansions"] = 150.0
    seed = {
        "seed": 7,
        "import": "vinadv maps import --format mpd <data-dir>/mazes_032_moore_c8.npz --seed 7",
        "compare_modes": {"command": "vinadv neural-astar compare-modes --data <work>/m7.npz", "figures": same},
        "eval": {"command": "vinadv eval --data <work>/m7.npz", "search": search},
    }
    seed8 = {**seed, "seed": 8, "eval": {**seed["eval"], "search": {**search, "opt": 0.9, "hmean": 0.7}}}
    rate = {"astar": 5000.0, "neural-astar exact": 10.0, "encoder only": 12.5, "differentiable": 4.0}
    speed = {
        "source": "<data-dir>/mazes_032_moore_c8.npz: 100 test maps",
        "rows": 100,
        "device": "cpu",
        "numba_threads": 2,
        "torch_threads": 1,
        "mean_expansions": {"astar": 62.5, "neural-astar": 35.25},
        "plans_per_s": {**rate, "differentiable + gradient": 1.0},
        "exact_over_differentiable": 2.5,
        "astar_over_neural_exact": 500.0,
        "identical_searches": 100,
    }
    machine = {"cpu": "C", "cores": 2, "torch": "9.9", "niceness": 10}
    return {
        "command": "python perf/neural_astar_table.py --data-dir <data-dir>",
        "date": "2026-01-02 03:04 UTC",
        "source": "S",
        "machine": {**machine, "load_average_before": 1.5, "load_average_after": 2.5},
        "modes": [seed, seed8],
        "speed": {"command": "python perf/neural_astar.py --rounds 4", "rounds": 4, "figures": speed},
    }


def test_the_neural_astar_measurements_are_read_from_their_json(tmp_path):
    measured = docs_module("measured")
    page = (DOCS / "guide" / "neural-astar.md").read_text()
    for name in ("neural-astar-modes", "neural-astar-speed", "neural-astar-commands"):
        assert page.count(f"<!-- vinadv:{name} -->") == 1
    # the section as written holds no table and no measured number: the hook brings them all
    section = page.split("\n## Measured\n", 1)[1].split("\n## ", 1)[0]
    assert not [line for line in section.splitlines() if line.startswith("|")]
    assert not re.search(r"\d\.\d|times as fast|\d+ of \d+", section)
    filled = filled_page("guide/neural-astar.md")
    data = json.loads(measured.NEURAL_ASTAR_JSON.read_text())
    assert [entry["seed"] for entry in data["modes"]] == [0, 1, 2, 3, 4] and "a982a04" in data["source"]
    assert data["command"] in filled and data["speed"]["command"] in filled
    for entry in data["modes"]:
        commands = [entry["import"], entry["compare_modes"]["command"], entry["eval"]["command"]]
        for command in commands:
            assert command in filled and "shared" not in command and "/tmp" not in command
        same, fig = entry["compare_modes"]["figures"], entry["eval"]["search"]
        assert f"| {entry['seed']} | {same['searches']} | {same['identical_paths']} | " in filled
        assert f" | {fig['opt']:.2f} | {fig['exp']:.3f} | {fig['hmean']:.3f} | " in filled
    speed = data["speed"]["figures"]
    assert "/tmp" not in json.dumps(data) and "shared" not in json.dumps(data)
    assert f"| {speed['plans_per_s']['astar']:,.1f} |" in filled
    assert f"load average {data['machine']['load_average_before']} before" in filled
    # another JSON gives other tables and other ratios: nothing is copied by hand
    path = tmp_path / "neural_astar.json"
    path.write_text(json.dumps(_neural_astar_record()))
    modes = measured.neural_astar_modes(path).splitlines()
    assert modes[2] == "| 7 | 100 | 99 | 98 | 0.80 | 0.500 | 0.600 | 100.0% | 60.0 (150.0) |"
    assert modes[4] == (
        "| all | 200 | 198 (99.0%) | 196 (98.0%) | 0.850 | 0.500 | 0.650 (mean of the 2) | 100.0% | 60.0 (150.0) |"
    )
    assert "Measured 2026-01-02 03:04 UTC on C (2 cores), PyTorch 9.9, niceness 10, load average 1.5" in modes[-1]
    speed_text = measured.neural_astar_speed(path)
    assert speed_text.startswith("| search (`<data-dir>/mazes_032_moore_c8.npz`: 100 test maps, one start each; ")
    assert "| `astar` (compiled, unit costs) | 5,000.0 |" in speed_text
    assert "plans 2.5 times as fast as the differentiable search" in speed_text
    assert "(100 of 100 in the same run); the encoder (the CNN) is 80.0% of its time" in speed_text
    assert "`astar` plans 500 times as fast" in speed_text and "best of 4 rounds" in speed_text
    assert "vinadv eval --data <work>/m7.npz" in measured.neural_astar_commands(path)
    record = _neural_astar_record()
    record["speed"]["figures"]["plans_per_s"]["encoder only"] = 9.0  # the exact mode's best round beat the encoder's
    path.write_text(json.dumps(record))
    assert "the encoder alone took as long as the whole of it (111.1%: " in measured.neural_astar_speed(path)


def _vin64_files(folder: Path) -> Path:
    """A made-up `vin64_reach.json` and the weights records the 64x64 VIN's section reads, in `folder`."""
    figures = {"maps": 10, "seed": 3, "size": 64, "starts_per_map": 7, "rollouts": 70}
    runs = [
        {"k": 9, "command": "vinadv vin eval --k 9", "figures": {**figures, "success_rate": 0.5, "optimal_rate": 0.25}}
    ]
    record = {
        "command": "python perf/vin64_reach.py --n 10",
        "date": "2026-01-02 03:04 UTC",
        "transfer": [{"weights": "a28.pt", "export": "vinadv vin export-weights a28.pt", "runs": runs}],
        "reach": {
            "maps": 20,
            "size": 64,
            "seed": 4,
            "starts_per_map": 1,
            "longest_from_a_start": 77,
            "cells": 1234,
            "cells_within": {"50": 0.75, "70": 0.875},
            "farthest_cell_median": 40.5,
            "farthest_cell_p99": 66.0,
            "farthest_cell_max": 90,
        },
    }
    (folder / "a28.json").write_text(json.dumps({"train_config": {"vi_init": "shift"}}))
    epochs = [{"val_action_accuracy": 0.9}, {"val_action_accuracy": 0.95}]
    hardware = {"cpu_model": "C", "cpu_count": 4, "torch_threads": 2}
    training = {"epochs_done": 2, "wall_time_s": 90.0, "hardware": hardware, "epochs": epochs, "model": {"k": 20}}
    (folder / "vin64.json").write_text(json.dumps(training))
    by_length = [
        {"moves": [10, 14], "rollouts": 90, "success_rate": 1.0},
        {"moves": [15, 19], "rollouts": 8, "success_rate": 0.5},
        {"moves": [20, 24], "rollouts": 2, "success_rate": 0.0},
    ]
    held_out = {"maps": 50, "size": 64, "seed": 1000, "rollouts": 100, "success_rate": 0.94, "command": "vinadv x"}
    held_out |= {"terminations": {"goal": 94}, "by_length": by_length}
    (folder / "vin64.metrics.json").write_text(json.dumps(held_out))
    path = folder / "vin64_reach.json"
    path.write_text(json.dumps(record))
    return path


def test_the_vin64_section_is_read_from_its_json_and_the_weights_files(tmp_path):
    hooks, measured = docs_module("hooks"), docs_module("measured")
    page = (DOCS / "guide" / "planners.md").read_text()
    section = page.split("\n### The 64x64 VIN (`vin64.pt`)\n", 1)[1].split("\n## ", 1)[0]
    for name in ("vin64-transfer", "vin64-reach", "vin64-training", "vin64-held-out"):
        marker = f"<!-- vinadv:{name} -->"
        assert page.count(marker) == 1 and marker in section
    # the prose holds no measured number: no percentage, and no decimal but the settings (k = 1.3 N) outside code
    prose = re.sub(r"```.*?```", "", section, flags=re.S)
    assert "%" not in prose and re.findall(r"\d+\.\d+", prose) == ["1.3"]
    assert not re.search(r"\d+ minutes|median \d|\d+ of the \d", prose)
    filled = hooks.on_page_markdown(section, page=None, config=None, files=None)
    assert "<!-- vinadv:" not in filled
    data = json.loads(measured.VIN64_JSON.read_text())
    assert data["command"] in filled and "/tmp" not in json.dumps(data)
    for entry in data["transfer"]:
        assert entry["export"] in filled and (WEIGHTS / entry["weights"]).is_file()
        for run in entry["runs"]:
            assert run["command"] in filled
            assert f" | {run['k']} | {measured.percent(run['figures']['success_rate'])} of " in filled
    assert f"within {max(data['reach']['cells_within'], key=int)} moves" in filled
    training = json.loads((WEIGHTS / "vin64.json").read_text())
    assert f"took {training['wall_time_s'] / 60:.1f} minutes" in filled
    assert measured.percent(training["epochs"][-1]["val_action_accuracy"]) in filled
    metrics = json.loads((WEIGHTS / "vin64.metrics.json").read_text())
    assert f"from {measured.percent(metrics['success_rate'])} of the {metrics['rollouts']:,} starts" in filled
    # other files give other text: nothing is copied by hand
    path = _vin64_files(tmp_path)
    assert measured.vin64_transfer(path, tmp_path).splitlines()[2] == "| `a28.pt` | `shift` | 9 | 50.0% of 70 | 25.0% |"
    assert "on 10 generated 64x64 maps (seed 3, 7 starts each)" in measured.vin64_transfer(path, tmp_path)
    assert measured.vin64_reach(path) == (
        "On the generator's first 20 64x64 maps of seed 4 (one start each, the training set's settings) the longest "
        "optimal path from a start has 77 moves, and 87.5% of the 1,234 free cells that reach the goal do so within 70 "
        "moves; within 50 moves: 75.0%; the per-map farthest cell has median 40.5, 99th percentile 66 and at most 90 "
        "moves (`python perf/vin64_reach.py --n 10`, 2026-01-02 03:04 UTC)"
    )
    assert measured.vin64_training(tmp_path) == (
        "The 2 epochs took 1.5 minutes on C (4 cores, 2 torch threads; `vin64.json`); validation action accuracy "
        "after epochs 1 to 2: 90.0% / 95.0%"
    )
    assert measured.vin64_held_out(tmp_path).endswith(
        "from 94.0% of the 100 starts (`vinadv x`); of the 6 starts it misses, 6 are among the 10 (10.0% of the "
        "starts) whose optimal path has 15 moves or more"
    )


@pytest.mark.slow  # loads the benchmark script and what it imports: seconds
def test_the_published_fma_count_is_the_forwards_as_pytorch_counts_it():
    # perf/map_size.py's formula against PyTorch's own count of the VIN's convolutions (2 flops a multiply-add)
    spec = importlib.util.spec_from_file_location("map_size", ROOT / "perf" / "map_size.py")
    map_size = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(map_size)
    for size, k, l_h in ((8, 3, 150), (11, 5, 7)):
        config = VINConfig(k=k, l_h=l_h)
        with FlopCounterMode(display=False) as counter:
            VIN(config).q_values(torch.zeros(1, 2, size, size))
        fma = map_size.fma_per_map(size, k, config.l_i, config.l_h, config.l_q)
        assert 2 * fma["forward"] == counter.get_total_flops()
        assert fma["forward"] == fma["h_conv"] + fma["r_conv"] + fma["q_conv_of_r"] + fma["value_iteration"]
        # the engine's count: h and r folded into one 2 -> 1 convolution, the rest as the forward
        assert fma["engine"] == fma["forward"] - fma["h_conv"] - fma["r_conv"] + size * size * 9 * config.l_i


def test_the_suite_times_render_from_their_committed_json():
    measured = docs_module("measured")
    data = json.loads(measured.SUITE_TIMES_JSON.read_text())
    page = filled_page("development.md")
    table = measured.suite_times()
    assert table in page and data["commit"] in table and f"{data['whole_suite_median_s']:.1f} s" in table
    assert len(data["runs"]) == len(data["whole_suite_s"]) == len(data["quick_tier_s"])
    if "base" in data:  # both commits' rows, and the ratio of the whole suites' medians
        ratio = data["whole_suite_median_s"] / data["base"]["whole_suite_median_s"]
        assert f"`{data['base']['commit']}`" in table and f"whole suite {ratio:.2f}x" in table


def test_the_neural_astar_page_gives_each_search_one_expansion_count():
    # the speed run draws its own starts: its mean expansions (35.2 / 62.1) beside the modes table's (63.5 / 148.0)
    # read as two counts for one search; an expansion count on the page is one the eval commands measured
    filled = filled_page("guide/neural-astar.md")
    data = json.loads(docs_module("measured").NEURAL_ASTAR_JSON.read_text())
    searches = [entry["eval"]["search"] for entry in data["modes"]]
    measured = {f"{fig[key]:.1f}" for fig in searches for key in ("expansions", "astar_expansions")}
    rows = [fig["rows"] for fig in searches]
    for key in ("expansions", "astar_expansions"):  # the modes table's last row: over all seeds
        measured.add(f"{sum(fig[key] * n for fig, n in zip(searches, rows, strict=True)) / sum(rows):.1f}")
    given = re.findall(r"(\d[\d,]*\.\d+) expansions", filled) + re.findall(r"\| (\d+\.\d) \((\d+\.\d)\) \|", filled)
    given = [number for found in given for number in ([found] if isinstance(found, str) else found)]
    assert given and set(given) <= measured, f"expansion counts not from the eval figures: {set(given) - measured}"


def test_the_transpath_page_is_read_from_its_json(tmp_path):
    measured = docs_module("measured")
    filled = filled_page("results/transpath.md")
    data = json.loads(measured.TRANSPATH_JSON.read_text())
    assert len(data["families"]) == 4
    for family in data["families"]:
        assert all(command in filled for command in family["import"])
        assert any("--size 64" in c or "--crop 64" in c or "--format transpath" in c for c in family["import"])
        for entry in family["planners"]:
            assert entry["command"] in filled
    for run in data["robustness"]:
        assert run["command"] in filled and len(run["figures"]["overall"]) == 3
    planners = {"transpath-cf", "transpath-focal", "astar", "wastar:w=2", "optimal", "vin64", "neural-astar"}
    assert planners == {run["planner"] for run in data["robustness"]}
    assert {run["family"] for run in data["robustness"]} == {family["family"] for family in data["families"]}
    # each family keeps its rule, as the page says: the crops without corner cutting, Neural A*'s twin on moore moves
    rules = {
        (run["family"].split()[0], run["figures"]["settings"]["moves"], run["figures"]["settings"]["corner_cutting"])
        for run in data["robustness"]
    }
    assert rules == {
        ("generated", "octile", True),
        ("Moving", "octile", False),
        ("TransPath's", "octile", True),
        ("generated", "moore", True),
    }
    assert {run["planner"] for run in data["robustness"] if run["figures"]["settings"]["moves"] == "moore"} == {
        "neural-astar",
        "astar",
    }
    assert "vin64" not in {run["planner"] for run in data["robustness"] if run["family"].startswith("Moving")}
    # another JSON gives another table of TransPath's ratios: nothing is copied by hand
    record = _mpd_record(0.5)
    ratios = {"rows": 7, "kept": 4, "hardness": 1.05, "expansions_ratio": 0.25, "cost_ratio": 1.0625}
    ratios |= {"unreached": 1, "expansions": 12.0, "vanilla_expansions": 48.0}
    record["families"][0]["planners"][0]["search"]["transpath"] = ratios
    path = tmp_path / "transpath.json"
    path.write_text(json.dumps(record))
    row = "| forest | `optimal` | 4 of 7 | 0.250 | 1.062 | 1 | 12.0 | 48.0 |"
    assert measured.transpath_ratios(path).splitlines()[2] == row


def test_the_transpath_families_render_in_their_order_with_effort_where_measured(tmp_path):
    measured = docs_module("measured")
    record = _mpd_record(0.5)
    forest = record["families"][0]
    forest |= {"import": ["vinadv maps import A", "vinadv maps concat A B"], "robustness_maps": 20, "seconds": 600}
    search = {**forest["planners"][0]["search"], "rows": 7, "expansions": 30.0, "astar_expansions": 40.0}
    astar = {"planner": "astar", "command": "vinadv eval --planner astar", "search": search}
    record["families"].insert(0, {"family": "zoo", "import": "vinadv maps generate Z", "planners": [astar]})
    run = record["robustness"][0]
    effort = [{**point, "effort_harmful_rate": rate} for point, rate in zip(run["figures"]["overall"], (0.5, 0.75))]
    searched = {**run, "family": "zoo", "planner": "astar", "figures": {**run["figures"], "overall": effort}}
    run["figures"]["seconds"], searched["figures"]["seconds"] = 12.4, 3.0
    record["robustness"].append(searched)
    path = tmp_path / "transpath.json"
    path.write_text(json.dumps(record))
    # the JSON's order (zoo first), not the names' (forest first), and A*'s expansions beside its own
    table = measured.mpd_table(path, "maps", keep_order=True).splitlines()
    assert [line.split(" | ")[0] for line in table[2:]] == ["| zoo", "| forest"]
    assert table[2].endswith("| 30.0 (40.0) |")
    assert measured.mpd_table(path, "maps").splitlines()[2].startswith("| forest |")
    robustness = measured.mpd_robustness(path, "maps", keep_order=True, seconds=True).splitlines()
    assert "effort-harmful, k = 1 / 2 / ..." in robustness[0] and robustness[0].endswith("| seconds |")
    effort = "| 50.0% / 75.0% |"
    assert robustness[2] == f"| zoo | `astar` | 19 of 20 | 100.0% | 25.0% / 50.0% | 10.0% / 20.0% {effort} 1.250 | 3 |"
    assert robustness[3] == "| forest | `vin` | 19 of 20 | 100.0% | 25.0% / 50.0% | 10.0% / 20.0% | — | 1.250 | 12 |"
    strategies = measured.mpd_robustness_strategies(path, keep_order=True).splitlines()
    assert [line.split(" | ")[0] for line in strategies[2:]] == ["| zoo", "| forest"]
    families = measured.transpath_families(path).splitlines()
    assert families[2] == "| zoo | 7 | — | `astar` | — |"
    assert families[3] == "| forest | 100 | 20 | `optimal` | 10 min |"
    commands = measured.mpd_commands(path)
    assert commands.index("vinadv maps generate Z") < commands.index("vinadv maps import A")
    assert commands.index("vinadv maps import A") < commands.index("vinadv maps concat A B")


def test_the_transpath_script_merges_families_and_planners_run_apart(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "perf"))  # the script imports perf/common.py as `common`
    spec = importlib.util.spec_from_file_location("transpath_table", ROOT / "perf" / "transpath_table.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)

    def family(name: str, made: str, planners: list[str]) -> dict:
        entries = [{"planner": p, "command": f"eval {name} {p} {made}"} for p in planners]
        return {"family": name, "import": [made], "robustness_maps": 5, "planners": entries, "seconds": 60.0}

    def record(families: list[dict], run: str) -> dict:
        runs = [{"family": f["family"], "planner": e["planner"], "run": run} for f in families for e in f["planners"]]
        return {"robustness_settings": {"max_obstacles": 3}, "runs": [run], "families": families, "robustness": runs}

    old = record([family("a", "gen 1", ["cf", "astar"]), family("b", "crop 1", ["cf", "astar"])], "old")
    # a's cf again on the same maps, b on other maps, c new
    new = record([family("a", "gen 1", ["cf"]), family("b", "crop 2", ["astar"]), family("c", "ex", ["cf"])], "new")
    merged = script.merge_record(old, new)
    assert [f["family"] for f in merged["families"]] == ["a", "b", "c"]
    assert [e["command"] for e in merged["families"][0]["planners"]] == ["eval a cf gen 1", "eval a astar gen 1"]
    assert [e["planner"] for e in merged["families"][1]["planners"]] == ["astar"]  # b's old maps went with cf
    # the time of a family's run where it made every planner's figures, not where some come from another run
    assert [f["seconds"] for f in merged["families"]] == [None, 60.0, 60.0]
    runs = {(r["family"], r["planner"]): r["run"] for r in merged["robustness"]}
    assert runs == {("a", "cf"): "new", ("a", "astar"): "old", ("b", "astar"): "new", ("c", "cf"): "new"}
    assert merged["runs"] == ["old", "new"]


def _transpath_cost_record() -> dict:
    """A made-up `perf/transpath.py --out` record: every time and ratio other than any measured one."""
    models = ("transpath-cf", "transpath-focal")
    per_map = {"astar plan": 0.002}
    for model, scale in zip(models, (1.0, 2.0), strict=True):
        per_map |= {f"{model} forward": 0.25 * scale, f"{model} plan": 0.5 * scale}
        per_map |= {f"{model} replica search": 0.0005 * scale, f"{model} differentiable search": 0.125 * scale}
    attacks = {
        "random": {"astar": 0.01, "transpath-cf": 0.5, "transpath-focal": 0.75, "maps": 4},
        "exhaustive": {"astar": 1.5, "transpath-cf": 250.0, "transpath-focal": 300.0, "maps": 1},
    }
    attacks["exhaustive"]["candidates_per_map"] = 2718.0
    ratios = {}
    for model, scale in zip(models, (1.0, 2.0), strict=True):
        ratios[f"{model}: differentiable search / replica search"] = 250.0
        ratios[f"{model}: forward / astar plan"] = 125.0 * scale
        ratios[f"{model}: plan / astar plan"] = 250.0 * scale
        for strategy, row in attacks.items():
            ratios[f"{model}: {strategy} / astar {strategy}"] = round(row[model] / row["astar"], 1)
    figures = {"maps": "generate_maps(4, 64, seed=9, n_starts=1), corner cutting", "rounds": 2, "torch_threads": 1}
    figures |= {"seconds_per_map": per_map, "ratios": ratios, "attack_seconds_per_map": attacks}
    figures["identical_searches"] = {"transpath-cf": "4/4", "transpath-focal": "3/4"}
    machine = {"cpu": "C", "cores": 2, "niceness": 10, "load_average_before": 3.5, "load_average_after": 4.25}
    command = "python perf/transpath.py --n 4 --seed 9 --rounds 2 --exhaustive-maps 1 --out OUT"
    return {
        "command": command,
        "date": "2026-01-02 03:04 UTC",
        "machine": machine,
        "seconds": 600.0,
        "figures": figures,
    }


def test_the_transpath_cost_is_read_from_its_json(tmp_path):
    measured = docs_module("measured")
    page = (DOCS / "guide" / "transpath.md").read_text()
    assert page.count("<!-- vinadv:transpath-cost -->") == 1
    assert page.count("<!-- vinadv:transpath-exhaustive-cost -->") == 1
    # the section as written holds no table and no measured number: the hook brings them all
    section = page.split("**Cost.**", 1)[1].split("\n## ", 1)[0]
    assert not [line for line in section.splitlines() if line.startswith("|")]
    assert not re.search(r"\d\.\d|\d ms|\d s\b|times as fast|\d+ of \d+|\d,\d{3}|minutes", section)
    data = json.loads(measured.TRANSPATH_COST_JSON.read_text())
    filled = filled_page("guide/transpath.md")
    assert data["command"] in filled and "/tmp" not in data["command"]
    assert (
        data["command"].startswith("python perf/transpath.py ")
        and "--out docs/results/transpath_cost.json" in data["command"]
    )
    exhaustive = data["figures"]["attack_seconds_per_map"]["exhaustive"]  # measured, on at least one map
    assert exhaustive["maps"] >= 1 and exhaustive["candidates_per_map"] > 1000
    assert f"load average {data['machine']['load_average_before']} before" in filled
    assert measured.transpath_exhaustive_cost() in filled_page("results/transpath.md")
    # another JSON gives another table and other ratios: nothing is copied by hand
    path = tmp_path / "transpath_cost.json"
    path.write_text(json.dumps(_transpath_cost_record()))
    table, text = measured.transpath_cost(path).split("\n\n", 1)
    lines = table.splitlines()
    assert lines[0] == "| per 64x64 map (x `astar`'s) | `astar` | `transpath-cf` | `transpath-focal` |"
    assert lines[2] == "| forward (the network alone) | — | 250 ms (125x) | 500 ms (250x) |"
    assert lines[3] == "| plan (forward and compiled search) | 2 ms | 500 ms (250x) | 1 s (500x) |"
    assert lines[4] == "| compiled replica's search (outputs cached) | — | 0.5 ms | 1 ms |"
    assert lines[5] == "| differentiable search (outputs cached, no gradient) | — | 125 ms | 250 ms |"
    assert lines[6] == "| `random` attack, 4 maps | 10 ms | 500 ms (50x) | 750 ms (75x) |"
    assert lines[7] == "| `exhaustive` attack (2,718 candidates a map), 1 map | 1.5 s | 250 s (167x) | 300 s (200x) |"
    assert "was 250 (`cf`) and 250 (`f`) times as fast as the differentiable search" in text
    assert "on 4 of 4 and 3 of 4 maps" in text
    assert "250 to 500 times `astar`'s plan, the forward alone 125 to 250 times" in text
    assert "every attack strategy costs 50 to 200 times `astar`'s per map" in text
    assert "Measured 2026-01-02 03:04 UTC on C (2 cores, 1 torch thread, niceness 10), load average 3.5 " in text
    assert "on `generate_maps(4, 64, seed=9, n_starts=1)` (corner cutting), so" in text
    assert "best of 2 rounds" in text and "The run took 600 s." in text and "--n 4 --seed 9" in text
    sentence = measured.transpath_exhaustive_cost(path)
    assert sentence.startswith("2,718 candidates a map, each one TransPath forward: 250 s with `transpath-cf` and 300")
    assert "against 1.5 s with `astar`" in sentence


def test_the_transpath_cost_script_records_the_command_that_makes_its_record_again(monkeypatch, tmp_path):
    monkeypatch.syspath_prepend(str(ROOT / "perf"))  # the script imports perf/common.py as `common`
    spec = importlib.util.spec_from_file_location("transpath_cost", ROOT / "perf" / "transpath.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    out = ROOT / "docs" / "results" / "transpath_cost.json"
    args = script.argparse.Namespace(n=3, seed=7, rounds=2, exhaustive_maps=1, out=out)
    written = {}
    monkeypatch.setattr(script.Path, "write_text", lambda self, text: written.setdefault(self, text))
    figures = {"maps": "m", "seconds": 12.5, "load_average": {"before": 1.5, "after": 2.0}, "ratios": {}}
    script.write_record(args, figures, "2026-01-02 03:04 UTC")
    record = json.loads(written[out])
    command = (
        "python perf/transpath.py --n 3 --seed 7 --rounds 2 --exhaustive-maps 1 --out docs/results/transpath_cost.json"
    )
    assert record["command"] == command
    assert record["machine"]["load_average_before"] == 1.5 and record["machine"]["load_average_after"] == 2.0
    assert record["seconds"] == 12.5 and record["figures"] == {"maps": "m", "ratios": {}}
    args.out = tmp_path / "elsewhere.json"  # outside the checkout: written as OUT, no private path recorded
    script.write_record(args, figures, "d")
    assert json.loads(written[args.out])["command"].endswith("--out OUT")
