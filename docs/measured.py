"""The measured pages' figures for `docs/hooks.py`: tables and sentences read from the committed JSON that the
benchmark scripts write with the commands they ran, so that no measured number is copied into a page by hand.

- `docs/results/mpd.md` and `docs/results/transpath.md`: `docs/results/mpd.json` (`perf/mpd_table.py`) and
  `docs/results/transpath.json` (`perf/transpath_table.py`, the same shape): Opt / Exp / Hmean per family and
  planner, the robustness runs (the worst case per map, and per strategy), how long they took, TransPath's own
  ratios and the commands.
- `docs/guide/gpu.md`: `docs/results/map_size.json` (`perf/map_size.py --out`), the VIN engine and the exhaustive
  attack at 28x28 to 64x64 beside the FMA count.
- `docs/guide/neural-astar.md`: `docs/results/neural_astar.json` (`perf/neural_astar_table.py`), the exact against
  the differentiable search per seed, and the plans/s side by side.
- `docs/development.md`: `docs/results/suite_times.json` (`OUT=docs/results/suite_times.json bash .ci/suite-times`).
- `docs/guide/transpath.md`, "Cost" (and the exhaustive attack's cost on `docs/results/transpath.md`):
  `docs/results/transpath_cost.json` (`perf/transpath.py --out`), a forward, a plan, the two searches and each attack
  strategy per map beside `astar`'s, and their ratios.
- `docs/guide/planners.md`, the 64x64 VIN: `docs/results/vin64_reach.json` (`perf/vin64_reach.py`) and the committed
  weights records `vin64.json` and `vin64.metrics.json`.

Also the formatting every page's figures share (`percent`, `decimal`, `markdown_table`, `shell_block`). The hook
imports this module as MkDocs runs it: with its own folder on the path.
"""

from __future__ import annotations

import json
from pathlib import Path

from vinadv import display  # how a figure is shown: rounded, float noise as 0
from vinadv.evaluation.planner_metrics import LENGTH_BUCKET  # the width of the `by_length` rows

ROOT = Path(__file__).resolve().parents[1]
WEIGHTS_DIR = ROOT / "src" / "vinadv" / "weights"
RESULTS = ROOT / "docs" / "results"
MPD_JSON = RESULTS / "mpd.json"
TRANSPATH_JSON = RESULTS / "transpath.json"
MAP_SIZE_JSON = RESULTS / "map_size.json"
NEURAL_ASTAR_JSON = RESULTS / "neural_astar.json"
SUITE_TIMES_JSON = RESULTS / "suite_times.json"
VIN64_JSON = RESULTS / "vin64_reach.json"
TRANSPATH_COST_JSON = RESULTS / "transpath_cost.json"


def percent(fraction: float | None) -> str:
    """A share as a percentage with one decimal; two where one would round a share below 1 up to 100%."""
    if fraction is None:
        return ""
    text = f"{100 * fraction:.1f}%"
    return f"{100 * fraction:.2f}%" if text == "100.0%" and fraction < 1 else text


def decimal(value: float | None, digits: int = 3) -> str:
    """A figure with `digits` decimals (float noise as 0: `vinadv.display.number`); an em dash where the planner has
    none (Exp without expansions)."""
    return display.number(None if value is None else float(value), digits)


def markdown_table(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table of `rows` (lists of cell texts) under `header`."""
    lines = [header, ["---"] * len(header), *rows]
    return "\n".join("| " + " | ".join(cells) + " |" for cells in lines)


def shell_block(lines: list[str]) -> str:
    """Commands as a fenced `sh` block."""
    return "```sh\n" + "\n".join(lines) + "\n```"


def _families(data: dict, keep_order: bool) -> list[dict]:
    """The families of a JSON by name, or as the JSON lists them (`keep_order`: TransPath's, in the page's order)."""
    return list(data["families"]) if keep_order else sorted(data["families"], key=lambda f: f["family"])


def mpd_table(path: Path = MPD_JSON, first: str = "family (test split)", keep_order: bool = False) -> str:
    """Opt / Exp / Hmean, success and mean expansions per MP family and planner, from `perf/mpd_table.py`'s
    JSON (families by name, or in the JSON's order with `keep_order`); Exp and Hmean are a dash for planners that
    report no expanded cells."""
    data = json.loads(path.read_text())
    rows = []
    for family in _families(data, keep_order):
        for entry in family["planners"]:
            fig = entry["search"]
            rows.append(
                [family["family"], f"`{entry['planner']}`", str(fig["rows"])]
                + [decimal(fig[key]) for key in ("opt", "exp", "hmean")]
                + [percent(fig["success"])]
                + ["—" if fig["expansions"] is None else f"{fig['expansions']:.1f} ({fig['astar_expansions']:.1f})"]
            )
    header = [first, "planner", "searches", "Opt", "Exp", "Hmean", "success", "expansions (A*'s)"]
    return markdown_table(header, rows)


def _robustness_runs(data: dict, keep_order: bool = False) -> list[dict]:
    """The robustness runs of the MP JSON by family (in the table's order), then in the order they were run."""
    order = {f["family"]: i for i, f in enumerate(_families(data, keep_order))}
    planners = list(dict.fromkeys(r["planner"] for r in data["robustness"] if r.get("family", "mazes") != "mazes"))
    # with `keep_order`, a family's runs in the order of its planners in the clean table (families differ in them)
    listed = {f["family"]: [e["planner"] for e in f["planners"]] for f in data["families"]} if keep_order else {}

    def key(run: dict) -> tuple[int, int]:
        names = listed.get(run.get("family", "mazes"), planners)
        planner = names.index(run["planner"]) if run["planner"] in names else len(names)
        return order.get(run.get("family", "mazes"), len(order)), planner

    return sorted(data["robustness"], key=key)


def _by_k(curve: list[dict], key: str) -> str:
    """A curve's `key` rates at k = 1, 2, ... joined by slashes."""
    return " / ".join(percent(point[key]) for point in curve)


def mpd_robustness(
    path: Path = MPD_JSON, first: str = "family (test split)", keep_order: bool = False, seconds: bool = False
) -> str:
    """The robustness runs of `perf/mpd_table.py`'s JSON, worst case per map over the strategies: per family
    and planner, the maps (the valid ones, which the rates count, where fewer), the harmful rate and the paper's
    success rate at k = 1..K added obstacles; where a run reports it
    (a planner with expansions), the effort-harmful rate too (a dash for the others); with `seconds`, each run's."""
    data = json.loads(path.read_text())
    runs = _robustness_runs(data, keep_order)
    effort = any("effort_harmful_rate" in run["figures"]["overall"][0] for run in runs)
    rows = []
    for run in runs:
        figures = run["figures"]
        overall = figures["overall"]
        maps, valid = overall[0]["maps"], overall[0].get("valid", overall[0]["maps"])
        counted = str(maps) if valid == maps else f"{valid} of {maps}"  # the rates are over the valid maps
        row = [run.get("family", "mazes"), f"`{run['planner']}`", counted]
        row += [percent(figures["clean"]["success_rate"]), _by_k(overall, "harmful_rate")]
        row += [_by_k(overall, "paper_success_rate")]
        if effort:
            row += [_by_k(overall, "effort_harmful_rate") if "effort_harmful_rate" in overall[0] else "—"]
        row += [decimal(overall[-1]["mean_regret"])] + ([f"{figures['seconds']:.0f}"] if seconds else [])
        rows.append(row)
    header = [first, "planner", "maps (valid)", "clean success", "harmful, k = 1 / 2 / ...", "paper success"]
    header += ["effort-harmful, k = 1 / 2 / ..."] if effort else []
    header += ["mean regret at the largest k"] + (["seconds"] if seconds else [])
    return markdown_table(header, rows)


def mpd_robustness_times(path: Path = MPD_JSON) -> str:
    """How long the robustness runs took, as a sentence: per planner the fewest and most seconds of a family's run,
    slowest planner first, and all the runs' minutes together."""
    data = json.loads(path.read_text())
    runs = _robustness_runs(data)
    seconds: dict[str, list[float]] = {}
    for run in runs:
        seconds.setdefault(run["planner"], []).append(run["figures"]["seconds"])
    each = [
        f"`{planner}` {min(s):.0f} to {max(s):.0f} s"
        for planner, s in sorted(seconds.items(), key=lambda item: (-max(item[1]), item[0]))
    ]
    total = sum(s for values in seconds.values() for s in values) / 60
    return f"{', '.join(each)} per family, so the {len(runs)} runs took about {total:.0f} minutes"


def mpd_robustness_strategies(path: Path = MPD_JSON, keep_order: bool = False) -> str:
    """The same runs per strategy: the harmful rate at k = 1..K of each strategy."""
    data = json.loads(path.read_text())
    runs = _robustness_runs(data, keep_order)
    names = list(dict.fromkeys(name for run in runs for name in run["figures"]["strategies"]))
    rows = [
        [run.get("family", "mazes"), f"`{run['planner']}`"]
        + [
            _by_k(run["figures"]["strategies"][name]["by_obstacles"], "harmful_rate")
            if name in run["figures"]["strategies"]
            else "—"
            for name in names
        ]
        for run in runs
    ]
    return markdown_table(["family", "planner", *(f"{name}: harmful, k = 1 / 2 / ..." for name in names)], rows)


def transpath_ratios(path: Path = TRANSPATH_JSON) -> str:
    """TransPath's own figures per TransPath planner of `perf/transpath_table.py`'s JSON (their `eval.py`: against
    their vanilla A*, on the rows whose vanilla cost is at least the hardness times the octile heuristic)."""
    data = json.loads(path.read_text())
    rows = []
    for family in data["families"]:
        for entry in family["planners"]:
            fig = entry["search"].get("transpath")
            if fig:
                rows.append(
                    [family["family"], f"`{entry['planner']}`", f"{fig['kept']} of {fig['rows']}"]
                    + [decimal(fig["expansions_ratio"]), decimal(fig["cost_ratio"]), str(fig["unreached"])]
                    + [decimal(fig["expansions"], 1), decimal(fig["vanilla_expansions"], 1)]
                )
    header = ["family", "planner", "rows kept", "expansions ratio", "cost ratio", "unreached"]
    return markdown_table([*header, "expansions", "vanilla A*'s"], rows)


def transpath_families(path: Path = TRANSPATH_JSON) -> str:
    """The families of `perf/transpath_table.py`'s JSON: its maps, the searches of the clean figures, the maps of
    the robustness runs, its planners and the wall time of the run that made them (maps, evaluations and robustness
    runs; a dash where planners were merged in from another run)."""
    data = json.loads(path.read_text())
    rows = []
    for family in data["families"]:
        planners = family["planners"]
        searches = sorted({str(entry["search"]["rows"]) for entry in planners})
        seconds = family.get("seconds")
        rows.append(
            [family["family"], " / ".join(searches), str(family.get("robustness_maps", "—"))]
            + [", ".join(f"`{entry['planner']}`" for entry in planners)]
            + ["—" if seconds is None else f"{seconds / 60:.0f} min"]
        )
    return markdown_table(["family", "searches", "robustness maps", "planners", "wall time"], rows)


def mpd_commands(path: Path = MPD_JSON) -> str:
    """Every command behind `mpd_table` and `mpd_robustness`, as a shell block."""
    data = json.loads(path.read_text())
    lines = []
    for family in data["families"]:  # a family made by one command, or several (crops joined by `maps concat`)
        made = family["import"] if isinstance(family["import"], list) else [family["import"]]
        lines += [*made, *(entry["command"] for entry in family["planners"])]
    lines += [run["command"] for run in data["robustness"]]
    weights = {}
    for run in data["robustness"]:  # the checksum the run recorded (a --weighted file's, or a shipped one's)
        sha = run.get("weights_sha256") or run["figures"].get("planner", {}).get("weights_sha256")
        if sha:
            weights[run["planner"]] = sha
    for entry in (e for f in data["families"] for e in f["planners"] if e.get("weights_sha256")):
        weights[entry["planner"]] = entry["weights_sha256"]
    lines += [f"# {name}: weights with SHA-256 {sha}" for name, sha in weights.items()]
    return shell_block(lines)


#: the growth columns of `map_size_table`: FMA per map, then the time per value map and per plan
GROWTH_KEYS = ("fma_per_map", "value_map_time_per_map", "engine_time_per_map")


def map_size_table(path: Path = MAP_SIZE_JSON) -> str:
    """The VIN's value maps/s, the engine's plans/s (near-tie replays included) and the exhaustive attack's seconds
    per map by map size, beside the multiply-adds per map and the rate they allow at the CPU's FMA peak, and each
    figure's growth from the first size; then the machine, its load and the command (`perf/map_size.py`)."""
    data = json.loads(path.read_text())
    rows = []
    for row in data["sizes"]:
        grow = row["growth_from_first"]
        rows.append(
            [
                f"{row['size']}x{row['size']}",
                str(row["k"]),
                f"{row['fma_per_map']['engine'] / 1e6:.1f} M ({row['fma_per_map']['forward'] / 1e6:.1f} M)",
                f"{row['fma_limit_plans_per_s']:,.0f}",
                f"{row['value_maps_per_s']:,.0f} ({percent(row['value_maps_share_of_fma_peak'])})",
                f"{row['engine_plans_per_s']:,.0f} ({row['near_tie_maps']} of {row['maps']:,})",
                f"{row['candidates_per_map']:,.0f}",
                f"{row['attack_s_per_map']:.3g} s ({percent(row['attack_share_of_fma_peak'])})",
                " / ".join(f"{grow[key]:.1f}x" for key in GROWTH_KEYS),
                f"{grow['attack_fma_per_map']:.0f}x / {grow['attack_time_per_map']:.0f}x",
            ]
        )
    first = data["sizes"][0]["size"]
    header = [
        "maps",
        "k",
        "FMA per map: engine (forward)",
        "maps/s at the FMA peak",
        "value maps/s (share of peak)",
        "engine plans/s (near-tie maps)",
        "attack candidates per map",
        "exhaustive attack per map (share of peak)",
        f"x {first}x{first}: FMA / value map / plan",
        f"x {first}x{first}: attack FMA / time",
    ]
    m = data["machine"]
    weights = ", ".join(sorted({f"`{row['weights']}`" for row in data["sizes"]}))
    note = (
        f"Measured on {m['cpu']} ({m['cores']} cores, {m['engine_threads']} engine threads, "
        f"FMA peak {m['fma_peak_per_s'] / 1e9:.0f} G/s), load average {m['load_average_before']} before and "
        f"{m['load_average_after']} after: a loaded, shared machine, so the absolute rates are low and noisy; the "
        f"sizes ran in one run, minutes apart, so the ratios are the figures to read. Weights {weights}. Command: "
        f"`{data['command']}`"
    )
    return markdown_table(header, rows) + "\n\n" + note


def _machine_note(machine: dict) -> str:
    """The machine of a Neural A* record in words: CPU, cores, PyTorch, niceness and load."""
    return (
        f"{machine['cpu']} ({machine['cores']} cores), PyTorch {machine['torch']}, niceness {machine['niceness']}, "
        f"load average {machine['load_average_before']} before and {machine['load_average_after']} after"
    )


def neural_astar_modes(path: Path = NEURAL_ASTAR_JSON) -> str:
    """Per seed of the mazes test split's import: the searches where the exact and the differentiable mode gave the
    same path and the same expanded cells (`vinadv neural-astar compare-modes`), beside Opt / Exp / Hmean and the mean
    expansions against A*'s (`vinadv eval`); a last row over all seeds (Opt, Exp and the expansions over all searches,
    Hmean the mean of the seeds', as the authors average it over batches); then the machine."""
    data = json.loads(path.read_text())
    rows, searches, compared = [], [], []
    for entry in data["modes"]:
        same, fig = entry["compare_modes"]["figures"], entry["eval"]["search"]
        searches.append(fig)
        compared.append(same)
        rows.append(
            [str(entry["seed"]), str(same["searches"]), str(same["identical_paths"]), str(same["identical_expansions"])]
            + [decimal(fig["opt"], 2), decimal(fig["exp"]), decimal(fig["hmean"]), percent(fig["success"])]
            + [f"{fig['expansions']:.1f} ({fig['astar_expansions']:.1f})"]
        )
    total = sum(s["searches"] for s in compared)
    weight = [fig["rows"] for fig in searches]

    def mean(key: str) -> float:
        return sum(fig[key] * w for fig, w in zip(searches, weight, strict=True)) / sum(weight)

    paths, cells = sum(s["identical_paths"] for s in compared), sum(s["identical_expansions"] for s in compared)
    rows.append(
        ["all", str(total), f"{paths} ({percent(paths / total)})", f"{cells} ({percent(cells / total)})"]
        + [decimal(mean("opt")), decimal(mean("exp"))]
        + [f"{decimal(sum(fig['hmean'] for fig in searches) / len(searches))} (mean of the {len(searches)})"]
        + [percent(mean("success")), f"{mean('expansions'):.1f} ({mean('astar_expansions'):.1f})"]
    )
    header = ["seed", "searches", "identical paths", "identical expanded cells", "Opt", "Exp", "Hmean", "success"]
    note = f"Measured {data['date']} on {_machine_note(data['machine'])}."
    return markdown_table([*header, "mean expansions (A*'s)"], rows) + "\n\n" + note


#: the rows of `neural_astar_speed`: the key of `perf/neural_astar.py`'s `plans_per_s`, and what it times
SPEED_ROWS = (
    ("astar", "`astar` (compiled, unit costs)"),
    ("neural-astar exact", "`neural-astar`, exact mode (encoder, then the compiled search)"),
    ("encoder only", "the encoder alone"),
    ("differentiable", "the differentiable search (encoder, then the PyTorch search; no gradients)"),
    (
        "differentiable + gradient",
        "the differentiable search with the gradient to the obstacles (`differentiable_paths`, forward and backward)",
    ),
)


def neural_astar_speed(path: Path = NEURAL_ASTAR_JSON) -> str:
    """Plans per second of `perf/neural_astar.py` (best of its rounds, side by side in one run), then the
    ratios between them: the exact mode against the differentiable search, the encoder's share of the exact mode's
    time, `astar` against the exact mode; and the machine, its load and the command."""
    data = json.loads(path.read_text())
    speed = data["speed"]["figures"]
    rate = speed["plans_per_s"]
    # rates only: the speed run's starts are `perf/search.py`'s, not the Neural A* loader's of the table above, so its
    # `mean_expansions` would be a second, different expansion count for the same maps (the modes table has them)
    rows = [[label, f"{rate[key]:,.1f}"] for key, label in SPEED_ROWS]
    data_file, _, maps = speed["source"].partition(": ")  # `<data-dir>/NAME.npz: N test maps`: the path as code
    measured_on = f"`{data_file}`: {maps}" if maps else speed["source"]
    table = markdown_table([f"search ({measured_on}, one start each; torch on {speed['device']})", "plans/s"], rows)
    encoder_share = rate["neural-astar exact"] / rate["encoder only"]  # the encoder's time over the exact mode's
    # the exact mode is the encoder and then a search of a few ms: under load its best round can beat the encoder's
    encoder = (
        f"the encoder (the CNN) is {percent(encoder_share)} of its time"
        if encoder_share < 1
        else f"the encoder alone took as long as the whole of it ({percent(encoder_share)}: the compiled search's part "
        "is within the timing noise)"
    )
    note = (
        f"The exact mode plans {speed['exact_over_differentiable']:.1f} times as fast as the differentiable search "
        f"and gives the same paths and expanded cells ({speed['identical_searches']} of {speed['rows']} in the same "
        f"run); {encoder}. `astar` plans "
        f"{speed['astar_over_neural_exact']:,.0f} times as fast as the exact mode: it has no network to run.\n\n"
        f"Measured {data['date']} on {_machine_note(data['machine'])}: a shared machine, so the absolute rates are "
        f"low and noisy; the searches took turns in one run, best of {data['speed']['rounds']} rounds, so the ratios "
        f"are the figures to read "
        f"({speed['numba_threads']} Numba threads, {speed['torch_threads']} torch threads). Command: "
        f"`{data['speed']['command']}`"
    )
    return table + "\n\n" + note


def neural_astar_commands(path: Path = NEURAL_ASTAR_JSON) -> str:
    """The command that wrote the JSON and every command behind `neural_astar_modes` and `neural_astar_speed`, as a
    shell block."""
    data = json.loads(path.read_text())
    lines = [f"# {data['command']}  (the data: {data['source']})"]
    for entry in data["modes"]:
        lines += [entry["import"], entry["compare_modes"]["command"], entry["eval"]["command"]]
    lines.append(data["speed"]["command"])
    return shell_block(lines)


def suite_times(path: Path = SUITE_TIMES_JSON) -> str:
    """The suite's wall times as `.ci/suite-times` measured them (fresh clones, two workers, `CI=true`): each run's
    whole suite and quick tier with the load average around it, the medians, the tests, the commit, the machine; with
    a `base` (`BASE=REV`), that commit's runs too, taken in turn with these, and the ratios of the medians."""
    data = json.loads(path.read_text())
    blocks = [(data["commit"], data)] + ([(data["base"]["commit"], data["base"])] if "base" in data else [])
    rows = []
    for commit, block in blocks:
        for i, run in enumerate(block["runs"]):
            for what, key in (
                ("whole suite (fresh clone, cold caches)", "whole_suite"),
                ("quick tier (warm)", "quick_tier"),
            ):
                r = run[key]
                tests = ", ".join(f"{n:,} {kind}" for kind, n in r["tests"].items())
                load = f"{r['load_average_before']} / {r['load_average_after']}"
                rows.append([f"`{commit}`", str(i + 1), what, f"{block[key + '_s'][i]:.1f} s", tests, load])
    header = ["commit", "clone", "what", "pytest's wall time", "tests", "load average before / after"]
    m = data["machine"]
    medians = [
        f"`{c}`: whole suite {b['whole_suite_median_s']:.1f} s, quick tier {b['quick_tier_median_s']:.1f} s"
        for c, b in blocks
    ]
    text = f"Medians: {'; '.join(medians)}."
    if "base" in data:
        base = data["base"]
        text += (
            f" `{data['commit']}` against `{base['commit']}`, in the same runs: whole suite "
            f"{data['whole_suite_median_s'] / base['whole_suite_median_s']:.2f}x, quick tier "
            f"{data['quick_tier_median_s'] / base['quick_tier_median_s']:.2f}x."
        )
    where = f"on {data['date']}, on {m['cpu']} ({m['cores']} cores)"
    return markdown_table(header, rows) + f"\n\n{text} Measured {where}, by `{data['command']}`."


def _vi_start(weights: str, folder: Path) -> str:
    """The value-iteration start a weights file was trained from, as its training record names it."""
    record = json.loads((folder / weights).with_suffix(".json").read_text())
    start = record.get("train_config", {}).get("vi_init") or "default"
    return f"`{start}` (the paper's)" if start == "default" else f"`{start}`"


def vin64_transfer(path: Path = VIN64_JSON, folder: Path = WEIGHTS_DIR) -> str:
    """The shipped 28x28 weights on generated 64x64 maps (`perf/vin64_reach.py`): per weights file and k, the
    share of the starts from which the rollout reaches the goal; then the maps, the date and every command."""
    data = json.loads(path.read_text())
    rows, commands, settings = [], [], set()
    for entry in data["transfer"]:
        commands.append(entry["export"])
        for run in entry["runs"]:
            fig = run["figures"]
            settings.add((fig["maps"], fig["seed"], fig["size"], fig["starts_per_map"]))
            rows.append(
                [f"`{entry['weights']}`", _vi_start(entry["weights"], folder), str(run["k"])]
                + [f"{percent(fig['success_rate'])} of {fig['rollouts']:,}", percent(fig["optimal_rate"])]
            )
            commands.append(run["command"])
    ((maps, seed, size, starts),) = settings  # one set of maps for every run, or the table would compare apples
    header = ["weights", "value-iteration start", "k", "reaches the goal (of the starts)", "optimal paths"]
    note = (
        f"Measured {data['date']} on {maps:,} generated {size}x{size} maps (seed {seed}, {starts} starts each) by "
        f"`{data['command']}`, which ran (`<work>`: a scratch folder):"
    )
    return markdown_table(header, rows) + "\n\n" + note + "\n\n" + shell_block(commands)


def vin64_reach(path: Path = VIN64_JSON) -> str:
    """The optimal move counts on the training set's generator (`perf/vin64_reach.py`), as a sentence: the
    longest from a start, the share of the cells that reach the goal within each k, each map's farthest cell."""
    data = json.loads(path.read_text())
    reach = data["reach"]
    within = sorted(reach["cells_within"].items(), key=lambda item: -int(item[0]))
    first, *others = within
    also = "".join(f"; within {k} moves: {percent(share)}" for k, share in others)
    starts = "one start" if reach["starts_per_map"] == 1 else f"{reach['starts_per_map']} starts"
    return (
        f"On the generator's first {reach['maps']:,} {reach['size']}x{reach['size']} maps of seed {reach['seed']} "
        f"({starts} each, the training set's settings) the longest optimal path from a start has "
        f"{reach['longest_from_a_start']} moves, and {percent(first[1])} of the {reach['cells']:,} free cells that "
        f"reach the goal do so within {first[0]} moves{also}; the per-map farthest cell has median "
        f"{reach['farthest_cell_median']:g}, 99th percentile {reach['farthest_cell_p99']:g} and at most "
        f"{reach['farthest_cell_max']} moves (`{data['command']}`, {data['date']})"
    )


def vin64_training(folder: Path = WEIGHTS_DIR) -> str:
    """`vin64.pt`'s training record as a sentence: the epochs, their wall time, the machine and the validation
    action accuracy after each epoch."""
    record = json.loads((folder / "vin64.json").read_text())
    hardware = record["hardware"]
    accuracy = " / ".join(percent(epoch["val_action_accuracy"]) for epoch in record["epochs"])
    threads = hardware["torch_threads"]
    return (
        f"The {record['epochs_done']} epochs took {record['wall_time_s'] / 60:.1f} minutes on "
        f"{hardware['cpu_model']} ({hardware['cpu_count']} cores, {threads} torch thread{'s' * (threads != 1)}; "
        f"`vin64.json`); validation action accuracy after epochs 1 to {len(record['epochs'])}: {accuracy}"
    )


def vin64_held_out(folder: Path = WEIGHTS_DIR) -> str:
    """`vin64.pt`'s figures on the held-out maps (`vin64.metrics.json`) as a sentence: its success, then the starts
    whose optimal path is within one length bucket of k or longer (k from `vin64.json`), and how many of them reach
    the goal."""
    fig = json.loads((folder / "vin64.metrics.json").read_text())
    k = json.loads((folder / "vin64.json").read_text())["model"]["k"]
    far = [row for row in fig["by_length"] if row["moves"][0] >= k - LENGTH_BUCKET]
    starts = sum(row["rollouts"] for row in far)
    missed_far = starts - round(sum(row["success_rate"] * row["rollouts"] for row in far))
    missed = fig["rollouts"] - fig["terminations"]["goal"]
    return (
        f"On the {fig['maps']:,} held-out {fig['size']}x{fig['size']} maps (seed {fig['seed']}, never trained on) it "
        f"reaches the goal from {percent(fig['success_rate'])} of the {fig['rollouts']:,} starts (`{fig['command']}`); "
        f"of the {missed} starts it misses, {missed_far} are among the {starts} ({percent(starts / fig['rollouts'])} "
        f"of the starts) whose optimal path has {k - LENGTH_BUCKET} moves or more"
    )


#: the models of `perf/transpath.py`'s record, in the table's column order after `astar`
TRANSPATH_MODELS = ("transpath-cf", "transpath-focal")
#: the rows of `transpath_cost` timed side by side: the key's suffix in `seconds_per_map`, and what it times
TRANSPATH_COST_ROWS = (
    ("forward", "forward (the network alone)"),
    ("plan", "plan (forward and compiled search)"),
    ("replica search", "compiled replica's search (outputs cached)"),
    ("differentiable search", "differentiable search (outputs cached, no gradient)"),
)


def _duration(seconds: float) -> str:
    """A time in milliseconds below a second, else seconds, three significant figures (thousands separated)."""
    if seconds < 1:
        return f"{seconds * 1000:.3g} ms"
    return f"{seconds:,.0f} s" if seconds >= 100 else f"{seconds:.3g} s"


def _times(ratio: float) -> str:
    """A ratio of two times: whole above 10, else one decimal."""
    return f"{ratio:,.0f}" if ratio >= 10 else f"{ratio:.1f}"


def _span(ratios: list[float]) -> str:
    low, high = min(ratios), max(ratios)
    return _times(low) if _times(low) == _times(high) else f"{_times(low)} to {_times(high)}"


def transpath_cost(path: Path = TRANSPATH_COST_JSON) -> str:
    """The cost of TransPath beside A*'s per 64x64 map (`perf/transpath.py --out`): a forward, a plan, the compiled
    replica's and the differentiable search on cached outputs, each attack strategy, each TransPath figure with its
    ratio to `astar`'s (the forward's and plan's to `astar`'s plan); then the ratios the prose would otherwise copy,
    the machine, its load, the run's wall time and the command."""
    data = json.loads(path.read_text())
    fig = data["figures"]
    per_map, ratios, attacks = fig["seconds_per_map"], fig["ratios"], fig["attack_seconds_per_map"]
    rows = []
    for key, label in TRANSPATH_COST_ROWS:
        astar = per_map["astar plan"] if key == "plan" else None
        row = [label, "—" if astar is None else _duration(astar)]
        for model in TRANSPATH_MODELS:
            cell = _duration(per_map[f"{model} {key}"])
            if key in ("forward", "plan"):  # both against astar's plan: a forward is what a TransPath plan adds
                cell += f" ({_times(ratios[f'{model}: {key} / astar plan'])}x)"
            row.append(cell)
        rows.append(row)
    for strategy, times in attacks.items():
        label = f"`{strategy}` attack"
        if "candidates_per_map" in times:
            label += f" ({times['candidates_per_map']:,.0f} candidates a map)"
        maps = times["maps"]
        label += f", {maps} map{'s' * (maps != 1)}"
        row = [label, _duration(times["astar"])]
        row += [
            f"{_duration(times[m])} ({_times(ratios[f'{m}: {strategy} / astar {strategy}'])}x)"
            for m in TRANSPATH_MODELS
        ]
        rows.append(row)
    header = ["per 64x64 map (x `astar`'s)", "`astar`", *(f"`{m}`" for m in TRANSPATH_MODELS)]
    search = [ratios[f"{m}: differentiable search / replica search"] for m in TRANSPATH_MODELS]
    same = [fig["identical_searches"][m].replace("/", " of ") for m in TRANSPATH_MODELS]
    forward = [ratios[f"{m}: forward / astar plan"] for m in TRANSPATH_MODELS]
    plan = [ratios[f"{m}: plan / astar plan"] for m in TRANSPATH_MODELS]
    attack = [ratios[f"{m}: {s} / astar {s}"] for m in TRANSPATH_MODELS for s in attacks]
    m = data["machine"]
    maps, _, rule = fig["maps"].rpartition(", ")  # `generate_maps(...)`, then the maps' rule
    text = (
        f"The compiled replica's search was {_times(search[0])} (`cf`) and {_times(search[1])} (`f`) times as fast as "
        f"the differentiable search on the same cached outputs, with the same paths and expanded cells on "
        f"{same[0]} and {same[1]} maps. A plan is the network's forward and then a search: {_span(plan)} times "
        f"`astar`'s plan, the forward alone {_span(forward)} times; every attack strategy costs {_span(attack)} "
        f"times `astar`'s per map.\n\n"
        f"Measured {data['date']} on {m['cpu']} ({m['cores']} cores, {fig['torch_threads']} torch thread"
        f"{'s' * (fig['torch_threads'] != 1)}, niceness {m['niceness']}), load average {m['load_average_before']} "
        f"before and {m['load_average_after']} after: a shared machine, so the times are high and noisy; the "
        f"forwards, plans and searches took turns in one run, best of {fig['rounds']} rounds, on `{maps}` ({rule}), "
        f"so the ratios are the figures to read; each attack ran once, after one untimed map. The run took "
        f"{data['seconds']:,.0f} s. Command: `{data['command']}`"
    )
    return markdown_table(header, rows) + "\n\n" + text


def transpath_exhaustive_cost(path: Path = TRANSPATH_COST_JSON) -> str:
    """The exhaustive attack's cost per 64x64 map (`perf/transpath.py --out`), as a sentence: its candidates, and the
    seconds of each TransPath model and of `astar`."""
    data = json.loads(path.read_text())
    times = data["figures"]["attack_seconds_per_map"]["exhaustive"]
    each = " and ".join(f"{_duration(times[m])} with `{m}`" for m in TRANSPATH_MODELS)
    return (
        f"{times['candidates_per_map']:,.0f} candidates a map, each one TransPath forward: {each}, against "
        f"{_duration(times['astar'])} with `astar` (`{data['command']}`, {data['date']})"
    )
