"""Attack strategies, from random to exhaustive, batched, on any planner (`vinadv.planners`): one added obstacle
per map (the paper's setting), or K added greedily; or, with `edit="remove"`, one (or K) obstacle cells freed.

Every strategy follows the same three steps, and differs only in the first:

1. score the candidate cells of each map (`candidate_scores`, `(B, N, N)`, `-inf` = not a candidate); only
   valid cells (see `validity.valid_cells`) are ever candidates, never a frozen cell (`frozen`);
2. evaluate the `budget` best-scored candidates of each map: add the obstacle, plan on the adversarial map
   (the original map is planned once per map);
3. keep `per_map` pairs per map: for the ranking strategies, the strongest by `strength` (default: a
   planner-only order; the command line passes the rule labeller's UrP > FP > DP > UcP), ties going to the
   better-scored candidate; for `random` and `near-path`, every evaluated candidate.

The strategies:
- `random`: uniformly chosen valid cells.
- `near-path`: uniformly chosen valid cells within Chebyshev distance `radius` (default 2) of the original
  planner path, path cells included (the paper's setting adds one obstacle "near the path"; its three rules are not
  public, so this is ours).
- `key-points`: rule-based ranking, in tiers: (1) cells where the original path turns (earlier turns first),
  (2) cells beside a diagonal move of the path (the corners it cuts), (3) other cells next to the path, steepest
  value change to a neighbour first (`Planner.value_maps`: the VIN's value map, `optimal`'s cost-to-go, for other
  planners the log-probability of the chosen action), (4) the remaining path cells. Evaluates the top `budget`
  (default 8).
- `saliency`: white-box. The gradient, with respect to the obstacles, of the log-probability of the planner's
  chosen actions along the original path (autograd through `Planner.logits_module`); the most negative
  gradient first (adding an obstacle there lowers the planner's confidence in its own path the most, to first
  order). Evaluates the top `budget`. A planner without gradients (`optimal`) is ranked as by `key-points`, and the
  pairs' params record it: `ranked_as: "key-points"`.
- `exhaustive`: every valid cell of every map; keeps the strongest per map, or all pairs with `per_map=0`.
  This is the upper bound of what one obstacle can do.

On a planner without a policy at every cell (`Capabilities.policy` False: a search planner): `random`,
`near-path` and `exhaustive` are unchanged (they need only paths); `key-points` ranks tier 3 by the planner's
`value_maps`, its own cost or heuristic map where it has one, else minus the exact cost-to-go; `saliency` takes the
gradient, with respect to the obstacles, of the planner's differentiable path map
(`SearchPlanner.differentiable_paths`, a soft path as Neural A*'s) summed over the cells of the original path, most
negative first (an obstacle there pulls the path off its cells the most, to first order); a search planner without
one is ranked as by `key-points`, recorded as `ranked_as: "key-points"` as for `optimal`.

Obstacle removal (`edit="remove"`, DESIGN.md "Obstacle removal"): the candidates are the removable cells
(`validity.removable_cells`: obstacle cells, never a border wall) instead of the valid free cells, and the chosen cell
is freed instead of filled. Freeing a cell makes the world easier (the optimum never gets longer), so any harm it
causes is the planner's own failure. Each strategy's removal candidates:
- `random`: uniform over the removable cells.
- `near-path`: uniform over the removable cells within Chebyshev distance `radius` of the original planner path.
- `key-points`: the same tiers and signal as for additions, on obstacle cells: (2) the corners a diagonal move of the
  path passes (with corner cutting they may be obstacles), earlier first; (3) other obstacles next to the path, by
  the value change across the cell (the largest |value difference| between two free 8-neighbours of the cell: what a
  shortcut through it would skip); (4) every other removable cell, by the same value change. (Tiers 1 and the path
  cells of tier 4 hold only free cells.)
- `saliency`: the same gradient, the sign flipped for the direction of the edit: freeing a cell lowers its obstacle
  input from 1 to 0, so the most positive gradient lowers the planner's confidence in its own path the most.
- `exhaustive`: every removable cell.
K cells (`obstacles=K`) are freed greedily exactly as K are added (each step on the map with the cells freed so far).

K obstacles (`obstacles=K`, DESIGN.md "Several obstacles"): greedy. Step 1 is the attack above; each later step runs
the same strategy again on the maps with the cells chosen so far added (their valid cells, the planner's paths on
them, the strategy's candidates, a fresh random stream: `SeedSequence(seed, spawn_key=(step,))`). Every candidate is
judged as the pair it would make with the ORIGINAL map (its path and the `strength` against it). A step before the
last keeps the strongest candidate of each map (per_map 1 of a ranking strategy, whatever the strategy: for `random`
and `near-path` the strongest of their `per_map` drawn cells); the last step keeps `per_map` pairs as a one-obstacle
attack does. So the pairs of K obstacles with per_map 1 extend those of K - 1 (`AttackResult.steps` holds every
step's pairs). A map with no valid cell at some step gets no pair; once no map has one, the search stops there (a K
past the cells a map can take, `obstacles=10**9`, ends when the cells run out): its pairs are that step's (none),
and `steps` ends with it, as every later step would make none.

The strategies and the shared steps (evaluate, keep, greedy K, removal) are in this one module, as CleanRL keeps an
algorithm in one file: the strategies differ only in how they score candidates. The white-box strategy's gradients
(PyTorch) are in `vinadv.attacks.gradients`, the neighbourhoods the ranking reads in `vinadv.attacks.neighbourhood`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from vinadv.attacks.gradients import TORCH_CHUNK as TORCH_CHUNK  # the white-box chunk, importable here too
from vinadv.attacks.gradients import path_saliency, policy_saliency
from vinadv.attacks.neighbourhood import steepness, steepness_across, within_distance
from vinadv.attacks.pairs import PairSet
from vinadv.attacks.validity import removable_cells, valid_cells
from vinadv.errors import InputError
from vinadv.grid.paths import PackedPaths
from vinadv.grid.selection import smallest_first
from vinadv.planners.interface import Planner
from vinadv.planners.result import PlanResult
from vinadv.planners.vin.planner import as_planner
from vinadv.vocabulary import ADD, EDITS, REMOVE

#: candidates planned together, about (a chunk is whole maps: it ends at the first map starting past a multiple of
#: this): bounds memory (each holds an N x N map and a path) and sets how often the progress bar moves, about once per
#: map of an exhaustive attack. The planners cut a batch in chunks of this order themselves (`plan_maps`' 1024 maps),
#: so larger ones would not plan faster (`perf/eval_chunk.py`)
EVAL_CHUNK = 1024


def planner_strength(pairs: PairSet) -> np.ndarray:
    """A planner-only strength, used when no labeller is given: unreached 3, changed path 1, unchanged 0."""
    changed = ~pairs.path_o.same_as(pairs.path_a)
    return np.where(~pairs.reached_a & pairs.reached_o, 3, np.where(changed, 1, 0))


@dataclass
class AttackResult:
    """What an attack made.

    Attributes:
        pairs: the map pairs, grouped by map in map order (`pairs.map_index`); `pairs.added` is `(n, K, 2)`.
        no_valid_cell: indices of the maps for which no valid candidate existed, at some step (no pair was made for
            them).
        planner_calls: rollouts run, the original maps' included.
        steps: the pairs kept after each greedy step, `steps[k - 1]` of k added obstacles (the original map against
            the map with the first k cells); the last is `pairs`. With per_map 1, `steps[k - 1]` is exactly what an
            attack with `obstacles=k` makes. Fewer than K where every map ran out of valid cells before step K (the
            last is then empty, and so would every later step be).
    """

    pairs: PairSet
    no_valid_cell: np.ndarray
    planner_calls: int
    steps: list[PairSet] = field(default_factory=list)


@dataclass
class AttackContext:
    """What every strategy may use to score candidates of one step.

    Attributes:
        obstacles: `(B, N, N)` bool, the maps searched at this step: the original maps at the first step, the maps
            with the cells chosen so far added at a later one. starts, goals: `(B, 2)`.
        valid: `(B, N, N)` bool, the valid cells of `obstacles` (`validity.valid_cells`; none for a map already
            out of the attack).
        plans: the planner's paths on `obstacles`. planner; rng: this step's random stream.
        base_obstacles, base: the original maps and the planner's paths on them (the pairs are made against them;
            default: `obstacles` and `plans`). added: `(B, k, 2)`, the k cells chosen at the steps before (default
            none). edit: `add` (the candidates are free cells to fill) or `remove` (obstacle cells to free).
        base_expanded, base_astar: for a planner that reports expansions, the cells it expanded on the original maps
            (`PackedPaths`) and the exact A*'s expansion counts there (`(B,)`), which every pair carries; else None.
    """

    obstacles: np.ndarray
    starts: np.ndarray
    goals: np.ndarray
    valid: np.ndarray
    plans: PlanResult
    planner: Planner
    rng: np.random.Generator
    base_obstacles: np.ndarray | None = None
    base: PlanResult | None = None
    added: np.ndarray | None = None
    edit: str = ADD
    base_expanded: PackedPaths | None = None
    base_astar: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.base_obstacles is None:
            self.base_obstacles = self.obstacles
        if self.base is None:
            self.base = self.plans
        if self.added is None:
            self.added = np.zeros((len(self.obstacles), 0, 2), np.int64)

    def path_mask(self) -> np.ndarray:
        """`(B, N, N)` bool: the cells of the planner's path on each searched map."""
        mask = np.zeros_like(self.obstacles)
        paths = self.plans.paths
        cells = paths.cells.astype(np.int64)
        mask[paths.owners(), cells[:, 0], cells[:, 1]] = True
        return mask


class Attack:
    """Base class: subclasses set `name` and implement `candidate_scores`.

    `revision`: bumped whenever a change alters the strategy's results (its pairs, on some planner), so that an entry
    recomputed from an older one (`vinadv bench run --reuse`, `vinadv.bench.reuse`) recomputes its attacks."""

    name = ""
    revision = 1
    ranked = True  # keep the strongest evaluated candidates; False: keep every evaluated candidate

    def __init__(self, per_map: int = 1, budget: int | None = 8, seed: int = 0, obstacles: int = 1, edit: str = ADD):
        if edit not in EDITS:
            raise InputError(f"edit must be one of {'|'.join(EDITS)}, got {edit!r}", "edit")
        if per_map < 0:
            raise InputError(f"per_map must be >= 0, got {per_map}", "per_map")
        if budget is not None and budget < 1:
            raise InputError(f"budget must be >= 1, got {budget}", "budget")
        if obstacles < 1:
            raise InputError(f"obstacles must be >= 1, got {obstacles}", "obstacles")
        self.per_map = per_map
        self.budget = budget
        self.seed = seed
        self.obstacles = int(obstacles)
        self.edit = edit

    def params(self) -> dict:
        """The strategy's parameters, stored with its pairs (`_edited`: `edit` only for removal)."""
        return self._edited(
            {"per_map": self.per_map, "budget": self.budget, "seed": self.seed, "obstacles": self.obstacles}
        )

    def _edited(self, params: dict) -> dict:
        """`params` plus `edit` when the attack removes: an adding attack's parameters have no `edit` (an absent
        `edit` reads as `add`)."""
        return params if self.edit == ADD else {**params, "edit": self.edit}

    def candidate_scores(self, ctx: AttackContext) -> np.ndarray:
        raise NotImplementedError

    def ranked_as(self, planner: Planner) -> str | None:
        """The strategy whose ranking this one uses on `planner`, where it cannot rank its own way (saliency
        without gradients: key-points); None where it ranks its own way. Recorded in the pairs' params."""
        return None

    def attack(
        self,
        obstacles: np.ndarray,
        starts: np.ndarray,
        goals: np.ndarray,
        planner: Planner,
        corner_cutting: bool = True,
        strength: Callable[[PairSet], np.ndarray] | None = None,
        progress: bool = False,
        first_map: int = 0,
        frozen: np.ndarray | None = None,
        start: np.ndarray | None = None,
    ) -> AttackResult:
        """Attack a batch of maps with `planner` (a `Planner`, or a `VIN`): obstacles `(B, N, N)` bool, starts
        and goals `(B, 2)`; `self.obstacles` cells per pair, greedily (see the module doc).

        The maps' movement model is the planner's (`Planner.moves`: `load_planner` gives the planner for the maps'
        model): the valid cells and the pairs follow it.

        `first_map`: these maps are maps `first_map..first_map+B-1` of a larger batch; the result is that
        batch's result for them (so a batch can be attacked in shards). Randomised strategies draw one
        `rng.random((B, N, N))` per step, one PCG64 step per number, so a shard starts `first_map * N * N` steps in
        (every step draws for all B maps, those out of the attack included, so no map's draw depends on another's).

        `frozen`: `(B, N, N)` bool, the cells no step may add to or free (`MapSet.frozen`: an importer's padding), or
        None; they are never candidates (`validity`), so no strategy edits them.

        `start`: `(B, j, 2)` cells each map's chain starts from, edited already (another attack's kept cells: the
        exhaustive one-cell optimum), a map's rows -1 where it has none (it gets no pair); the greedy steps then make
        cells j + 1..`self.obstacles`, each step's stream the one it has without `start`, and `steps[i]` holds the
        pairs of j + i + 1 cells.
        """
        obstacles = np.ascontiguousarray(obstacles, dtype=bool)
        starts = np.ascontiguousarray(starts, dtype=np.int64)
        goals = np.ascontiguousarray(goals, dtype=np.int64)
        planner = as_planner(planner, obstacles.shape[1])
        strength = strength or planner_strength
        b = len(obstacles)
        base = planner.plan(obstacles, starts, goals, corner_cutting)
        base_expanded = getattr(base, "expanded_cells", None)  # a search planner's, where it reports them
        base_astar = None if base_expanded is None else _astar(obstacles, starts, goals, corner_cutting, planner.moves)
        calls = b
        current, plans = obstacles, base
        chosen = np.zeros((b, 0, 2), np.int64)
        alive = np.ones(b, dtype=bool)  # maps that got a cell at every step so far
        if start is not None:
            chosen = np.asarray(start, dtype=np.int64).reshape(b, -1, 2)
            alive = (chosen >= 0).all(axis=(1, 2))
            chosen = np.where(alive[:, None, None], chosen, 0)
            current = obstacles.copy()
            rows = np.flatnonzero(alive)
            for j in range(chosen.shape[1]):
                current[rows, chosen[rows, j, 0], chosen[rows, j, 1]] = self.edit == ADD
        steps: list[PairSet] = []
        for step in range(chosen.shape[1], self.obstacles):
            last = step == self.obstacles - 1
            if step:
                plans = planner.plan(current, starts, goals, corner_cutting)
                calls += b
            candidates = removable_cells if self.edit == REMOVE else valid_cells
            valid = candidates(current, starts, goals, corner_cutting, planner.moves, frozen) & alive[:, None, None]
            ctx = AttackContext(
                current,
                starts,
                goals,
                valid,
                plans,
                planner,
                self._rng(step, first_map, obstacles),
                base_obstacles=obstacles,
                base=base,
                added=chosen,
                edit=self.edit,
                base_expanded=base_expanded,
                base_astar=base_astar,
            )
            scores = np.where(valid, self.candidate_scores(ctx), -np.inf)
            alive &= np.isfinite(scores).any(axis=(1, 2))
            # a step before the last keeps the strongest candidate of each map, whatever the strategy
            map_idx, cells, rank = _top_candidates(scores, self._evaluated_per_map())
            desc = f"attack {self.name}" + (f", obstacle {step + 1}/{self.obstacles}" if self.obstacles > 1 else "")
            kept = self._evaluate(
                ctx,
                map_idx,
                cells,
                rank,
                corner_cutting,
                strength,
                progress and desc,
                keep=self.per_map if last else 1,
                ranked=self.ranked or not last,
            )
            calls += len(map_idx)
            # which planner the attacks were found on, and the ranking used where the strategy's own could not be
            fallback = self.ranked_as(planner)
            kept.params = {**kept.params, "planner": planner.spec(), **({"ranked_as": fallback} if fallback else {})}
            steps.append(kept)
            if not alive.any():  # no map has a cell left: every later step would make no pair
                break
            if not last:
                current = obstacles.copy()
                current[kept.map_index] = kept.obstacles_a
                chosen = np.zeros((b, step + 1, 2), np.int64)
                chosen[kept.map_index] = kept.added
        return AttackResult(steps[-1], np.flatnonzero(~alive), calls, steps)

    def _rng(self, step: int, first_map: int, obstacles: np.ndarray) -> np.random.Generator:
        """Step `step`'s random stream, advanced to map `first_map`: the seed's own for the first step (the stream of
        a one-obstacle attack), an independent child stream of the seed for each later one."""
        seed = self.seed if step == 0 else np.random.SeedSequence(self.seed, spawn_key=(step,))
        rng = np.random.default_rng(seed)
        rng.bit_generator.advance(first_map * obstacles.shape[1] * obstacles.shape[2])
        return rng

    def _evaluated_per_map(self) -> int | None:
        if not self.ranked:
            return self.per_map or None
        return self.budget

    def _evaluate(
        self, ctx, map_idx, cells, rank, corner_cutting, strength, progress, keep: int, ranked: bool
    ) -> PairSet:
        """The pairs of the candidates `(map_idx, cells, rank)`: with `ranked`, the `keep` strongest of each map
        (all with `keep` 0), else all. `progress`: a progress bar's description, or False: the bar counts the maps,
        moving as each chunk of them is judged, with tqdm's estimate of the time left."""
        # chunks of about EVAL_CHUNK candidates, split at map boundaries so a map's candidates are judged together
        n_maps = len(ctx.obstacles)
        first = np.searchsorted(map_idx, np.arange(n_maps + 1))
        chunk_of_map = first[:-1] // EVAL_CHUNK
        first_maps = np.append(np.searchsorted(chunk_of_map, np.unique(chunk_of_map)), n_maps)
        bar = None
        if progress:
            from tqdm import tqdm

            # leave=None: kept on its own, cleared under another bar (a bench run's, at position 0)
            bar = tqdm(total=n_maps, desc=progress, unit="map", leave=None)
        parts = []
        try:
            for m0, m1 in zip(first_maps[:-1], first_maps[1:]):
                lo, hi = first[m0], first[m1]
                if hi > lo:
                    parts.append(
                        self._evaluate_chunk(
                            ctx, map_idx[lo:hi], cells[lo:hi], rank[lo:hi], corner_cutting, strength, keep, ranked
                        )
                    )
                if bar is not None:
                    bar.update(int(m1 - m0))
        finally:
            if bar is not None:
                bar.close()
        return PairSet.concat(
            parts,
            size=ctx.obstacles.shape[1],
            strategy=self.name,
            params=self.params(),
            corner_cutting=corner_cutting,
            moves=ctx.planner.moves,
            n_added=ctx.added.shape[1] + 1,
        )

    def _evaluate_chunk(self, ctx, map_idx, cells, rank, corner_cutting, strength, keep, ranked) -> PairSet:
        obstacles_a = ctx.obstacles[map_idx].copy()
        obstacles_a[np.arange(len(map_idx)), cells[:, 0], cells[:, 1]] = ctx.edit == ADD
        planned = ctx.planner.plan(obstacles_a, ctx.starts[map_idx], ctx.goals[map_idx], corner_cutting)
        pairs = _make_pairs(ctx, map_idx, cells, obstacles_a, planned, corner_cutting)
        if ranked and keep:
            # per map, the `keep` strongest; ties to the better rank (lexsort: last key is the primary one)
            order = np.lexsort((rank, -np.asarray(strength(pairs)), map_idx))
            group_start = np.searchsorted(map_idx[order], map_idx[order], side="left")
            pairs = pairs.take(np.sort(order[np.arange(len(order)) - group_start < keep]))
        if pairs.expanded_a is not None:  # A*'s reference on the kept pairs' maps only
            pairs.astar_expansions_a = _astar(
                pairs.obstacles_a, pairs.starts, pairs.goals, corner_cutting, ctx.planner.moves
            )
        return pairs


def _top_candidates(scores: np.ndarray, per_map: int | None):
    """The best `per_map` candidates of each map (all with None), best first: (map_idx, cells, rank)."""
    b, n, m = scores.shape
    flat = scores.reshape(b, -1)
    order = smallest_first(-flat, flat.shape[1] if per_map is None else per_map)
    picked = np.take_along_axis(flat, order, axis=1)
    ok = np.isfinite(picked)
    map_idx = np.repeat(np.arange(b), order.shape[1]).reshape(b, -1)[ok]
    rank = np.tile(np.arange(order.shape[1]), (b, 1))[ok]
    cells = np.stack(np.divmod(order[ok], m), axis=1)
    return map_idx, cells, rank


def _astar(obstacles, starts, goals, corner_cutting: bool, moves: str) -> np.ndarray:
    """The exact A*'s expansion counts on these maps, the effort figures' reference."""
    from vinadv.planners.classical.astar import reference_expansions  # noqa: PLC0415 (Numba: search planners only)

    return reference_expansions(obstacles, starts, goals, corner_cutting, moves)


def _make_pairs(ctx: AttackContext, map_idx, cells, obstacles_a, planned: PlanResult, corner_cutting) -> PairSet:
    """The pairs (original map, searched map + cell): the original map's path against the new one's, and both
    searches' expanded cells where the planner reports them (A*'s on the adversarial maps are added once kept)."""
    added = np.concatenate([ctx.added[map_idx], cells.astype(np.int64)[:, None, :]], axis=1)
    expanded_a = getattr(planned, "expanded_cells", None)
    effort = ctx.base_expanded is not None and expanded_a is not None
    return PairSet(
        obstacles_o=ctx.base_obstacles[map_idx],
        obstacles_a=obstacles_a,
        starts=ctx.starts[map_idx],
        goals=ctx.goals[map_idx],
        added=added,
        map_index=map_idx.astype(np.int64),
        path_o=ctx.base.paths.take(map_idx),
        path_a=planned.paths,
        term_o=ctx.base.termination_names[map_idx],
        term_a=planned.termination_names,
        edit=ctx.edit,
        corner_cutting=corner_cutting,
        moves=ctx.planner.moves,
        expanded_o=ctx.base_expanded.take(map_idx) if effort else None,
        expanded_a=expanded_a if effort else None,
        astar_expansions_o=ctx.base_astar[map_idx] if effort else None,
    )


class RandomAttack(Attack):
    name = "random"
    ranked = False

    def params(self) -> dict:
        return self._edited({"per_map": self.per_map, "seed": self.seed, "obstacles": self.obstacles})

    def candidate_scores(self, ctx: AttackContext) -> np.ndarray:
        return ctx.rng.random(ctx.obstacles.shape)


class NearPathAttack(Attack):
    name = "near-path"
    ranked = False

    def __init__(self, per_map: int = 1, radius: int = 2, seed: int = 0, obstacles: int = 1, edit: str = ADD):
        super().__init__(per_map=per_map, budget=None, seed=seed, obstacles=obstacles, edit=edit)
        if radius < 0:
            raise InputError(f"radius must be >= 0, got {radius}", "radius")
        self.radius = radius

    def params(self) -> dict:
        return self._edited(
            {"per_map": self.per_map, "radius": self.radius, "seed": self.seed, "obstacles": self.obstacles}
        )

    def candidate_scores(self, ctx: AttackContext) -> np.ndarray:
        near = within_distance(ctx.path_mask(), self.radius)
        return np.where(near, ctx.rng.random(ctx.obstacles.shape), -np.inf)


class KeyPointsAttack(Attack):
    name = "key-points"
    revision = 2  # 2: the value maps of a planner with `Capabilities.start_values` read the attacked starts

    def candidate_scores(self, ctx: AttackContext) -> np.ndarray:
        b, n, _ = ctx.obstacles.shape
        paths = ctx.plans.paths
        cells, offsets, lengths, owner = paths.cells.astype(np.int64), paths.offsets, paths.lengths, paths.owners()
        pos = np.arange(len(cells)) - np.repeat(offsets[:-1], lengths)  # index along its path
        on_path = ctx.path_mask()
        scores = np.full((b, n, n), -np.inf)

        # an encoder with a start channel gets the starts, to rank the cells of the searches attacked, not of a map
        # whose start channel holds the goal alone
        starts = {"starts": ctx.starts} if ctx.planner.capabilities.start_values else {}
        value = ctx.planner.value_maps(ctx.obstacles, ctx.goals, **starts)
        near = within_distance(on_path, 1) & ~on_path
        if ctx.edit == REMOVE:
            # tier 4 (lowest): every obstacle, in [0, 1); tier 3: those next to the path, in [1, 2); both by the
            # value change across the cell
            steep = steepness_across(value, ctx.obstacles)
            scale = np.maximum(steep.reshape(b, -1).max(axis=1), 1e-12)[:, None, None]
            scores = np.where(ctx.obstacles, 0.999 * steep / scale, scores)
        else:
            # tier 4 (lowest): any path cell; tier 3: other cells next to the path, by the steepest value change to
            # a neighbour, in [1, 2)
            scores[on_path] = 0.0
            steep = steepness(value, ctx.obstacles)
            scale = np.maximum(steep.reshape(b, -1).max(axis=1), 1e-12)[:, None, None]
        scores = np.where(near, 1.0 + 0.999 * steep / scale, scores)
        # moves of the path: move k goes from cell k to cell k + 1 of the same path
        same = np.append(owner[1:] == owner[:-1], False)
        move = np.zeros_like(cells)
        move[:-1] = cells[1:] - cells[:-1]
        # tier 2: the two cells beside each diagonal move (the corners it cuts), in [2, 3)
        diag = same & (move[:, 0] != 0) & (move[:, 1] != 0)
        frac = 1.0 - pos / np.maximum(lengths[owner], 1)
        for corner in (
            np.stack([cells[:, 0] + move[:, 0], cells[:, 1]], 1),
            np.stack([cells[:, 0], cells[:, 1] + move[:, 1]], 1),
        ):
            sel = diag & ~on_path[owner, corner[:, 0].clip(0, n - 1), corner[:, 1].clip(0, n - 1)]
            np.maximum.at(scores, (owner[sel], corner[sel, 0], corner[sel, 1]), 2.0 + 0.999 * frac[sel])
        # tier 1 (highest): the cells where the path turns, earlier turns first, in [3, 4)
        prev_same = np.insert(same[:-1], 0, False)
        prev_move = np.zeros_like(move)
        prev_move[1:] = move[:-1]
        turn = same & prev_same & np.any(move != prev_move, axis=1)
        np.maximum.at(scores, (owner[turn], cells[turn, 0], cells[turn, 1]), 3.0 + 0.999 * frac[turn])
        return scores


class SaliencyAttack(Attack):
    name = "saliency"

    @staticmethod
    def gradient_module(planner: Planner):
        """Its declared gradients' module (`Capabilities.gradients`): of the logits, or of a search's path map; None."""
        if not planner.capabilities.gradients:
            return None
        return planner.logits_module if planner.capabilities.policy else planner.differentiable_paths

    def ranked_as(self, planner: Planner) -> str | None:
        return KeyPointsAttack.name if self.gradient_module(planner) is None else None

    def candidate_scores(self, ctx: AttackContext) -> np.ndarray:
        module = self.gradient_module(ctx.planner)
        if module is None:  # no gradients (the `optimal` control, most search planners): rank as key-points does
            return KeyPointsAttack.candidate_scores(self, ctx)
        if not ctx.planner.capabilities.policy:  # a search planner's module is its path map's
            return path_saliency(ctx, module)
        return policy_saliency(ctx, module)


class ExhaustiveAttack(Attack):
    name = "exhaustive"

    def __init__(self, per_map: int = 1, seed: int = 0, obstacles: int = 1, edit: str = ADD):
        super().__init__(per_map=per_map, budget=None, seed=seed, obstacles=obstacles, edit=edit)

    def params(self) -> dict:
        return self._edited({"per_map": self.per_map, "obstacles": self.obstacles})

    def candidate_scores(self, ctx: AttackContext) -> np.ndarray:
        return np.zeros(ctx.obstacles.shape)  # every valid cell, in row-major order


STRATEGIES: dict[str, type[Attack]] = {
    cls.name: cls for cls in (RandomAttack, NearPathAttack, KeyPointsAttack, SaliencyAttack, ExhaustiveAttack)
}


def make_attack(
    name: str,
    per_map: int = 1,
    seed: int = 0,
    budget: int = 8,
    radius: int = 2,
    obstacles: int = 1,
    edit: str = ADD,
) -> Attack:
    """The strategy `name` with its parameters (those it does not use are ignored); `obstacles`: K, the cells
    edited per pair (greedily, see the module doc); `edit`: `add` obstacles or `remove` them."""
    if name not in STRATEGIES:
        raise InputError(f"unknown attack strategy '{name}'; choose one of {', '.join(STRATEGIES)}")
    if name == "near-path":
        return NearPathAttack(per_map=per_map, radius=radius, seed=seed, obstacles=obstacles, edit=edit)
    if name in ("key-points", "saliency"):
        return STRATEGIES[name](per_map=per_map, budget=budget, seed=seed, obstacles=obstacles, edit=edit)
    return STRATEGIES[name](per_map=per_map, seed=seed, obstacles=obstacles, edit=edit)
