"""Independent oracles and random path pairs for the classify tests (written straight from DESIGN.md)."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from vinadv.classify.batch import PathPairBatch

MOVES = [(-1, 0), (1, 0), (0, 1), (0, -1), (-1, 1), (-1, -1), (1, 1), (1, -1)]


def rule_oracle(original, adversarial, goal, t):
    """The DESIGN.md label of one pair, by brute force over all cell pairs: (label, dh, dv)."""
    o = [tuple(map(int, c)) for c in original]
    a = [tuple(map(int, c)) for c in adversarial]
    d_o = set(o) - set(a)
    d_a = set(a) - set(o)
    dh = max([abs(ci - cj) for (ri, ci) in d_o for (rj, cj) in d_a if ri == rj], default=0)
    dv = max([abs(ri - rj) for (ri, ci) in d_o for (rj, cj) in d_a if ci == cj], default=0)
    goal = tuple(map(int, goal))
    if not o or o[-1] != goal:
        label = "invalid"
    elif not a or a[-1] != goal:
        label = "UrP"
    elif o == a:
        label = "UcP"
    elif dh <= t and dv <= t:
        label = "DP"
    else:
        label = "FP"
    return label, dh, dv


def walk(start, moves, size):
    """An 8-connected path from `start` following `moves` (ids 0-7), skipping moves that leave the grid."""
    path = [tuple(start)]
    for m in moves:
        r, c = path[-1][0] + MOVES[m][0], path[-1][1] + MOVES[m][1]
        if 0 <= r < size and 0 <= c < size:
            path.append((r, c))
    return path


@st.composite
def path_pairs(draw, max_size: int = 14, max_pairs: int = 6):
    """A PathPairBatch of random 8-connected path pairs: random walks sharing a prefix and often a suffix,
    goals chosen so that every category appears."""
    size = draw(st.integers(3, max_size))
    n = draw(st.integers(1, max_pairs))
    originals, adversarials, goals = [], [], []
    cell = st.tuples(st.integers(0, size - 1), st.integers(0, size - 1))
    moves = st.lists(st.integers(0, 7), max_size=3 * size)
    for _ in range(n):
        start = draw(cell)
        o = walk(start, draw(moves), size)
        shape = draw(st.sampled_from(["fork", "detour", "same", "independent"]))
        if shape == "same":
            a = list(o)
        elif shape == "independent":
            a = walk(start, draw(moves), size)
        else:
            cut = draw(st.integers(0, len(o) - 1))
            a = walk(o[cut], draw(moves), size)
            a = o[:cut] + a
            if shape == "detour":
                rejoin = draw(st.integers(0, len(o) - 1))
                a = a + o[rejoin:]
        goal_kind = draw(st.sampled_from(["o", "o", "o", "a", "other"]))
        goal = o[-1] if goal_kind == "o" else a[-1] if goal_kind == "a" else draw(cell)
        originals.append(np.array(o))
        adversarials.append(np.array(a))
        goals.append(goal)
    return PathPairBatch.from_paths(originals, adversarials, goals, size)


def pairs_as_lists(batch: PathPairBatch):
    """The pairs of a batch as Python lists of (original cells, adversarial cells, goal)."""
    out = []
    for i in range(len(batch)):
        o = batch.path_o[i].tolist()
        a = batch.path_a[i].tolist()
        out.append((o, a, batch.goals[i].tolist()))
    return out
