"""The quality of the planner a run used (the report's "planner's quality" section), measured and stored.

`planner_quality` finds it: for `vin` and `gppn` a metrics JSON shipped next to the weights, else the training
record inside the weights file; for every planner, else a quick evaluation now (`QUICK_EVAL_MAPS` fresh maps).
`evaluate_planner_quality` stores it with the run (`Store.add_measurement`, kind `PLANNER_QUALITY`): `{"metrics":
..., "source": ...}`.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from vinadv.errors import InputError
from vinadv.evaluation.classifiers import jsonable
from vinadv.evaluation.planner_metrics import evaluate_planner
from vinadv.grid.generator import generate_maps
from vinadv.grid.moves import DEFAULT_MOVES
from vinadv.planners.registry import default_weights, load_planner
from vinadv.vocabulary import PLANNER_QUALITY

QUICK_EVAL_MAPS = 50
QUICK_EVAL_SEED = 20_240_601


def planner_quality(config: dict, checksum: str | None, size: int, moves: str = DEFAULT_MOVES) -> tuple[dict, str]:
    """The quality of the planner a run used (`config["planner"]`, default the VIN): `(metrics, source)`; metrics as
    `vinadv.evaluation.planner_metrics.evaluate_planner` (success_rate, optimal_rate, action_accuracy, ...), `{}`
    when the planner or its weights are not on this machine, or are not the ones the run used (`checksum`); `source`
    says where the metrics come from, or why there are none. `moves`: the run's movement model (the quick evaluation's
    maps are of that model)."""
    name = config.get("planner") or "vin"
    corner_cutting = bool(config.get("corner_cutting", True))
    path = Path(config["weights"]) if config.get("weights") else default_weights(name, size)
    if path is not None and not path.exists():
        return {}, f"not available: the run's weights file {path} is not on this machine"
    try:
        planner = load_planner(name, size, weights=config.get("weights"), corner_cutting=corner_cutting, moves=moves)
    except InputError as exc:
        return {}, f"not available: {exc}"
    if checksum and planner.checksum != checksum:
        return {}, f"not available: planner {name!r} here is not the one the run used (its checksum differs)"
    if path is not None:
        for candidate in (
            path.with_suffix(".metrics.json"),
            path.with_name(path.stem + "_metrics.json"),
            path.with_name(path.stem + "-metrics.json"),
            path.with_name(path.name + ".metrics.json"),
            path.with_suffix(".json"),
        ):
            if candidate.exists():
                try:
                    data = json.loads(candidate.read_text())
                except (OSError, ValueError):
                    continue
                found = find_metrics(data)
                if found:
                    return found, f"metrics file {candidate.name} shipped with the weights {path.name}"
        model = getattr(planner, "vin", None) or getattr(planner, "module", None)
        found = find_metrics(getattr(model, "record", None) or {})
        if found:
            return found, f"the training record inside the weights file {path.name}"
    maps = generate_maps(QUICK_EVAL_MAPS, size, seed=QUICK_EVAL_SEED, corner_cutting=corner_cutting, moves=moves)
    start = time.perf_counter()
    metrics = evaluate_planner(planner, maps)
    seconds = time.perf_counter() - start
    weights = "" if path is None else f", weights {path.name}"
    return metrics, (
        f"quick evaluation of planner {name!r} by vinadv evaluate: {QUICK_EVAL_MAPS} fresh "
        f"{size}x{size} maps (seed {QUICK_EVAL_SEED}), {maps.n_starts} starts each{weights}, "
        f"{seconds:.1f} s"
    )


def find_metrics(data) -> dict | None:
    """A dict holding `success_rate` and `optimal_rate` inside a metrics/record JSON (top level or nested)."""
    if isinstance(data, dict):
        if "success_rate" in data and "optimal_rate" in data:
            return data
        for value in data.values():
            found = find_metrics(value)
            if found:
                return found
    elif isinstance(data, list):
        for value in reversed(data):  # the last epoch / latest evaluation first
            found = find_metrics(value)
            if found:
                return found
    return None


def evaluate_planner_quality(store, run_id: int) -> dict:
    """Find the quality of the planner of the stored run `run_id` (`planner_quality`) and store it with the run;
    return what was stored, `{"metrics": {...}, "source": "..."}`."""
    info = store.run_info(run_id)
    config = info.get("config") or {}
    size = config.get("size")
    if size is None:  # a config without the size (`vinadv identify`'s, or none): its first pair's
        index, _ = store.pair_labels(run_id)
        size = store.read_pairs(run_id, pair_indices=index[:1]).size
    metrics, source = planner_quality(config, info.get("weights_checksum"), int(size), info["moves"])
    result = {"metrics": jsonable(metrics), "source": source}
    store.add_measurement(run_id, PLANNER_QUALITY, result)
    return result
