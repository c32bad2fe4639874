"""A benchmark result entry: one planner (with its weights) run on one suite (`vinadv.bench.suites`).

The suite's maps are run in chunks of `suite.chunk` maps (`compute_chunk`): the clean planner on them, then every
attack group of the suite through the robustness benchmark (`vinadv.robustness.robustness`: one pair per map, 1..k
cells edited greedily, labelled and judged for harm), keeping every map's outcome. With a database each finished
chunk is stored in one transaction (`Store.add_bench_chunk`), so `--resume` after a crash, even kill -9, recomputes
only the chunks not stored; the randomised strategies draw as they would over the whole suite (`first_map`), so the
chunks make the whole suite's pairs. Two runs resuming one entry at once may both compute a chunk: the first stores
it, the other checks its own is the same and uses the stored one (`vinadv.bench.chunkstore`). Without a shared
database the chunks may be computed in parts, files joined later (`run_part`, `vinadv.bench.parts`). The entry
(`make_entry`) is then computed from the per-map outcomes of all chunks, in map order:

- `clean`: the unattacked maps. vinadv's convention: rollout success from the start (`success_rate`), the share of
  maps whose path is optimal (`percent_optimal`), the mean regret of the reached paths; GPPN's convention (`gppn`:
  `percent_optimal`, `percent_success` over every free cell, `vinadv.evaluation.protocols.gppn_protocol`, averaged over
  the maps); for a search planner, which has no policy to follow from every cell, `gppn` is None and `search` holds
  the Neural A* authors' Opt / Exp / Hmean, success, cost ratio and expansions (`join_search`).
- `attacks`: per attack (`edit:strategy`), its figures at k = 1..max (`vinadv.robustness.Figures`: paper success rate,
  harmful rate, mean regret, label counts), the k curve.
- `worst_case`: per k, the worst case per map over the attacks that reach k (`vinadv.robustness.worst_case`).
- `flags` (`vinadv.bench.flags`), `time` (wall seconds, per chunk) and `machine` (where it ran).

That is the entry of a suite of definitions 1 (`vinadv.bench_entry/1`). A suite of definitions 2 writes
`vinadv.bench_entry/2` (`vinadv.bench.outcomes`): the per-map outcomes of the chunks (`per_map`), every figure computed
from them, the worst case at k over every attack of at most k edits; and its `checks` and `submission`. A group with a
`start` (`AttackGroup.start`) chains from the cells the named strategy's group kept on each map in the same chunk
(kept in the chunk and the entry, `start_cells`, for a recompute: `vinadv.bench.reuse`).

Everything but `time` and `machine` is a function of the suite, the planner and its weights: the same on the same
device type, byte for byte (`entry_json` writes sorted keys, fixed indentation).
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from vinadv import __version__
from vinadv.attacks.strategies import STRATEGIES
from vinadv.bench.flags import CHECK_MAPS, differs_between_passes, gradient_is_masked, raise_flags, trained_rules
from vinadv.bench.outcomes import cells_array, cells_json, chunk_per_map, entry_figures, figures_v1
from vinadv.bench.suites import ENTRY_FORMAT_2, DataSuite, Suite, maps_sha256
from vinadv.errors import InputError
from vinadv.evaluation.protocols import gppn_protocol
from vinadv.evaluation.search_metrics import path_costs, search_rows
from vinadv.executor import LOCAL, Executor, resolve, shipped
from vinadv.grid.mapset import MapSet
from vinadv.planners.interface import Planner
from vinadv.records import BENCH_CHUNK, RECORD_VERSIONS, VERSION_KEY
from vinadv.robustness import attack_settings, heldout_maps, robustness

#: an entry's fields that depend on when and where it ran (the rest is deterministic)
VOLATILE_FIELDS = ("time", "machine")
#: the results-format version of a stored chunk: bumped whenever what `compute_chunk` computes changes, so that
#: `--resume` never joins chunks of two computations (chunks stored before fingerprints are version 1). Version 2
#: added the efforts of a planner that reports its expansions; a planner that reports none computes what it did in
#: version 1, so its chunks keep version 1 (`chunk_format`) and stay reusable
CHUNK_FORMAT = 2


def chunk_format(planner: Planner) -> int:
    """The results format of `planner`'s chunks: `CHUNK_FORMAT`, or 1 for a planner that reports no expansions
    (nothing it computes changed in version 2)."""
    return CHUNK_FORMAT if planner.capabilities.expansions else 1


def suite_maps(suite: Suite, data: str | os.PathLike | None = None) -> MapSet:
    """The suite's maps, checked against its frozen sha256: generated, or for a `DataSuite` read from the folder
    `data` (`data_suite_maps`). InputError when they differ (a generator or reader that makes other maps), or for
    `data` given to a suite that makes its maps, or missing for one that reads them."""
    if isinstance(suite, DataSuite):
        maps, what = data_suite_maps(suite, data), "reader"
    else:
        if data is not None:
            raise InputError(f"suite {suite.name} makes its maps: data (a folder of files) is for data suites", "data")
        maps, what = heldout_maps(suite.n, suite.size, seed=suite.maps_seed), "generator"
    digest = maps_sha256(maps.obstacles, maps.starts[:, 0], maps.goals)
    if digest != suite.maps_sha256:
        raise InputError(
            f"suite {suite.name}: this vinadv's {what} makes other maps (sha256 {digest[:12]}, the suite froze "
            f"{suite.maps_sha256[:12]}); its results would not compare",
            "suite",
        )
    return maps


def data_suite_maps(suite: DataSuite, data: str | os.PathLike | None) -> MapSet:
    """A data suite's maps from the folder `data`: each file checked against its sha256 (InputError naming the file
    and both checksums), its split imported with one start per map (`vinadv.interop.formats.read_maps`, seed
    `suite.maps_seed`), its first maps taken, the files joined in order."""
    if data is None:
        names = ", ".join(f.name for f in suite.files)
        raise InputError(f"suite {suite.name} reads public files: give data, the folder holding {names}", "data")
    from vinadv.interop.formats import read_maps  # noqa: PLC0415 (the readers: only for a data suite)

    parts = []
    for f in suite.files:
        path = Path(data) / f.name
        if not path.is_file():
            raise InputError(f"{path}: no such file (suite {suite.name} reads it from data)", "data")
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        if digest != f.sha256:
            raise InputError(
                f"{path}: sha256 {digest} is not the {f.sha256} suite {suite.name} froze (another version of the file)"
            )
        # one start per map (`read_options`): the reader's k > 1 draws are not needed (and each is its own draw)
        maps, _ = read_maps(str(path), suite.layout, **suite.read_options(f))
        if len(maps) < f.maps:
            raise InputError(f"{path}: {len(maps)} maps in split {suite.split}, suite {suite.name} takes {f.maps}")
        parts.append(maps.take(np.arange(f.maps)))
    return MapSet.concat(parts)


def entry_key(suite: Suite, planner: Planner, name: str | None = None) -> str:
    """The entry's identity in a database: `spec_key` of the suite's checksum and the planner's spec."""
    return spec_key(suite.checksum, planner.spec(), name)


def spec_key(suite_checksum: str, spec: dict, name: str | None = None) -> str:
    """sha256 of a suite's checksum and a planner's spec, its name as the spec recorded it when the entry's chunks
    were first stored (`recorded_name`: `vin-robust` and `vin_robust` key as `vin_robust`, so the chunks stored and
    the entries committed before names were spelled with hyphens keep their keys); `name`: another name to key it
    by (`entry_keys`)."""
    from vinadv.planners.registry import recorded_name  # noqa: PLC0415 (light: the declarations)

    spec = {**spec, "name": recorded_name(spec["name"]) if name is None else name}
    text = json.dumps([suite_checksum, spec], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def entry_keys(suite: Suite, planner: Planner) -> list[str]:
    """Every key the chunks of this entry may be stored under, `entry_key` first: a fixed planner (`vin-robust`) was
    also loaded as its family with its weights (`--planner vin --weights vin28_robust`), whose spec named the family
    (`vin`), before the two were one planner."""
    from vinadv.planners.registry import REGISTRY, SUFFIX, canonical_name  # noqa: PLC0415 (light)

    name = canonical_name(planner.spec()["name"])
    suffix = SUFFIX if name.endswith(SUFFIX) else ""
    info = REGISTRY.get(name[: len(name) - len(suffix)])
    keys = [entry_key(suite, planner)]
    if info is not None and not info.takes_weights and info.family is not None:
        keys.append(entry_key(suite, planner, info.family + suffix))
    return keys


def strategy_revisions(suite: Suite) -> dict[str, int]:
    """The revision of every strategy `suite` runs, by name (`vinadv.attacks.strategies.Attack.revision`)."""
    names = sorted({s for group in suite.attacks for s in group.strategies})
    return {name: STRATEGIES[name].revision for name in names}


def computed_with(suite: Suite, planner: Planner) -> dict:
    """What an entry of format 2 of `planner` on `suite` is computed with (its field `computed_with`,
    `vinadv.bench.reuse`): the chunks' `results_format` and the suite's `strategies` with their revisions."""
    return {"results_format": chunk_format(planner), "strategies": strategy_revisions(suite)}


def chunk_fingerprint(suite: Suite, planner: Planner) -> dict:
    """What a stored chunk must have been computed with to be reused (`run_bench`): the results format
    (`chunk_format`), the suite's checksum, the revision of each of its strategies (`strategy_revisions`) and the
    planner's provenance (a bring-your-own planner's: the files it imports from beside it, or the version it
    declares, `vinadv.planners.provenance`; None for vinadv's own, which the results format covers). Stored beside
    the chunk's result (field `fingerprint`), out of the entry key."""
    provenance = getattr(planner, "provenance", None)
    return {
        "format": chunk_format(planner),
        "suite": suite.checksum,
        "strategies": strategy_revisions(suite),
        "provenance": provenance,
    }


def chunk_maps(maps: MapSet, lo: int, hi: int) -> MapSet:
    """Maps `lo:hi` of `maps` (with their starts and expert paths, frozen cells and provenance)."""
    return maps.take(np.arange(lo, min(hi, len(maps))))


def _floats(values) -> list:
    return [None if np.isnan(v) else float(v) for v in np.asarray(values, dtype=np.float64)]


def _clean_part(planner: Planner, sub: MapSet) -> dict:
    """A chunk's clean part: each map's path reached and regret, and the clean protocol's means (and values)."""
    plans = planner.plan(sub.obstacles, sub.starts[:, 0], sub.goals, sub.corner_cutting, sub.moves)
    # costs under the maps' movement model (every move 1 on `moore`), as their expert costs
    regret = np.where(plans.reached, path_costs(plans.paths, sub.moves) - sub.expert_costs[:, 0], np.nan)
    if not planner.capabilities.policy:  # no policy at every cell: the Neural A* authors' Opt / Exp instead
        rows = search_rows(planner, sub)
        clean = {"search": dict(rows.metrics())}
        # each map's values behind the means (one start per map): their bootstrap intervals over the maps
        clean["cost_ratio"] = _floats(rows.cost_ratio)
        exp = rows.exp
        if exp is not None:
            clean["exp"] = _floats(exp)
    else:
        gppn = gppn_protocol(planner, sub)
        clean = {"gppn_percent_optimal": gppn["percent_optimal"], "gppn_percent_success": gppn["percent_success"]}
    return {"reached": plans.reached.tolist(), "regret": _floats(regret), **clean}


def compute_chunk(
    suite: Suite,
    planner: Planner,
    maps: MapSet,
    chunk: int,
    compute=None,
    reused: dict | None = None,
    progress: bool = False,
) -> dict:
    """Chunk `chunk` of the suite (maps `chunk * suite.chunk ..`): the clean planner and every attack, per map (the
    record `vinadv.records.BENCH_CHUNK`, its version included), and `start_cells`: the one-cell cells each start of a
    chain kept on each map (`Suite.start_keys`, `vinadv.bench.outcomes.cells_json`; absent in a suite without chains,
    or where some start's cells were neither computed nor given). `compute`: {group index: the group's strategies to
    compute} (None: all of every group); `reused`: the chunk's parts taken from an entry instead
    (`vinadv.bench.reuse`: its `clean`, where given, the records of every attack not computed and, where given,
    `start_cells`). `progress`: a bar per attack counting the chunk's maps, each cleared when done (under the
    run's bar)."""
    t0 = time.perf_counter()
    lo = chunk * suite.chunk
    sub = chunk_maps(maps, lo, min(len(maps), lo + suite.chunk))
    reused = reused or {}
    clean = reused["clean"] if "clean" in reused else _clean_part(planner, sub)
    attacks = dict(reused.get("attacks", {}))
    cells = {key: cells_array(values) for key, values in reused.get("start_cells", {}).items()}
    for i, group in enumerate(suite.attacks):
        names = group.strategies if compute is None else tuple(compute.get(i, ()))
        if not names:
            continue
        # each strategy runs alone (its own attack, seed and settings): a subset of the group makes the same pairs
        # a group started from an earlier group's one-cell pairs (the exhaustive optimum) chains from its cells
        start = None if group.start is None else cells[f"{group.edit}:{group.start}"]
        result = robustness(
            planner,
            sub,
            names,
            group.max_obstacles,
            edit=group.edit,
            first_map=lo,
            start=start,
            progress=progress,
            **attack_settings(suite),
        )
        keys = dict(zip(group.strategies, group.keys()))
        for name, strategy in result.strategies.items():
            if group.start is None:
                cells[keys[name]] = strategy.cells[0]
            attacks[keys[name]] = [_attack_part(o, f) for o, f in zip(strategy.outcomes, strategy.by_k)]
    out = {"first_map": lo, "maps": len(sub), "clean": clean, "attacks": attacks}
    if suite.start_keys() and all(key in cells for key in suite.start_keys()):
        out["start_cells"] = {key: cells_json(cells[key]) for key in suite.start_keys()}
    return {**out, "seconds": round(time.perf_counter() - t0, 3), VERSION_KEY: RECORD_VERSIONS[BENCH_CHUNK]}


def _attack_part(o, f) -> dict:
    """One attack's part of a chunk at one k: its outcomes `o` (`vinadv.robustness.MapOutcomes`) and figures `f`."""
    return {
        "pair": o.pair.tolist(),
        "valid": o.valid.tolist(),
        "broken": o.broken.tolist(),
        "harmful": o.harmful.tolist(),
        "regret": _floats(o.regret),
        "label": o.label.tolist(),
        "counts": f.counts,
        # a planner that reports its expansions: each valid pair's effort ratio and verdict
        **(
            {}
            if o.effort_harmful is None
            else {"effort": _floats(o.effort), "effort_harmful": o.effort_harmful.tolist()}
        ),
    }


def make_entry(
    suite: Suite,
    planner: Planner,
    chunks: dict[int, dict],
    checks: dict,
    seconds: float,
    submission: dict | None = None,
) -> dict:
    """The entry of `planner` on `suite` from its chunks' results (`compute_chunk`, {chunk: result}, all of them):
    `vinadv.bench_entry/1` for a suite of definitions 1, else `vinadv.bench_entry/2`, its figures computed from the
    per-map outcomes it holds (`vinadv.bench.outcomes`), with `checks` and the `submission` (`submission_fields`;
    an entry of format 1 has none: InputError where one is given)."""
    order = [chunks[c] for c in sorted(chunks)]
    spec = planner.spec()
    head = {
        "format": suite.entry_format,
        "suite": {"name": suite.name, "checksum": suite.checksum},
        "vinadv_version": __version__,
        "planner": spec,
        "weights_sha256": spec.get("weights_sha256"),
    }
    submission = submission_fields(suite, submission)
    if suite.definitions == 1:
        clean, attacks, worst = figures_v1(suite, order)
        body = {"clean": clean, "attacks": attacks, "worst_case": worst}
    else:
        per_map = chunk_per_map(suite, order)
        body = entry_figures(suite, per_map)
        if "worst_effort" in body:
            per_map["worst_effort"] = body.pop("worst_effort")
        body = {"submission": submission, "checks": checks, **body, "per_map": per_map}
        body["computed_with"] = computed_with(suite, planner)
    return {
        **head,
        **body,
        "flags": raise_flags(suite, checks, body["clean"]["success_rate"], body["attacks"]),
        "time": {"wall_s": round(seconds, 3), "chunks_s": [c["seconds"] for c in order]},
        "machine": machine(),
    }


def submission_fields(suite: Suite, submission: dict | None) -> dict | None:
    """An entry's submission, every field (`vinadv.bench.validate.check_submission` checks them): `display_name`
    (text or null: the planner's label), `authors` (a list of names), `paper` and `code` (http or https links, or
    null) and `external` (submitted from outside the project: false by default). None for a suite of definitions 1,
    whose entries (format 1) carry none: InputError naming the first field given. InputError naming the field for a
    value the schema refuses."""
    from vinadv.bench.validate import Bad, check_submission  # noqa: PLC0415 (the schema: light, plain Python)

    given = [name for name, value in (submission or {}).items() if value]
    if suite.definitions == 1:
        if given:
            raise InputError(
                f"{given[0]}: suite {suite.name}'s entries ({suite.entry_format}) carry no submission; run its -v2",
                given[0],
            )
        return None
    out = {"display_name": None, "authors": [], "paper": None, "code": None, "external": False, **(submission or {})}
    try:
        check_submission(out)
    except Bad as exc:
        name = exc.field.split(".")[1].split("[")[0]
        raise InputError(f"{name}: {exc.why}", name) from None
    return out


def machine() -> dict:
    """Where the entry was computed (not part of what must reproduce)."""
    import torch  # noqa: PLC0415 (PyTorch: the planners loaded it already)

    return {
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "torch": torch.__version__,
        "device": "cuda" if torch.cuda.is_available() else "cpu",
        "torch_threads": torch.get_num_threads(),
    }


def planner_checks(suite: Suite, planner: Planner, maps: MapSet) -> dict:
    """The flags' checks on the suite's first maps: is the gradient masked, do two forward passes differ; and the
    rule the planner's weights were trained under (`trained_rules`)."""
    sub = chunk_maps(maps, 0, min(len(maps), CHECK_MAPS))
    args = (planner, sub.obstacles, sub.starts[:, 0], sub.goals, sub.corner_cutting)
    return {
        "gradient_masked": gradient_is_masked(*args),
        "non_deterministic": differs_between_passes(*args),
        "trained_rules": trained_rules(planner),
    }


@dataclasses.dataclass(frozen=True)
class SuiteMaps:
    """A suite's maps by reference, for a remote task (`vinadv.executor.shipped`): made, or read from the folder
    `data` (an absolute path), once per process; known by the suite's checksum."""

    suite: Suite = dataclasses.field(compare=False)
    checksum: str
    data: str | None

    def load(self) -> MapSet:
        return suite_maps(self.suite, self.data)


def _chunk_task(suite: Suite, planner, maps, reuse, progress: bool, chunk: int) -> tuple[int, dict]:
    """The task of `run_bench`: `(chunk, compute_chunk(...))`, the planner and maps given or by reference; `reuse`:
    None, or what is taken from an older entry (`vinadv.bench.reuse.ReusePlan`); `progress`: `compute_chunk`'s."""
    args = () if reuse is None else (reuse.computed, reuse.chunk_part(suite, chunk))
    return chunk, compute_chunk(suite, resolve(planner), resolve(maps), chunk, *args, progress=progress)


def run_bench(
    suite: Suite,
    planner: Planner,
    db: str | None = None,
    resume: bool = False,
    progress: bool = False,
    data: str | os.PathLike | None = None,
    executor: Executor = LOCAL,
    planner_ref=None,
    submission: dict | None = None,
    reuse=None,
    parts=(),
) -> dict:
    """The entry of `planner` on `suite` (module doc). With `db` each chunk is stored when done; with `resume` the
    chunks stored there are read, not recomputed (without it, a database already holding chunks of this entry is
    refused: say --resume, or use another database). `data`: the folder of a data suite's files.

    The chunks are computed on `executor` (`vinadv.executor`: in this process, in order, by default) and stored as
    they come back, in any order; a remote executor needs the planner by reference, `planner_ref`
    (`vinadv.planners.registry.PlannerRef.of`). `submission`: the entry's submission fields (`submission_fields`;
    an entry of format 2 only), checked before the work. `reuse`: an older entry of format 2 of this suite and
    planner (a dict, or `vinadv.bench.reuse.ReusedEntry`) whose attacks that did not change are taken from it
    (`vinadv.bench.reuse.plan_reuse`; InputError naming the field of another suite, planner or format). `parts`:
    parts of the entry computed before (`vinadv.bench.parts.Part`, read), whose chunks are taken."""
    t0 = time.perf_counter()
    _check_remote(executor, planner_ref)
    submission_fields(suite, submission)  # refused in one line before the work
    plan = _reuse_plan(suite, planner, reuse)
    maps = suite_maps(suite, data)
    checks = planner_checks(suite, planner, maps)
    done = _chunks(suite, planner, maps, None, db, resume, progress, data, executor, planner_ref, plan, parts)
    entry = make_entry(suite, planner, done, checks, time.perf_counter() - t0, submission)
    if plan is not None:  # how it was made: `time` is not part of what must reproduce
        entry["time"]["reused"] = plan.reused_time()
    if parts:
        entry["time"]["parts"] = [{"sha256": p.sha256, "chunks": sorted(p.part["chunks"])} for p in parts]
    return entry


def run_part(
    suite: Suite,
    planner: Planner,
    chunks: list[int],
    db: str | None = None,
    resume: bool = False,
    progress: bool = False,
    data: str | os.PathLike | None = None,
    executor: Executor = LOCAL,
    planner_ref=None,
    reuse=None,
    parts=(),
) -> dict:
    """The part of the entry of `planner` on `suite` that holds the chunks numbered in `chunks`
    (`vinadv.bench.parts`): each computed as `run_bench` computes it (the arguments are `run_bench`'s), or taken from
    `db` with `resume`, or from `parts`."""
    from vinadv.bench.parts import make_part  # noqa: PLC0415 (only for a part)

    t0 = time.perf_counter()
    _check_remote(executor, planner_ref)
    plan = _reuse_plan(suite, planner, reuse)
    maps = suite_maps(suite, data)
    done = _chunks(suite, planner, maps, chunks, db, resume, progress, data, executor, planner_ref, plan, parts)
    # a chunk read from the database carries its fingerprint: the part holds it once, for all of its chunks
    kept = {c: {k: v for k, v in done[c].items() if k != "fingerprint"} for c in chunks}
    return make_part(suite, planner.spec(), chunk_fingerprint(suite, planner), kept, time.perf_counter() - t0)


def _check_remote(executor: Executor, planner_ref) -> None:
    """InputError naming `planner_ref` where a remote executor is not given the planner by reference."""
    if executor.remote and planner_ref is None:
        raise InputError("planner_ref: a remote executor needs the planner by reference", "planner_ref")


def _reuse_plan(suite: Suite, planner: Planner, reuse):
    """What is taken from the older entry `reuse` (`vinadv.bench.reuse.plan_reuse`), or None without one."""
    if reuse is None:
        return None
    from vinadv.bench.reuse import plan_reuse  # noqa: PLC0415 (only with an entry to reuse)

    return plan_reuse(suite, planner, reuse)


def _chunks(suite, planner, maps, only, db, resume, progress, data, executor, planner_ref, plan, parts):
    """The chunks of `run_bench` and `run_part` ({chunk: result}): those numbered in `only` (None: all of them),
    taken from `parts` and, with `resume`, from `db`, the others computed (and stored in `db`); `plan`: what is taken
    from an older entry (`_reuse_plan`)."""
    keys = entry_keys(suite, planner)
    key = keys[0]
    fingerprint = chunk_fingerprint(suite, planner)
    n_chunks = -(-suite.n // suite.chunk)
    done: dict[int, dict] = {}
    if parts:
        from vinadv.bench.parts import part_chunks  # noqa: PLC0415 (only with parts)

        done = part_chunks(list(parts), fingerprint)
    store = None
    if db is not None:
        from vinadv.bench.chunkstore import check_stored, same_chunk, stored_chunks  # noqa: PLC0415 (only with --db)
        from vinadv.store import Store  # noqa: PLC0415 (SQLAlchemy: only with --db)

        store = Store.open(db)
        try:
            stored, key = stored_chunks(store, db, keys, suite, n_chunks, fingerprint, resume)
            for chunk, result in stored.items():  # a chunk in a part and in the database: the same in both
                if chunk in done:
                    same_chunk(
                        f"database {db}",
                        chunk,
                        done[chunk],
                        result,
                        fingerprint,
                        "resume",
                        "in a part",
                        "the database's",
                    )
                done.setdefault(chunk, result)
        except InputError:
            store.close()
            raise
    wanted = range(n_chunks) if only is None else only
    todo = [c for c in wanted if c not in done]

    def chunk_maps(chunk: int) -> int:
        """The maps of chunk `chunk` (the last one may be short)."""
        return min(suite.n, (chunk + 1) * suite.chunk) - chunk * suite.chunk

    absolute = None if data is None else os.path.abspath(os.fspath(data))  # workers may run in another folder
    task = functools.partial(
        _chunk_task,
        suite,
        shipped(executor, planner, lambda: planner_ref),
        shipped(executor, maps, lambda: SuiteMaps(suite, suite.checksum, absolute)),
        plan,
        # a chunk's attacks show their maps where the chunk runs here: a remote worker's bar would be seen by no one
        bool(progress) and not executor.remote,
    )
    bar = None
    if progress:
        from tqdm import tqdm  # noqa: PLC0415 (only with a progress bar)

        # counts maps (a chunk's at once as it completes), so that tqdm's time left reads in maps; the bars of the
        # chunk's attacks show the maps in between
        total = sum(map(chunk_maps, wanted))
        bar = tqdm(desc=f"bench {suite.name}", unit="map", initial=total - sum(map(chunk_maps, todo)), total=total)
    try:
        for chunk, result in executor.map(task, todo, ordered=False):
            if store is not None:
                stored = store.add_bench_chunk(
                    key, chunk, {**result, "fingerprint": fingerprint}, check=check_stored(suite, n_chunks)
                )
                if stored is not None:  # stored meanwhile (another run resuming this entry): the same, or refused
                    result = same_chunk(f"database {db}", chunk, stored, result, fingerprint)
            done[chunk] = result
            if bar is not None:
                bar.update(chunk_maps(chunk))
    finally:
        if bar is not None:
            bar.close()
        if store is not None:
            store.close()
    return done


def entry_json(entry: dict) -> str:
    """The entry as written: sorted keys, two-space indentation, a final newline; in an entry of format 2 a list of
    plain values (the per-map outcomes, one value per map) on one line."""
    if entry.get("format") == ENTRY_FORMAT_2:
        return _compact(entry, "") + "\n"
    return json.dumps(entry, sort_keys=True, indent=2) + "\n"


def _compact(value, indent: str, cells: bool = False) -> str:
    """`value` as `json.dumps(sort_keys=True, indent=2)` writes it, but for its lists of plain values, one line each;
    `cells`: `value` is `per_map.start_cells`, each of its lists of cells on one line."""
    inner = indent + "  "
    if isinstance(value, dict) and value:
        # per_map.start_cells: per map a cell or null, on one line as the other per-map lists
        shown = {k: json.dumps(v) if cells else _compact(v, inner, k == "start_cells") for k, v in value.items()}
        items = [f"{inner}{json.dumps(k)}: {shown[k]}" for k in sorted(value)]
        return "{\n" + ",\n".join(items) + f"\n{indent}}}"
    if isinstance(value, list) and any(isinstance(v, (dict, list)) for v in value):
        return "[\n" + ",\n".join(inner + _compact(v, inner) for v in value) + f"\n{indent}]"
    return json.dumps(value, sort_keys=True)


def deterministic_part(entry: dict) -> dict:
    """The entry without its time and machine fields: what must reproduce byte for byte."""
    return {k: v for k, v in entry.items() if k not in VOLATILE_FIELDS}
