"""Random `PairRecords` for tests and benchmarks of the store (no planner needed; the rows need not be
consistent with each other, only well-formed)."""

from __future__ import annotations

import numpy as np

from vinadv.grid.paths import PackedPaths
from vinadv.store.records import PairRecords
from vinadv.store.schema import HARM_FLOAT_COLUMNS
from vinadv.vocabulary import ADD, HARMS, LABELS, REMOVE, TERMINATIONS, is_success


def random_records(
    n: int,
    size: int = 28,
    seed: int = 0,
    max_path: int = 80,
    first_index: int = 0,
    n_added: int = 1,
    removes: float = 0.0,
    effort: bool = False,
) -> PairRecords:
    """n random pairs on `size` x `size` maps, `n_added` added cells each; paths of 0..max_path random cells; some
    NULL scores and dh/dv. `removes`: the share of pairs (drawn last, so the rest is as without it) of edit `remove`,
    whose cells are freed instead of added. `effort`: the search-effort fields too (drawn last, likewise): 0..20
    expanded cells per map (0: none reported, NULL) and A*'s counts (some NULL, -1)."""
    rng = np.random.default_rng(seed)
    obstacles_o = rng.random((n, size, size)) < 0.3
    obstacles_a = obstacles_o.copy()
    added = rng.integers(0, size, (n, n_added, 2))
    obstacles_a[np.arange(n)[:, None], added[..., 0], added[..., 1]] = True

    def paths() -> PackedPaths:
        lengths = rng.integers(0, max_path + 1, n)
        offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
        return PackedPaths(rng.integers(0, size, (offsets[-1], 2)), offsets)

    path_o, path_a = paths(), paths()
    label = np.array(LABELS, dtype=object)[rng.integers(0, len(LABELS), n)]
    score = rng.random(n)
    score[rng.random(n) < 0.3] = np.nan
    dh = rng.integers(-1, size, n)
    dv = rng.integers(-1, size, n)
    # harm: costs with NULLs (NaN), labels with NULLs (None), like rows stored without harm
    costs = {name: np.where(rng.random(n) < 0.2, np.nan, rng.random(n) * 4 * size) for name in HARM_FLOAT_COLUMNS}
    expert_label = np.array([None, *LABELS], dtype=object)[rng.integers(0, len(LABELS) + 1, n)]
    harm = np.array([None, *HARMS], dtype=object)[rng.integers(0, len(HARMS) + 1, n)]
    edit = np.full(n, ADD, dtype="<U6")
    if removes:
        edit[rng.random(n) < removes] = REMOVE
        freed = obstacles_o.copy()
        freed[np.arange(n)[:, None], added[..., 0], added[..., 1]] = False
        obstacles_a = np.where((edit == REMOVE)[:, None, None], freed, obstacles_a)
    searched = {}
    if effort:
        for side in ("o", "a"):
            lengths = rng.integers(0, 21, n)
            offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
            searched[f"expanded_{side}"] = PackedPaths(rng.integers(0, size, (offsets[-1], 2)), offsets)
        for side in ("o", "a"):
            searched[f"astar_expansions_{side}"] = np.where(rng.random(n) < 0.2, -1, rng.integers(1, size * size, n))
    return PairRecords(
        pair_index=first_index + np.arange(n),
        obstacles_o=obstacles_o,
        obstacles_a=obstacles_a,
        starts=rng.integers(0, size, (n, 2)),
        goals=rng.integers(0, size, (n, 2)),
        added=added,
        path_o=path_o,
        path_a=path_a,
        label=label,
        attack=is_success(label),
        term_o=np.array(TERMINATIONS, dtype=object)[rng.integers(0, 4, n)],
        term_a=np.array(TERMINATIONS, dtype=object)[rng.integers(0, 4, n)],
        label_source=np.array(["rule", "svm"], dtype=object)[rng.integers(0, 2, n)],
        score=score,
        dh=dh,
        dv=dv,
        **costs,
        expert_label=expert_label,
        harm=harm,
        edit=edit,
        **searched,
    )
