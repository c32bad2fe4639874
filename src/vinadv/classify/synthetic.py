"""Synthetic path pairs for tests and benchmarks, until real attack pairs are at hand.

Each pair: an optimal (expert) path on a generated map, and the optimal path after one obstacle is added on
a random interior cell of it (an attack that always touches the path, so DP and FP pairs dominate). With
`mix=True`, some pairs are turned into the other categories: an obstacle off the path (usually UcP), a cut
adversarial path (UrP), a cut original path (invalid). These are expert paths, not VIN paths: the figures
they give are for code paths and speed, not for the paper's accuracy.
"""

from __future__ import annotations

import numpy as np

from vinadv.classify.batch import PathPairBatch, take_segments
from vinadv.grid.generator import generate_maps
from vinadv.grid.shortest_paths import expert_paths


def synthetic_pairs(n: int, size: int = 28, seed: int = 0, mix: bool = False) -> PathPairBatch:
    """`n` synthetic path pairs on `size x size` maps (deterministic for `seed`)."""
    rng = np.random.default_rng(seed)
    want = n
    batches_o, batches_a, goals_all = [], [], []
    have = 0
    round_ = 0
    while have < want:
        m = max(16, int((want - have) * 1.3))
        maps = generate_maps(m, size, seed=seed * 1000 + round_, n_starts=1)
        round_ += 1
        lengths = np.diff(maps.expert_offsets)
        keep = lengths >= 3
        idx = np.flatnonzero(keep)
        # a random interior cell of each expert path (not the start, not the goal)
        pos = maps.expert_offsets[idx] + 1 + (rng.random(len(idx)) * (lengths[idx] - 2)).astype(np.int64)
        blocked = maps.expert_cells[pos].astype(np.int64)
        obstacles = maps.obstacles[idx].copy()
        obstacles[np.arange(len(idx)), blocked[:, 0], blocked[:, 1]] = True
        costs, a_cells, a_offsets = expert_paths(obstacles, maps.goals[idx], maps.starts[idx], maps.corner_cutting)
        ok = np.isfinite(costs[:, 0])
        chosen = idx[ok][: want - have]
        o = take_segments(maps.expert_cells, maps.expert_offsets, chosen)
        a = take_segments(a_cells, a_offsets, np.flatnonzero(ok)[: len(chosen)])
        batches_o.append(o)
        batches_a.append(a)
        goals_all.append(maps.goals[chosen])
        have += len(chosen)
    from vinadv.classify.batch import concat_batches

    batch = concat_batches(
        [PathPairBatch(o[0], o[1], a[0], a[1], g, size) for o, a, g in zip(batches_o, batches_a, goals_all)]
    )
    if mix:
        batch = _mix_categories(batch, rng)
    return batch


def _mix_categories(batch: PathPairBatch, rng: np.random.Generator) -> PathPairBatch:
    """Roughly the paper's mix: 1/3 UrP (cut adversarial path), 2/5 UcP (copy of the original), a few invalid."""
    n = len(batch)
    kind = rng.choice(4, size=n, p=[0.27, 0.33, 0.38, 0.02])  # 0 keep, 1 UrP, 2 UcP, 3 invalid
    o_len = np.diff(batch.o_offsets)
    a_len = np.diff(batch.a_offsets)
    new_o = o_len.copy()
    new_a = a_len.copy()
    new_a[kind == 1] = np.maximum(a_len[kind == 1] - 1, 1)
    new_o[kind == 3] = np.maximum(o_len[kind == 3] - 1, 1)

    def cut(cells, offsets, lengths):
        new_offsets = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(lengths, out=new_offsets[1:])
        gather = np.repeat(offsets[:-1] - new_offsets[:-1], lengths) + np.arange(new_offsets[-1])
        return cells[gather], new_offsets

    o_cells, o_offsets = cut(batch.o_cells, batch.o_offsets, new_o)
    a_cells, a_offsets = cut(batch.a_cells, batch.a_offsets, new_a)
    # UcP: the adversarial path is the original path
    copy = kind == 2
    lengths = np.where(copy, new_o, new_a)
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(lengths, out=offsets[1:])
    source_is_o = np.repeat(copy, lengths)
    src_start = np.where(copy, o_offsets[:-1], a_offsets[:-1])
    gather = np.repeat(src_start - offsets[:-1], lengths) + np.arange(offsets[-1])
    cells = np.where(source_is_o[:, None], o_cells[np.minimum(gather, len(o_cells) - 1)],
                     a_cells[np.minimum(gather, len(a_cells) - 1)])
    return PathPairBatch(o_cells, o_offsets, cells.astype(np.int16), offsets, batch.goals, batch.size)
