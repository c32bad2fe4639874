"""Every pair of addable cells: the exact two-obstacle search (DESIGN.md "Several obstacles"), a diagnostic beside the
greedy attacks of `vinadv.attacks.strategies`, which choose the second cell only after fixing the first.

`exact_pairs` plans, for each searched map, the adversarial map of every unordered pair of distinct valid cells
(`validity.valid_cells`) with which the goal stays reachable (`validity.solvable` on the map with both added: a pair of
valid cells is a valid two-cell addition exactly then, `validity.valid_additions`), and judges each pair with a
caller's `judge` (the harm verdict lives downstream, in `vinadv.identify`; `vinadv.exact_k2` passes it). Two modes:

- `stop_at_harmful=True`: a map stops at its first harmful pair in the search order below (the harmful rate needs
  only whether one exists); a map with none plans every pair, so "no harmful pair" is exact.
- `stop_at_harmful=False`: every pair of every searched map, keeping the strongest by `judge`'s strength (the
  largest regret, say), the first in the search order on ties, and counting the harmful pairs.

Search order (it decides the witness of the first mode, never what is found): the valid cells sorted by Chebyshev
distance to the planner's path on the original map (its own cells first), ties in row-major order; pairs in colex
order over those cells, `(i, j)` with `i < j` at position `j * (j - 1) / 2 + i`, so all pairs of the nearest `r`
cells come before any pair with a farther one. Cells beside the path are where one obstacle usually harms, so a
harmed map tends to stop early.

Batching: each round plans at most `chunk` adversarial maps in one planner call, pairs of every live map at once
(an equal share each, the next pairs in its order), so a round with few live maps still fills the batch; nothing
loops over pairs in Python. The cost is that of planning: a 28x28 map has about 570 valid cells and 165,000 pairs
(`docs/guide/robustness.md` gives the VIN's measured cost).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from vinadv.attacks.neighbourhood import chebyshev_distance
from vinadv.attacks.pairs import PairSet
from vinadv.attacks.validity import solvable, valid_cells
from vinadv.errors import InputError
from vinadv.planners.interface import Planner
from vinadv.planners.vin.planner import as_planner
from vinadv.vocabulary import ADD

#: adversarial maps planned per round (as the strategies' `EVAL_CHUNK`: bounds memory)
PAIR_CHUNK = 8192
#: the strategy name of the pairs it keeps
EXACT_PAIRS = "exact-pairs"

#: `judge(pairs) -> (harmful (n,) bool, strength (n,) float)`: the harm verdict and the order of "worse" (larger is
#: worse; `vinadv.identify.harm_strength`'s: UrP inf, else the adversarial regret)
Judge = Callable[[PairSet], tuple[np.ndarray, np.ndarray]]


@dataclass
class ExactPairsResult:
    """What `exact_pairs` found, per map of the batch (`(B,)` arrays, map order).

    Attributes:
        pairs: one pair per map that has one to show, in map order (`pairs.map_index`): the first harmful pair
            (stopping mode) or the strongest pair (all-pairs mode); `pairs.added` is `(n, 2, 2)`.
        searched: the maps searched (asked for, with at least two valid cells).
        candidate_pairs: pairs of valid cells, `n * (n - 1) / 2` for n valid cells (0 for a map not searched).
        tried: candidate pairs taken in search order (all, unless the map stopped at a harmful pair).
        planned: valid pairs among those tried (the goal reachable with both cells added): one planner call each.
        harmful: some planned pair is harmful. harmful_pairs: how many (all-pairs mode: the map's count; stopping mode:
            1 where harmful).
        complete: every candidate pair was tried, so `harmful` False is exact.
        planner_calls: planner calls, the original maps' included.
    """

    pairs: PairSet
    searched: np.ndarray
    candidate_pairs: np.ndarray
    tried: np.ndarray
    planned: np.ndarray
    harmful: np.ndarray
    harmful_pairs: np.ndarray
    complete: np.ndarray
    planner_calls: int


def pair_at(position: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The colex pairs `(i, j)`, `i < j`, at `position` (int64 array): position `j * (j - 1) / 2 + i`."""
    position = np.asarray(position, dtype=np.int64)
    j = ((1 + np.sqrt(1 + 8 * position.astype(np.float64))) // 2).astype(np.int64)
    # float rounding near a triangular number: step j to the one whose block holds the position
    j -= j * (j - 1) // 2 > position
    j += (j + 1) * j // 2 <= position
    return position - j * (j - 1) // 2, j


def ordered_cells(valid: np.ndarray, path_mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each map's valid cells in search order (see the module doc): `(cells (M, 2) int64, offsets (B + 1,))`, map b's
    cells at `cells[offsets[b]:offsets[b + 1]]`. valid, path_mask: `(B, N, N)` bool."""
    b, n, m = valid.shape
    distance = chebyshev_distance(path_mask)
    owner, flat = np.nonzero(valid.reshape(b, -1))  # map order, then row-major
    order = np.lexsort((flat, distance.reshape(b, -1)[owner, flat], owner))
    owner, flat = owner[order], flat[order]
    offsets = np.searchsorted(owner, np.arange(b + 1))
    return np.stack(np.divmod(flat, m), axis=1).astype(np.int64), offsets


def exact_pairs(
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    planner: Planner,
    judge: Judge,
    *,
    search: np.ndarray | None = None,
    stop_at_harmful: bool = True,
    corner_cutting: bool = True,
    frozen: np.ndarray | None = None,
    chunk: int = PAIR_CHUNK,
    progress: bool = False,
) -> ExactPairsResult:
    """Search every pair of addable cells of the maps `search` selects (see the module doc).

    Args:
        obstacles: `(B, N, N)` bool; starts, goals: `(B, 2)`.
        planner: a `Planner` (or a VIN) for the maps' size; its movement model is the maps'.
        judge: `(harmful, strength)` of a `PairSet` of pairs against the original maps (see `Judge`); its pairs'
            `map_index` are indices into this batch.
        search: `(B,)` bool, the maps to search (default all).
        stop_at_harmful: stop a map at its first harmful pair (else plan all pairs and keep the strongest).
        corner_cutting: the maps' move rule. frozen: `(B, N, N)` bool, cells no attack may edit, or None.
        chunk: adversarial maps per planner call, >= 1.
        progress: a progress bar over the candidate pairs (a stopped map's untried pairs count as done).
    """
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    starts = np.ascontiguousarray(starts, dtype=np.int64)
    goals = np.ascontiguousarray(goals, dtype=np.int64)
    b, size = len(obstacles), obstacles.shape[1]
    if chunk < 1:
        raise InputError(f"chunk must be >= 1, got {chunk}", "chunk")
    planner = as_planner(planner, size)
    search = np.ones(b, dtype=bool) if search is None else np.asarray(search, dtype=bool)
    base = planner.plan(obstacles, starts, goals, corner_cutting)
    path_mask = np.zeros_like(obstacles)
    on_path = base.paths.cells.astype(np.int64)
    path_mask[base.paths.owners(), on_path[:, 0], on_path[:, 1]] = True
    valid = valid_cells(obstacles, starts, goals, corner_cutting, planner.moves, frozen) & search[:, None, None]
    cells, offsets = ordered_cells(valid, path_mask)
    counts = np.diff(offsets)
    candidate = counts * (counts - 1) // 2
    state = _State(b, candidate)
    bar = _bar(progress, int(candidate.sum()), stop_at_harmful)
    calls = b
    while (live := np.flatnonzero(state.cursor < candidate)).size:
        share = np.minimum(candidate[live] - state.cursor[live], max(1, chunk // len(live)))
        map_idx = np.repeat(live, share)
        position = np.arange(len(map_idx)) - np.repeat(np.cumsum(share) - share, share) + state.cursor[map_idx]
        state.cursor[live] += share
        i, j = pair_at(position)
        added = np.stack([cells[offsets[map_idx] + i], cells[offsets[map_idx] + j]], axis=1)
        obstacles_a = obstacles[map_idx]
        rows = np.arange(len(map_idx))[:, None]
        obstacles_a[rows, added[..., 0], added[..., 1]] = True
        ok = solvable(obstacles_a, starts[map_idx], goals[map_idx], corner_cutting, planner.moves)
        map_idx, added, obstacles_a = map_idx[ok], added[ok], obstacles_a[ok]
        if not len(map_idx):  # no pair of this round keeps the goal reachable
            if bar is not None:
                bar.update(int(share.sum()))
            continue
        planned = planner.plan(obstacles_a, starts[map_idx], goals[map_idx], corner_cutting)
        calls += len(map_idx)
        pairs = PairSet(
            obstacles_o=obstacles[map_idx],
            obstacles_a=obstacles_a,
            starts=starts[map_idx],
            goals=goals[map_idx],
            added=added,
            map_index=map_idx,
            path_o=base.paths.take(map_idx),
            path_a=planned.paths,
            term_o=base.termination_names[map_idx],
            term_a=planned.termination_names,
            edit=ADD,
            corner_cutting=corner_cutting,
            moves=planner.moves,
        )
        harmful, strength = judge(pairs)
        state.record(pairs, np.asarray(harmful, dtype=bool), np.asarray(strength, dtype=np.float64), stop_at_harmful)
        if bar is not None:
            bar.update(int(share.sum()) + state.skipped_now)
    if bar is not None:
        bar.close()
    kept = [state.best[m] for m in sorted(state.best)]
    result = PairSet.concat(
        kept,
        size=size,
        strategy=EXACT_PAIRS,
        params={"stop_at_harmful": bool(stop_at_harmful), "planner": planner.spec()},
        corner_cutting=corner_cutting,
        moves=planner.moves,
    )
    return ExactPairsResult(
        pairs=result,
        searched=candidate > 0,
        candidate_pairs=candidate,
        tried=np.minimum(state.cursor, candidate) - state.skipped,
        planned=state.planned,
        harmful=state.harmful_pairs > 0,
        harmful_pairs=state.harmful_pairs,
        complete=state.skipped == 0,
        planner_calls=calls,
    )


class _State:
    """Per map: the next position to take, the pairs planned and harmful, the pair kept, and (stopping mode) the
    untried pairs skipped when it stopped."""

    def __init__(self, b: int, candidate: np.ndarray):
        self.candidate = candidate
        self.cursor = np.zeros(b, np.int64)
        self.planned = np.zeros(b, np.int64)
        self.harmful_pairs = np.zeros(b, np.int64)
        self.skipped = np.zeros(b, np.int64)
        self.best: dict[int, PairSet] = {}
        self.best_strength: dict[int, float] = {}
        self.skipped_now = 0

    def record(self, pairs: PairSet, harmful: np.ndarray, strength: np.ndarray, stop_at_harmful: bool) -> None:
        b = len(self.cursor)
        map_idx = pairs.map_index
        self.planned += np.bincount(map_idx, minlength=b)
        self.skipped_now = 0
        if stop_at_harmful:
            # a round's pairs of one map are in search order: its first harmful one is its first in the round
            hit_maps, first = np.unique(map_idx[harmful], return_index=True)
            rows = np.flatnonzero(harmful)[first]
            self.harmful_pairs[hit_maps] = 1
            for m, row in zip(hit_maps.tolist(), rows.tolist()):
                self.best[m] = pairs.take([row])
            self.skipped[hit_maps] = self.candidate[hit_maps] - self.cursor[hit_maps]
            self.skipped_now = int(self.skipped[hit_maps].sum())
            self.cursor[hit_maps] = self.candidate[hit_maps]  # stopped
            return
        self.harmful_pairs += np.bincount(map_idx[harmful], minlength=b)
        # per map, the strongest of the round, the first on ties (lexsort: the last key is the primary one)
        order = np.lexsort((np.arange(len(map_idx)), -strength, map_idx))
        heads = order[np.r_[True, map_idx[order][1:] != map_idx[order][:-1]]] if len(order) else order
        for row in heads.tolist():
            m = int(map_idx[row])
            if m not in self.best or strength[row] > self.best_strength[m]:
                self.best[m] = pairs.take([row])
                self.best_strength[m] = float(strength[row])


def _bar(progress: bool, total: int, stop_at_harmful: bool):
    if not progress:
        return None
    from tqdm import tqdm  # noqa: PLC0415 (tqdm: a search without a bar does not load it)

    return tqdm(total=total, unit="pair", desc="exact pairs" + (", to the first harmful" if stop_at_harmful else ""))
