"""Synthetic path pairs for tests and benchmarks, until real attack pairs are at hand.

Each pair: an optimal (expert) path on a generated map, and the optimal path after one obstacle is added on
a random interior cell of it (an attack that always touches the path, so DP and FP pairs dominate). With
`mix=True`, some pairs are turned into the other categories: an obstacle off the path (usually UcP), a cut
adversarial path (UrP), a cut original path (invalid). These are expert paths, not VIN paths: the figures
they give are for code paths and speed, not for the paper's accuracy.
"""

from __future__ import annotations

import numpy as np

from vinadv.classify.batch import PathPairBatch
from vinadv.grid.generator import generate_maps
from vinadv.grid.paths import PackedPaths
from vinadv.grid.shortest_paths import expert_paths


def synthetic_pairs(n: int, size: int = 28, seed: int = 0, mix: bool = False) -> PathPairBatch:
    """`n` synthetic path pairs on `size x size` maps (deterministic for `seed`)."""
    rng = np.random.default_rng(seed)
    want = n
    batches = []
    have = 0
    round_ = 0
    while have < want:
        m = max(16, int((want - have) * 1.3))
        maps = generate_maps(m, size, seed=seed * 1000 + round_, n_starts=1)
        round_ += 1
        lengths = maps.expert.lengths
        keep = lengths >= 3
        idx = np.flatnonzero(keep)
        # a random interior cell of each expert path (not the start, not the goal)
        pos = maps.expert.offsets[idx] + 1 + (rng.random(len(idx)) * (lengths[idx] - 2)).astype(np.int64)
        blocked = maps.expert.cells[pos].astype(np.int64)
        obstacles = maps.obstacles[idx].copy()
        obstacles[np.arange(len(idx)), blocked[:, 0], blocked[:, 1]] = True
        costs, detours = expert_paths(obstacles, maps.goals[idx], maps.starts[idx], maps.corner_cutting, maps.moves)
        ok = np.isfinite(costs[:, 0])
        chosen = idx[ok][: want - have]
        detours = detours.take(np.flatnonzero(ok)[: len(chosen)])
        batches.append(
            PathPairBatch(path_o=maps.expert.take(chosen), path_a=detours, goals=maps.goals[chosen], size=size)
        )
        have += len(chosen)
    batch = PathPairBatch.concat(batches, size=size)
    if mix:
        batch = _mix_categories(batch, rng)
    return batch


def _mix_categories(batch: PathPairBatch, rng: np.random.Generator) -> PathPairBatch:
    """Roughly the paper's mix: 1/3 UrP (cut adversarial path), 2/5 UcP (copy of the original), a few invalid."""
    n = len(batch)
    kind = rng.choice(4, size=n, p=[0.27, 0.33, 0.38, 0.02])  # 0 keep, 1 UrP, 2 UcP, 3 invalid
    o_len, a_len = batch.path_o.lengths, batch.path_a.lengths
    new_o = o_len.copy()
    new_a = a_len.copy()
    new_a[kind == 1] = np.maximum(a_len[kind == 1] - 1, 1)
    new_o[kind == 3] = np.maximum(o_len[kind == 3] - 1, 1)
    path_o, path_a = batch.path_o.prefixes(new_o), batch.path_a.prefixes(new_a)
    # UcP: the adversarial path is (the possibly cut) original path
    both = PackedPaths.concat([path_o, path_a])
    path_a = both.take(np.where(kind == 2, np.arange(n), n + np.arange(n)))
    return PathPairBatch(path_o=path_o, path_a=path_a, goals=batch.goals, size=batch.size)
