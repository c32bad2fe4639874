"""The documentation cannot go stale: the CLI reference is the parsers' help, the results are the committed metrics.

The site itself is built by `make docs` (`mkdocs build --strict`, in CI); these tests hold what the build cannot see.
"""

import importlib
import importlib.util
import json
import re
from pathlib import Path

import matplotlib.pyplot as plt
import pytest
import torch
from torch.utils.flop_counter import FlopCounterMode

import vinadv.plot.files
from vinadv.attacks.pairs import PAIRS_FORMAT
from vinadv.classify.base import MODEL_FORMAT
from vinadv.cli import build_parser
from vinadv.commands.store import EXPORT_FORMAT
from vinadv.grid.mapset import MAPS_FORMAT
from vinadv.planners.gppn import GPPN_FORMAT
from vinadv.planners.pathset import PATHS_FORMAT
from vinadv.planners.vin.arrays import VINConfig
from vinadv.planners.vin.model import VIN
from vinadv.planners.vin.weights import WEIGHTS_FORMAT

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
WEIGHTS = ROOT / "src" / "vinadv" / "weights"


def docs_module(name: str):
    """A script of docs/ (not a package) loaded from its file."""
    spec = importlib.util.spec_from_file_location(f"docs_{name}", DOCS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_cli_reference_is_the_parsers_help():
    gen_cli = docs_module("gen_cli")
    assert (DOCS / "reference" / "cli.md").read_text() == gen_cli.render(), (
        "docs/reference/cli.md is stale: run .venv/bin/python docs/gen_cli.py"
    )


def test_the_cli_reference_has_every_command():
    gen_cli = docs_module("gen_cli")
    text = gen_cli.render()
    commands = [words for words, _ in gen_cli.walk(build_parser())]
    assert "vinadv maps generate" in commands and "vinadv run" in commands and "vinadv gppn train" in commands
    for words in commands:
        assert f"`{words}`\n\n```text\nusage: {words} " in text


def test_the_results_table_is_read_from_the_metrics_files(tmp_path):
    hooks = docs_module("hooks")
    table = hooks.weights_table()
    for metrics in sorted(WEIGHTS.glob("*.metrics.json")):
        data = json.loads(metrics.read_text())
        figures = data.get("vinadv", data)
        weights = metrics.name.replace(".metrics.json", ".pt")
        row = next(line for line in table.splitlines() if f"| `{weights}` |" in line)
        assert f"{100 * figures['success_rate']:.1f}%" in row or f"{100 * figures['success_rate']:.2f}%" in row
        assert f"{figures['rollouts']:,}" in row
        assert data["command"] in hooks.weights_commands()
    # a re-measured file changes the table: nothing is copied by hand
    (tmp_path / "vin28.metrics.json").write_text(
        json.dumps(
            {
                "weights_sha256": "ab" * 32,
                "command": "vinadv vin eval --n 10",
                "size": 28,
                "success_rate": 0.5,
                "rollouts": 10,
                "optimal_rate": 0.25,
                "action_accuracy": 0.999996,
            }
        )
    )
    assert hooks.weights_table(tmp_path).splitlines()[2] == (
        "| `vin` | `vin28.pt` | 50.0% of 10 | 25.0% | 100.00% |  |  |"
    )


def test_the_hook_fills_the_results_page(monkeypatch):
    hooks = docs_module("hooks")
    monkeypatch.setattr(hooks, "by_length_svg", lambda folder: "<svg/>")  # drawn for real in the slow test below
    page = (DOCS / "results" / "index.md").read_text()
    for marker in (hooks.WEIGHTS_TABLE, hooks.WEIGHTS_COMMANDS, hooks.BY_LENGTH, hooks.BY_LENGTH_FIGURE):
        assert marker in page
    filled = hooks.on_page_markdown(page, page=None, config=None, files=None)
    assert "<!-- vinadv:" not in filled and hooks.weights_table() in filled
    assert "| 25-29 |" in hooks.by_length_table()
    assert "](data:image/svg+xml;base64,PHN2Zy8+)" in filled  # base64 of "<svg/>"


@pytest.mark.slow  # matplotlib's import and a figure: about two seconds
def test_the_length_curve_draws_every_metrics_file_with_rows_by_length():
    hooks = docs_module("hooks")
    svg = hooks.by_length_svg()
    drawn = [e for e in hooks.weights_metrics() if e["vinadv"].get("by_length")]
    assert drawn  # the shipped files record rows by length
    for entry in drawn:
        assert entry["weights"] in svg  # the legend names each file
        for row in entry["vinadv"]["by_length"]:
            assert f"{row['moves'][0]}-{row['moves'][1]}" in svg  # each bucket labelled
    assert svg == hooks.by_length_svg()  # same files, same bytes: the page changes only with the data


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
    hooks = docs_module("hooks")
    page = (DOCS / "results" / "mpd.md").read_text()
    filled = hooks.on_page_markdown(page, page=None, config=None, files=None)
    assert "<!-- vinadv:" not in filled
    data = json.loads(hooks.MPD_JSON.read_text())
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
    assert hooks.mpd_table(path).splitlines()[2] == "| forest | `optimal` | 100 | 0.125 | — | — | 50.0% | — |"
    row = "| forest | `vin` | 20 | 100.0% | 25.0% / 50.0% | 10.0% / 20.0% | 1.250 |"
    assert hooks.mpd_robustness(path).splitlines()[2] == row
    assert hooks.mpd_robustness_strategies(path).splitlines()[2] == "| forest | `vin` | 25.0% / 50.0% |"
    commands = hooks.mpd_commands(path)
    assert "vinadv robustness --planner vin --weights <weights>/vin32.pt" in commands
    assert "vin: weights with SHA-256 ab12" in commands


def test_user_facing_pages_name_public_sources_not_the_workspace():
    pages = [ROOT / "README.md", *DOCS.rglob("*.md")]
    for page in pages:
        assert not re.search(r"shared/data|/work/", page.read_text()), page


NOT_PYTHON = {"vinadv.db", "vinadv.by_length"}  # a database file name; a key of `vinadv eval --json`


def named_objects() -> set[str]:
    """Every `vinadv.x.y` the README and the pages name in code spans, file formats (`vinadv.maps/1`) left out."""
    pages = [ROOT / "README.md", *DOCS.rglob("*.md")]
    names = set()
    for page in pages:
        for name, after in re.findall(r"`(vinadv(?:\.\w+)+)(.?)", page.read_text()):
            if after not in "/-" or not after:
                names.add(name)
    return names - NOT_PYTHON


def test_every_python_name_the_docs_give_exists():
    missing = []
    for name in sorted(named_objects()):
        parts = name.split(".")
        for cut in range(len(parts), 0, -1):  # the longest importable module, then attributes
            try:
                obj = importlib.import_module(".".join(parts[:cut]))
            except ModuleNotFoundError:
                continue
            for attr in parts[cut:]:
                obj = getattr(obj, attr, None)
            if obj is None:
                missing.append(name)
            break
    assert not missing, f"the docs name what the code no longer has: {missing}"


def test_the_readme_is_a_front_page():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    for heading in ("## Install", "## A five-minute tour", "## Documentation", "## Citing", "## Licence"):
        assert f"\n{heading}\n" in text
    for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", text):  # every relative link leads to a file
        assert (ROOT / target).exists(), target


def test_the_readme_results_table_is_the_generated_one():
    hooks = docs_module("hooks")
    assert hooks.readme_table((ROOT / "README.md").read_text()) == hooks.weights_table(), (
        "README.md's results table is stale: run .venv/bin/python docs/hooks.py"
    )


def test_the_formats_page_names_every_file_format_version():
    page = (DOCS / "formats.md").read_text()
    for name in (MAPS_FORMAT, PATHS_FORMAT, PAIRS_FORMAT, WEIGHTS_FORMAT, GPPN_FORMAT, MODEL_FORMAT, EXPORT_FORMAT):
        assert f'"{name}"' in page or f"`{name}`" in page, f"docs/formats.md does not describe {name}"


@pytest.mark.slow  # matplotlib's import and a k curve per suite, drawn: seconds
def test_the_benchmark_page_carries_the_leaderboard_of_the_committed_entries(monkeypatch):
    hooks = docs_module("hooks")
    # the figures are drawn, not rendered to SVG (tests/plot/test_curves.py renders one): a second each
    monkeypatch.setattr(vinadv.plot.files, "svg_text", lambda fig: plt.close(fig) or "<svg/>")
    page = (DOCS / "results" / "bench.md").read_text()
    assert hooks.BENCH_LEADERBOARD in page
    board = hooks.on_page_markdown(page)
    entries = sorted((DOCS / "results" / "bench").glob("*.json"))
    assert entries, "no committed benchmark entry"
    for path in entries:  # every committed entry is a row, linked from the page
        assert f"(bench/{path.name})" in board
    # the compact table in its own box, its legend, and one k curve per suite drawn in place of the marker
    assert '<div class="leaderboard" markdown>' in board and "**harmful, k = 1**:" in board
    assert hooks.BENCH_K_CURVES in page and "<!-- vinadv:" not in board
    suites = {json.loads(p.read_text())["suite"]["name"] for p in entries}
    assert board.count("](data:image/svg+xml;base64,") == len(suites)


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
    hooks = docs_module("hooks")
    page = (DOCS / "guide" / "gpu.md").read_text()
    assert hooks.MAP_SIZE_TABLE in page
    filled = hooks.on_page_markdown(page, page=None, config=None, files=None)
    data = json.loads(hooks.MAP_SIZE_JSON.read_text())
    assert "<!-- vinadv:" not in filled and data["command"] in filled
    assert [row["size"] for row in data["sizes"]] == [28, 32, 64]
    for row in data["sizes"]:
        assert f"| {row['size']}x{row['size']} | {row['k']} | {row['fma_per_map']['engine'] / 1e6:.1f} M" in filled
        assert f"| {row['engine_plans_per_s']:,.0f} ({row['near_tie_maps']} of {row['maps']:,}) |" in filled
    # another JSON gives another table: nothing is copied by hand
    path = tmp_path / "map_size.json"
    path.write_text(json.dumps(_map_size_record()))
    table = hooks.map_size_table(path)
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
    hooks = docs_module("hooks")
    page = (DOCS / "guide" / "neural-astar.md").read_text()
    for marker in (hooks.NEURAL_ASTAR_MODES, hooks.NEURAL_ASTAR_SPEED, hooks.NEURAL_ASTAR_COMMANDS):
        assert page.count(marker) == 1
    # the section as written holds no table and no measured number: the hook brings them all
    measured = page.split("\n## Measured\n", 1)[1].split("\n## ", 1)[0]
    assert not [line for line in measured.splitlines() if line.startswith("|")]
    assert not re.search(r"\d\.\d|times as fast|\d+ of \d+", measured)
    filled = hooks.on_page_markdown(page, page=None, config=None, files=None)
    assert "<!-- vinadv:" not in filled
    data = json.loads(hooks.NEURAL_ASTAR_JSON.read_text())
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
    modes = hooks.neural_astar_modes(path).splitlines()
    assert modes[2] == "| 7 | 100 | 99 | 98 | 0.80 | 0.500 | 0.600 | 100.0% | 60.0 (150.0) |"
    assert modes[4] == (
        "| all | 200 | 198 (99.0%) | 196 (98.0%) | 0.850 | 0.500 | 0.650 (mean of the 2) | 100.0% | 60.0 (150.0) |"
    )
    assert "Measured 2026-01-02 03:04 UTC on C (2 cores), PyTorch 9.9, niceness 10, load average 1.5" in modes[-1]
    speed_text = hooks.neural_astar_speed(path)
    assert speed_text.startswith("| search (`<data-dir>/mazes_032_moore_c8.npz`: 100 test maps, one start each; ")
    assert "| `astar` (compiled, unit costs) | 5,000.0 |" in speed_text
    assert "plans 2.5 times as fast as the differentiable search" in speed_text
    assert "(100 of 100 in the same run); the encoder (the CNN) is 80.0% of its time" in speed_text
    assert "`astar` plans 500 times as fast" in speed_text and "best of 4 rounds" in speed_text
    assert "vinadv eval --data <work>/m7.npz" in hooks.neural_astar_commands(path)
    record = _neural_astar_record()
    record["speed"]["figures"]["plans_per_s"]["encoder only"] = 9.0  # the exact mode's best round beat the encoder's
    path.write_text(json.dumps(record))
    assert "the encoder alone took as long as the whole of it (111.1%: " in hooks.neural_astar_speed(path)


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
    hooks = docs_module("hooks")
    page = (DOCS / "guide" / "planners.md").read_text()
    section = page.split("\n### The 64x64 VIN (`vin64.pt`)\n", 1)[1].split("\n## ", 1)[0]
    markers = (hooks.VIN64_TRANSFER, hooks.VIN64_REACH, hooks.VIN64_TRAINING, hooks.VIN64_HELD_OUT)
    for marker in markers:
        assert page.count(marker) == 1 and marker in section
    # the prose holds no measured number: no percentage, and no decimal but the settings (k = 1.3 N) outside code
    prose = re.sub(r"```.*?```", "", section, flags=re.S)
    assert "%" not in prose and re.findall(r"\d+\.\d+", prose) == ["1.3"]
    assert not re.search(r"\d+ minutes|median \d|\d+ of the \d", prose)
    filled = hooks.on_page_markdown(section, page=None, config=None, files=None)
    assert "<!-- vinadv:" not in filled
    data = json.loads(hooks.VIN64_JSON.read_text())
    assert data["command"] in filled and "/tmp" not in json.dumps(data)
    for entry in data["transfer"]:
        assert entry["export"] in filled and (WEIGHTS / entry["weights"]).is_file()
        for run in entry["runs"]:
            assert run["command"] in filled
            assert f" | {run['k']} | {hooks.percent(run['figures']['success_rate'])} of " in filled
    assert f"within {max(data['reach']['cells_within'], key=int)} moves" in filled
    training = json.loads((WEIGHTS / "vin64.json").read_text())
    assert f"took {training['wall_time_s'] / 60:.1f} minutes" in filled
    assert hooks.percent(training["epochs"][-1]["val_action_accuracy"]) in filled
    metrics = json.loads((WEIGHTS / "vin64.metrics.json").read_text())
    assert f"from {hooks.percent(metrics['success_rate'])} of the {metrics['rollouts']:,} starts" in filled
    # other files give other text: nothing is copied by hand
    path = _vin64_files(tmp_path)
    assert hooks.vin64_transfer(path, tmp_path).splitlines()[2] == "| `a28.pt` | `shift` | 9 | 50.0% of 70 | 25.0% |"
    assert "on 10 generated 64x64 maps (seed 3, 7 starts each)" in hooks.vin64_transfer(path, tmp_path)
    assert hooks.vin64_reach(path) == (
        "On the generator's first 20 64x64 maps of seed 4 (one start each, the training set's settings) the longest "
        "optimal path from a start has 77 moves, and 87.5% of the 1,234 free cells that reach the goal do so within 70 "
        "moves; within 50 moves: 75.0%; the per-map farthest cell has median 40.5, 99th percentile 66 and at most 90 "
        "moves (`python perf/vin64_reach.py --n 10`, 2026-01-02 03:04 UTC)"
    )
    assert hooks.vin64_training(tmp_path) == (
        "The 2 epochs took 1.5 minutes on C (4 cores, 2 torch threads; `vin64.json`); validation action accuracy "
        "after epochs 1 to 2: 90.0% / 95.0%"
    )
    assert hooks.vin64_held_out(tmp_path).endswith(
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


def test_algorithm_stars_are_text_not_emphasis_outside_code():
    hooks = docs_module("hooks")
    text = "Beside A*, weighted A* and **bold** `A*, A*`\n```sh\nA*, A*\n```\nNeural A*'s"
    assert hooks.escape_algorithm_stars(text) == (
        "Beside A\\*, weighted A\\* and **bold** `A*, A*`\n```sh\nA*, A*\n```\nNeural A\\*'s"
    )


def test_the_suite_times_render_from_their_committed_json():
    hooks = docs_module("hooks")
    data = json.loads(hooks.SUITE_TIMES_JSON.read_text())
    page = hooks.on_page_markdown((DOCS / "development.md").read_text())
    assert hooks.SUITE_TIMES not in page
    table = hooks.suite_times()
    assert table in page and data["commit"] in table and f"{data['whole_suite_median_s']:.1f} s" in table
    assert len(data["runs"]) == len(data["whole_suite_s"]) == len(data["quick_tier_s"])
    if "base" in data:  # both commits' rows, and the ratio of the whole suites' medians
        ratio = data["whole_suite_median_s"] / data["base"]["whole_suite_median_s"]
        assert f"`{data['base']['commit']}`" in table and f"whole suite {ratio:.2f}x" in table


def test_the_neural_astar_page_gives_each_search_one_expansion_count():
    # the speed run draws its own starts: its mean expansions (35.2 / 62.1) beside the modes table's (63.5 / 148.0)
    # read as two counts for one search; an expansion count on the page is one the eval commands measured
    hooks = docs_module("hooks")
    filled = hooks.on_page_markdown((DOCS / "guide" / "neural-astar.md").read_text(), page=None)
    data = json.loads(hooks.NEURAL_ASTAR_JSON.read_text())
    searches = [entry["eval"]["search"] for entry in data["modes"]]
    measured = {f"{fig[key]:.1f}" for fig in searches for key in ("expansions", "astar_expansions")}
    rows = [fig["rows"] for fig in searches]
    for key in ("expansions", "astar_expansions"):  # the modes table's last row: over all seeds
        measured.add(f"{sum(fig[key] * n for fig, n in zip(searches, rows, strict=True)) / sum(rows):.1f}")
    given = re.findall(r"(\d[\d,]*\.\d+) expansions", filled) + re.findall(r"\| (\d+\.\d) \((\d+\.\d)\) \|", filled)
    given = [number for found in given for number in ([found] if isinstance(found, str) else found)]
    assert given and set(given) <= measured, f"expansion counts not from the eval figures: {set(given) - measured}"


#: the README's word that the built site, not GitHub's rendering of docs/, is where the pages are read whole
SITE_IS_THE_PLACE = "the site is the place to read the documentation"


def test_pages_github_shows_incomplete_send_the_reader_to_the_site():
    # GitHub renders docs/*.md without the snippets extension and without the hooks: a `--8<--` line shows as itself
    # and a figure's marker as nothing; such pages are allowed only while the README says to read the built site
    incomplete = [
        str(page.relative_to(ROOT))
        for page in sorted(DOCS.rglob("*.md"))
        if re.search(r"^\s*--8<--|<!-- vinadv:", page.read_text(), re.M)
    ]
    assert "docs/own-planner.md" in incomplete and "docs/guide/neural-astar.md" in incomplete
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert SITE_IS_THE_PLACE in readme, (
        f"{incomplete} read incomplete on GitHub; the README must say: {SITE_IS_THE_PLACE}"
    )


def shell_blocks(text: str) -> list[str]:
    return re.findall(r"```(?:sh|bash|console)\n(.*?)```", text, re.S)


def unmade_folders(text: str) -> list[str]:
    """The commands of a page's shell blocks that write a file (`--out`, `--report`, `--db`, `--index`) into a
    relative folder that nothing before them on the page made (`mkdir`, or an output that is a folder)."""
    made, wrong = set(), []
    for block in shell_blocks(text):
        for line in block.splitlines():
            made.update(folder.rstrip("/") for folder in re.findall(r"mkdir (?:-p )?(\S+)", line))
            for value in re.findall(r"--(?:out|report|db|index)[ =](\S+)", line):
                path = Path(value)
                if value.endswith("/") or not path.suffix:  # a folder the command makes
                    made.add(value.rstrip("/"))
                elif (
                    str(path.parent) != "."
                    and not value.startswith(("/", "<", "$", "~"))
                    and str(path.parent) not in made
                ):
                    wrong.append(line.strip())
    return wrong


def test_the_docs_commands_write_only_into_folders_that_exist():
    assert unmade_folders("```sh\nvinadv bench run --out entries/vin.json\n```\n") == [
        "vinadv bench run --out entries/vin.json"
    ]
    assert not unmade_folders("```sh\nmkdir -p entries\nvinadv bench run --out entries/vin.json\n```\n")
    pages = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]
    wrong = {str(p.relative_to(ROOT)): unmade_folders(p.read_text()) for p in pages}
    assert not {page: lines for page, lines in wrong.items() if lines}


def test_a_diagonal_of_sqrt_2_is_said_of_octile_moves():
    # `moore` moves all cost 1 and `news` has no diagonal: a paragraph that gives a diagonal sqrt 2 says it is octile's
    wrong = []
    for page in [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]:
        for paragraph in page.read_text().split("\n\n"):
            if re.search(r"diagonal[^.|]*(sqrt ?\(?2|√2)", paragraph) and "octile" not in paragraph:
                wrong.append(f"{page.relative_to(ROOT)}: {paragraph[:100]}")
    assert not wrong


def test_make_demo_says_how_long_it_takes():
    makefile = (ROOT / "Makefile").read_text()
    recipe = makefile.split("\ndemo:", 1)[1].split("\n\n", 1)[0]
    (echo,) = [line for line in recipe.splitlines() if "@echo" in line and "minutes" in line]
    minutes = re.search(r"about (\d+) minutes", echo).group(1)
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert f"about {minutes} minutes" in readme.split("make demo", 1)[1].split("make test", 1)[0]


def test_the_transpath_page_is_read_from_its_json(tmp_path):
    hooks = docs_module("hooks")
    page = (DOCS / "results" / "transpath.md").read_text()
    filled = hooks.on_page_markdown(page, page=None, config=None, files=None)
    assert "<!-- vinadv:" not in filled
    data = json.loads(hooks.TRANSPATH_JSON.read_text())
    (family,) = data["families"]
    assert family["import"] in filled and "--size 64" in family["import"]
    for entry in family["planners"]:
        assert entry["command"] in filled
    for run in data["robustness"]:
        assert run["command"] in filled and len(run["figures"]["overall"]) == 3
    assert {"transpath-cf", "transpath-focal", "astar"} <= {run["planner"] for run in data["robustness"]}
    # another JSON gives another table of TransPath's ratios: nothing is copied by hand
    record = _mpd_record(0.5)
    ratios = {"rows": 7, "kept": 4, "hardness": 1.05, "expansions_ratio": 0.25, "cost_ratio": 1.0625}
    ratios |= {"unreached": 1, "expansions": 12.0, "vanilla_expansions": 48.0}
    record["families"][0]["planners"][0]["search"]["transpath"] = ratios
    path = tmp_path / "transpath.json"
    path.write_text(json.dumps(record))
    row = "| forest | `optimal` | 4 of 7 | 0.250 | 1.062 | 1 | 12.0 | 48.0 |"
    assert hooks.transpath_ratios(path).splitlines()[2] == row
