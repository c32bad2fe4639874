"""The quality of the planner a run used (the report's "planner's quality" section), measured on the run's own maps
and stored.

`run_maps` reads the maps to measure on from the store: the original maps of the run's stored pairs, each once (a
map attacked several times, `per_map > 1`, is one map), in pair-index order, the first `limit` of them
(`QUALITY_MAPS` by default: a run of a million maps is measured on its first thousand, which for generated maps are
as random as any, and for a maps file its first maps), with the start each pair used. `planner_quality` loads the
run's planner (its spec and weights, checked against the weights checksum the run recorded) and measures it there:
`evaluate_planner`'s rollout figures (success, % optimal, mean extra cost) for every planner, action accuracy where it
declares a policy, the search figures (`evaluate_search`: Opt, Exp, Hmean, expansions beside A*'s) where it declares
expansions, and the value map of the first map where it declares value maps. `evaluate_planner_quality` stores it
with the run (`Store.add_measurement`, kind `PLANNER_QUALITY`): `{"metrics", "source", "capabilities", "planner",
"maps", "search", "value_map"}` (module doc of `vinadv.report.sections.planner` for what the report shows of it).
"""

from __future__ import annotations

import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from vinadv.errors import InputError
from vinadv.evaluation.classifiers import jsonable
from vinadv.evaluation.planner_metrics import evaluate_planner
from vinadv.evaluation.search_metrics import evaluate_search
from vinadv.grid.mapset import MapSet
from vinadv.grid.shortest_paths import expert_paths
from vinadv.planners.interface import plan_every_start
from vinadv.planners.registry import default_weights, load_planner
from vinadv.vocabulary import PLANNER_QUALITY

#: the most maps of a run its planner's quality is measured on (the first, in pair-index order)
QUALITY_MAPS = 1000
#: pairs read from the store at a time while collecting the maps
READ_CHUNK = 5000


def run_maps(store, run_id: int, corner_cutting: bool, limit: int = QUALITY_MAPS) -> tuple[MapSet, np.ndarray]:
    """The first `limit` distinct original maps (obstacles, goal and start) of the stored run `run_id`, in pair-index
    order, as a `MapSet` of one start each with its expert paths (the run's movement model, `corner_cutting`), and the
    pair index of each map's first pair. Pairs are read a chunk at a time, and no further than the maps need."""
    if int(limit) < 1:
        raise InputError(f"quality_maps: at least 1 map, got {limit}", "quality_maps")
    moves = store.run_moves(run_id)
    seen: set[bytes] = set()
    obstacles, goals, starts, first = [], [], [], []
    for records in store.iter_pairs(run_id, chunk=READ_CHUNK):
        keys = np.concatenate(
            [np.packbits(records.obstacles_o.reshape(len(records), -1), axis=1), _bytes(records.goals)]
            + [_bytes(records.starts)],
            axis=1,
        )
        for i, key in enumerate(map(bytes, keys)):
            if key in seen:
                continue
            seen.add(key)
            obstacles.append(records.obstacles_o[i])
            goals.append(records.goals[i])
            starts.append(records.starts[i])
            first.append(int(records.pair_index[i]))
            if len(first) == limit:
                break
        if len(first) == limit:
            break
    if not first:
        raise InputError(f"run {run_id}: no stored pairs, so no maps to measure its planner on", "run")
    obstacles, goals = np.stack(obstacles), np.stack(goals).astype(np.int64)
    starts = np.stack(starts).astype(np.int64)[:, None, :]
    costs, expert = expert_paths(obstacles, goals, starts, corner_cutting, moves)
    maps = MapSet(
        obstacles=obstacles,
        goals=goals,
        starts=starts,
        expert_costs=costs,
        expert=expert,
        corner_cutting=corner_cutting,
        moves=moves,
    )
    return maps, np.asarray(first, dtype=np.int64)


def _bytes(cells: np.ndarray) -> np.ndarray:
    """`(n, 2)` cells as `(n, 4)` uint8 (two little-endian uint16: a map side is below 65,536)."""
    return np.ascontiguousarray(np.asarray(cells, dtype="<u2")).view(np.uint8).reshape(len(cells), -1)


def planner_quality(
    config: dict, checksum: str | None, maps: MapSet, first_pairs: np.ndarray, pairs: int, run_id: int
) -> dict:
    """The quality of the run's planner (`config["planner"]`, default the VIN, with `config["weights"]`) on `maps`
    (`run_maps`: their first pairs' indices `first_pairs`, of the run's `pairs` stored pairs): the measurement
    `evaluate_planner_quality` stores. Its `metrics` are `{}`, and its `source` says why, when the planner or its
    weights are not on this machine or are not the ones the run used (`checksum`)."""
    name = config.get("planner") or "vin"
    size = maps.size
    path = Path(config["weights"]) if config.get("weights") else default_weights(name, size)
    described = (
        f"the first {len(maps):,} distinct maps of run {run_id}'s {pairs:,} stored pairs (pairs "
        f"{int(first_pairs[0])}..{int(first_pairs[-1])}), the start each pair used"
    )
    result = {"metrics": {}, "source": None, "capabilities": None, "planner": None, "maps": described}
    if path is not None and not path.exists():
        return {**result, "source": f"not available: the run's weights file {path} is not on this machine"}
    try:
        planner = load_planner(
            name, size, weights=config.get("weights"), corner_cutting=maps.corner_cutting, moves=maps.moves
        )
    except InputError as exc:
        return {**result, "source": f"not available: {exc}"}
    if checksum and planner.checksum != checksum:
        return {
            **result,
            "source": f"not available: planner {name!r} here is not the one the run used (its checksum differs)",
        }
    capabilities = planner.capabilities
    start = time.perf_counter()
    planner = planner.for_moves(maps.moves)
    plans = plan_every_start(planner, maps)  # once for both
    metrics = evaluate_planner(planner, maps, result=plans)
    search = evaluate_search(planner, maps, result=plans) if capabilities.expansions else None
    value_map = None
    if capabilities.value_maps:  # the first map's, drawn in the report
        values = planner.value_maps(maps.obstacles[:1], maps.goals[:1])[0]
        value_map = {"pair_index": int(first_pairs[0]), "values": np.asarray(values, dtype=np.float64).tolist()}
    seconds = time.perf_counter() - start
    weights = "" if path is None else f", weights {path.name}"
    return {
        **result,
        "metrics": metrics,
        "source": f"measured by vinadv evaluate on {described}; planner {name!r}{weights}, {seconds:.1f} s",
        "capabilities": asdict(capabilities),
        "planner": planner.spec(),
        "search": search,
        "value_map": value_map,
    }


def evaluate_planner_quality(store, run_id: int, limit: int = QUALITY_MAPS) -> dict:
    """Measure the planner of the stored run `run_id` on its first `limit` maps (`run_maps`, `planner_quality`),
    store the result with the run and return it."""
    info = store.run_info(run_id)
    config = info.get("config") or {}
    maps, first = run_maps(store, run_id, bool(config.get("corner_cutting", True)), limit)
    measured = planner_quality(config, info.get("weights_checksum"), maps, first, store.count_pairs(run_id), run_id)
    result = jsonable(measured)
    store.add_measurement(run_id, PLANNER_QUALITY, result)
    return result
