"""The per-map outcomes a `vinadv.bench_entry/2` entry holds, and every figure of the entry computed from them.

An entry of a suite of definitions 2 (`vinadv.bench.suites.Suite.definitions`) carries, beside its figures, the
outcome of every map (`per_map`), so that a reader recomputes every figure (`entry_figures`; `vinadv bench verify`
checks that they follow), and a recompute of some chunks is compared with the entry map by map:

- `per_map.clean`: `reached` (the clean path reaches the goal) and `regret` (its cost minus the optimum; null where
  it does not reach), one value per map, in map order;
- `per_map.chunks`: per chunk of maps, its `maps` and the means of the clean protocols that are taken per chunk:
  GPPN's `gppn_percent_optimal` and `gppn_percent_success`, or a search planner's `search` (`join_search`); for a
  search planner `per_map.clean` also holds each map's values behind those means (optional: entries computed before
  have none): `cost_ratio` (the path's cost over the optimal one, null where it does not reach) and, where the planner
  reports its expansions, `exp` (the share of A*'s expansions it saved, `max(0, (E_A* - E) / E_A*)`), so that their
  means get a bootstrap interval over the maps (`vinadv.bench.comparison.mean_intervals`);
- `per_map.attacks`: per attack (`edit:strategy`), per k from the group's `first_k`: `k`, `label` (the pair's paper
  label, "" where the map got no pair), `harmful` (true or false) and `regret` (`regret_a`, null where the pair is not
  valid or its path does not reach); and, where the planner reports its expansions (`Capabilities.expansions`; every
  record of the entry, or none), `effort` (the effort ratio, the adversarial search's expansions over the clean one's,
  null without a valid pair) and `effort_harmful` (the pair is valid and effort-harmful: DESIGN.md "Search effort",
  `vinadv.classify.effort`; false without a valid pair);
- `per_map.start_cells` (optional: a suite with chains, `AttackGroup.start`, and every chunk computed since the field
  exists; an entry made before has none): per attack a chain starts from (`edit:start`, say `add:exhaustive`), the
  one cell it kept on each map, `[row, column]`, or null where the map got no pair (`cells_json`); what a recompute of
  a changed chain starts from without running its start again (`vinadv.bench.reuse`).

From them: a map's pair was made where its label is not "", is valid where it is neither "" nor `invalid`, broken
where valid and UrP or FP; the label counts are those of the pairs. The worst case at k is over every attack of at most
k edits on a fixed denominator (`worst_case_within`), so its k curve cannot fall; where efforts are
present, every figure also counts the effort-harmful maps (`effort_harmful`, `effort_harmful_rate` over the valid
maps; the worst case: a map effort-harmful for any attack of at most k edits) and `per_map.worst_effort[k - 1]` is each
map's largest effort ratio over those attacks. Means are correctly rounded sums (`math.fsum`): the same bits on every
CPU.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable

import numpy as np

from vinadv.evaluation.search_metrics import harmonic_mean
from vinadv.robustness import Figures, MapOutcomes, worst_case
from vinadv.vocabulary import SUCCESS_LABELS, label_counts

#: a path is optimal when its cost is within this of the optimum
OPTIMAL_TOL = 1e-9
#: a search planner's per-map values of its clean protocol (`per_map.clean`): the values behind the chunks' means
CLEAN_SEARCH_VALUES = ("exp", "cost_ratio")
#: a chunk's clean values that are per map (the rest: its protocol means, `per_map.chunks`)
_PER_MAP_CLEAN = ("reached", "regret", *CLEAN_SEARCH_VALUES)
#: how far a chunk's stored mean may be from the mean of its per-map values (`chunk_mean_problems`): the chunk's mean
#: was summed by NumPy (pairwise), the check sums exactly
MEAN_TOL = 1e-12


def chunk_mean_problems(per_map: dict) -> list[tuple[str, float, float]]:
    """`(field, stored, from the per-map values)` for each chunk whose search mean (`exp`: over its maps; `cost_ratio`:
    over the maps that reach the goal) is not the mean of its maps' values in `per_map.clean` (within `MEAN_TOL`,
    relative); [] for an entry without them."""
    out, lo = [], 0
    for i, chunk in enumerate(per_map["chunks"]):
        hi = lo + chunk["maps"]
        for name in CLEAN_SEARCH_VALUES:
            if name not in per_map["clean"] or "search" not in chunk:
                continue
            mean = exact_mean(per_map["clean"][name][lo:hi])
            stored = chunk["search"].get(name)
            if (stored is None) != (mean is None) or (
                mean is not None and abs(stored - mean) > MEAN_TOL * max(1.0, abs(mean))
            ):
                out.append((f"per_map.chunks[{i}].search.{name}", stored, mean))
        lo = hi
    return out


def weighted_mean(weights: Iterable[float], values: Iterable[float]) -> float:
    """sum(w * v) / sum(w), each sum correctly rounded (`math.fsum`): the same bits on every CPU, where a BLAS dot
    product sums in the order of the CPU's kernel (an entry made on an Intel and on an AMD CPU differed in the last
    digit)."""
    weights, values = list(weights), list(values)
    return math.fsum(w * v for w, v in zip(weights, values)) / math.fsum(weights)


def exact_mean(values) -> float | None:
    """The mean of the finite `values`, its sum correctly rounded (None for none)."""
    values = [float(v) for v in values if v is not None and not math.isnan(v)]
    return math.fsum(values) / len(values) if values else None


def join_search(parts: list[dict]) -> dict:
    """The search metrics (`vinadv.evaluation.search_metrics`) over every row of the chunks `parts` (each chunk's, one
    start per map): the means weighted by their rows (the cost ratio by the rows that reached the goal), Hmean the
    harmonic mean of the joined Opt and Exp, as the authors take it with one start per map."""
    rows = np.array([p["rows"] for p in parts], dtype=np.float64)

    def mean(name, weights=rows):  # over the chunks that weigh (a chunk where nothing reached has no cost ratio)
        used = [(w, p[name]) for w, p in zip(weights, parts) if w > 0]
        if not used or any(v is None for _, v in used):
            return None
        return weighted_mean(*zip(*used))

    reached = rows * np.array([p["success"] or 0.0 for p in parts])
    out = {
        "rows": int(rows.sum()),
        "opt": mean("opt"),
        "exp": mean("exp"),
        "success": mean("success"),
        "cost_ratio": mean("cost_ratio", reached) if reached.sum() else None,
        "expansions": mean("expansions"),
        "astar_expansions": mean("astar_expansions"),
    }
    out["hmean"] = None if out["exp"] is None else float(harmonic_mean(out["opt"], out["exp"]))
    return out


def _floats(values) -> list:
    return [None if v is None or math.isnan(v) else float(v) for v in values]


def cells_json(cells: np.ndarray) -> list:
    """One-cell cells `(n, 1, 2)` (`vinadv.robustness.StrategyResult.cells[0]`: integers, -1 where a map got no pair)
    as `per_map.start_cells` holds them: per map `[row, column]`, or None."""
    return [None if c[0, 0] < 0 else [int(c[0, 0]), int(c[0, 1])] for c in np.asarray(cells)]


def cells_array(values: list) -> np.ndarray:
    """`cells_json`'s per-map values back as the `(n, 1, 2)` int64 cells, -1 where None."""
    out = np.full((len(values), 1, 2), -1, dtype=np.int64)
    for i, cell in enumerate(values):
        if cell is not None:
            out[i, 0] = cell
    return out


def chunk_per_map(suite, order: list[dict]) -> dict:
    """The `per_map` of an entry of `suite` from its chunks' results (`vinadv.bench.scoring.compute_chunk`), in map
    order; `start_cells` where every chunk holds them."""
    attacks = {}
    for group in suite.attacks:
        for key in group.keys():
            attacks[key] = [_attack_record([c["attacks"][key][i] for c in order], k) for i, k in enumerate(group.ks)]
    clean = {
        "reached": [v for c in order for v in c["clean"]["reached"]],
        "regret": _floats(v for c in order for v in c["clean"]["regret"]),
    }
    for name in CLEAN_SEARCH_VALUES:  # a search planner's per-map protocol values (chunks computed before: none)
        if all(name in c["clean"] for c in order):
            clean[name] = _floats(v for c in order for v in c["clean"][name])
    out = {
        "clean": clean,
        "chunks": [
            {"maps": c["maps"], **{k: v for k, v in c["clean"].items() if k not in _PER_MAP_CLEAN}} for c in order
        ],
        "attacks": attacks,
    }
    starts = suite.start_keys()
    if starts and all(key in c.get("start_cells", {}) for c in order for key in starts):
        out["start_cells"] = {key: [v for c in order for v in c["start_cells"][key]] for key in starts}
    return out


def _attack_record(parts: list[dict], k: int) -> dict:
    """One attack's `per_map` record at k from its chunks' parts."""
    record = {
        "k": k,
        "label": [v for p in parts for v in p["label"]],
        "harmful": [v for p in parts for v in p["harmful"]],
        "regret": _floats(v for p in parts for v in p["regret"]),
    }
    if all("effort" in p for p in parts):
        record["effort"] = _floats(v for p in parts for v in p["effort"])
        record["effort_harmful"] = [bool(v) for p in parts for v in p["effort_harmful"]]
    return record


def outcome(record: dict) -> MapOutcomes:
    """One attack's per-map outcomes at one k from its `per_map` record."""
    label = np.array(record["label"], dtype="<U7")
    pair = label != ""
    valid = pair & (label != "invalid")
    regret = np.array([np.nan if v is None else v for v in record["regret"]], dtype=np.float64)
    effort = effort_harmful = None
    if "effort" in record:  # a planner that reports its expansions
        effort = np.array([np.nan if v is None else v for v in record["effort"]], dtype=np.float64)
    if "effort_harmful" in record:
        effort_harmful = np.array(record["effort_harmful"], dtype=bool).reshape(len(label))
    return MapOutcomes(
        pair=pair,
        valid=valid,
        broken=valid & np.isin(label, SUCCESS_LABELS),
        harmful=np.array(record["harmful"], dtype=bool).reshape(len(label)),
        regret=regret.reshape(len(label)),
        label=label,
        effort_harmful=effort_harmful,
        effort=effort,
    )


def _figures(k: int, o: MapOutcomes, counts: dict | None = None) -> dict:
    """`Figures.of`, its mean regret correctly rounded (`exact_mean`)."""
    figures = Figures.of(k, o, counts=counts)
    figures.mean_regret = exact_mean(o.regret)
    return figures.to_dict()


def clean_figures(per_map: dict) -> dict:
    """The entry's `clean` from the per-map outcomes and the chunks' protocol means."""
    reached = np.array(per_map["clean"]["reached"], dtype=bool)
    regret = np.array([np.nan if v is None else v for v in per_map["clean"]["regret"]], dtype=np.float64)
    n = len(reached)
    chunks = per_map["chunks"]
    clean = {
        "maps": n,
        "reached": int(reached.sum()),
        "success_rate": int(reached.sum()) / n,
        "percent_optimal": int((reached & (np.abs(regret) <= OPTIMAL_TOL)).sum()) / n,
        "mean_regret": exact_mean(regret[reached]),
    }
    if "search" in chunks[0]:
        clean["gppn"] = None  # a search planner has no policy to follow from every cell
        clean["search"] = join_search([c["search"] for c in chunks])
    else:
        weights = [c["maps"] for c in chunks]
        clean["gppn"] = {
            name: weighted_mean(weights, [c[f"gppn_{name}"] for c in chunks])
            for name in ("percent_optimal", "percent_success")
        }
    return clean


def entry_figures(suite, per_map: dict) -> dict:
    """Every figure of an entry of `suite` from its `per_map` (module doc): `clean`, `attacks` (per attack, its
    figures at each k), `worst_case` (at each k, over every attack of at most k edits) and, where efforts are
    present, `worst_effort` (per k, each map's largest)."""
    attacks, by_k = {}, {}
    for group in suite.attacks:
        for key in group.keys():
            records = per_map["attacks"][key]
            figures = []
            for record in records:
                o = outcome(record)
                by_k.setdefault(record["k"], []).append(o)
                figures.append(_figures(record["k"], o, label_counts(o.label[o.pair])))
            attacks[key] = {"strategy": key.split(":", 1)[1], "edit": group.edit, "by_obstacles": figures}
    per_k = [by_k.get(k, []) for k in range(1, max(by_k) + 1)]
    within = worst_case_within(per_k)
    worst = [{**_figures(k + 1, o), "attacks": sum(len(outs) for outs in per_k[: k + 1])} for k, o in enumerate(within)]
    out = {"clean": clean_figures(per_map), "attacks": attacks, "worst_case": worst}
    if all(o.effort is not None for outs in per_k for o in outs):
        # each map's largest effort ratio over the attacks of at most k edits (`worst_case`), null where none has one
        out["worst_effort"] = [_floats(o.effort) for o in within]
    return out


def worst_case_within(per_k: list[list[MapOutcomes]]) -> list[MapOutcomes]:
    """The worst case per map at each budget k over every attack of AT MOST k edits (`per_k[k - 1]`: the outcomes of
    the attacks that edit exactly k cells, of the same maps), on a fixed denominator: a map is valid (attacked) at
    every k when it is valid for (got a pair from) any attack at any k. A map broken or harmful at k stays so at every
    larger k, so the rates cannot fall as k grows; its regret at k is that of its worst pair of at most k edits."""
    every = [o for outs in per_k for o in outs]
    pair = np.any([o.pair for o in every], axis=0)
    valid = np.any([o.valid for o in every], axis=0)
    out = []
    for k in range(len(per_k)):
        worst = worst_case([o for outs in per_k[: k + 1] for o in outs])
        out.append(dataclasses.replace(worst, pair=pair, valid=valid))
    return out


def _outcome(parts: list[dict]) -> MapOutcomes:
    """One attack's per-map outcomes at one k, the chunks' joined in map order."""

    def join(name, dtype):
        return np.array([v for p in parts for v in p[name]], dtype=dtype)

    regret = np.array([np.nan if v is None else v for p in parts for v in p["regret"]], dtype=np.float64)
    return MapOutcomes(
        pair=join("pair", bool),
        valid=join("valid", bool),
        broken=join("broken", bool),
        harmful=join("harmful", bool),
        regret=regret,
        label=join("label", "<U7"),
    )


def _counts(parts: list[dict]) -> dict:
    total: dict[str, int] = {}
    for p in parts:
        for label, count in p["counts"].items():
            total[label] = total.get(label, 0) + int(count)
    return total


def figures_v1(suite, order: list[dict]) -> tuple[dict, dict, list]:
    """`clean`, `attacks` and `worst_case` of a `vinadv.bench_entry/1` entry, as they were computed when the format was
    released (its committed entries recompute byte for byte): the worst case at k over the attacks that reach k."""
    reached = np.array([v for c in order for v in c["clean"]["reached"]], dtype=bool)
    regret = np.array([np.nan if v is None else v for c in order for v in c["clean"]["regret"]], dtype=np.float64)
    n = len(reached)
    weights = [c["maps"] for c in order]

    def gppn(name):  # the chunks' means, weighted by their maps: the mean over every map
        return weighted_mean(weights, [c["clean"][name] for c in order])

    clean = {
        "maps": n,
        "reached": int(reached.sum()),
        "success_rate": float(reached.mean()),
        "percent_optimal": float((reached & (np.abs(regret) <= OPTIMAL_TOL)).mean()),
        "mean_regret": float(np.nanmean(regret)) if reached.any() else None,
    }
    if "search" in order[0]["clean"]:
        clean["gppn"] = None  # a search planner has no policy to follow from every cell
        clean["search"] = join_search([c["clean"]["search"] for c in order])
    else:
        clean["gppn"] = {
            "percent_optimal": gppn("gppn_percent_optimal"),
            "percent_success": gppn("gppn_percent_success"),
        }
    outcomes: dict[str, list[MapOutcomes]] = {}
    attacks = {}
    for group in suite.attacks:
        for key in group.keys():
            per_k = [[c["attacks"][key][k] for c in order] for k in range(group.max_obstacles)]
            outcomes[key] = [_outcome(parts) for parts in per_k]
            attacks[key] = {
                "strategy": key.split(":", 1)[1],
                "edit": group.edit,
                "by_obstacles": [
                    Figures.of(k + 1, o, counts=_counts(parts)).to_dict()
                    for k, (o, parts) in enumerate(zip(outcomes[key], per_k))
                ],
            }
    max_k = max(g.max_obstacles for g in suite.attacks)
    worst = []
    for k in range(max_k):
        at_k = [outs[k] for outs in outcomes.values() if len(outs) > k]
        worst.append({**Figures.of(k + 1, worst_case(at_k)).to_dict(), "attacks": len(at_k)})
    return clean, attacks, worst
