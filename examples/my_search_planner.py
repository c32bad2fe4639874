"""A bring-your-own search planner for vinadv: `vinadv plan --maps maps.npz --out paths.npz
--planner examples/my_search_planner.py:make`.

`make(size)` returns an object with `plan_paths(obstacles, starts, goals, corner_cutting)`: obstacles (B, N, N) bool,
starts and goals (B, 2) int64 (row, col), one search per row. It returns a `SearchResult` (or just a list of B (L, 2)
paths): each path starts at its start and moves one legal move at a time; a path that does not end at the goal (the
start alone, say) means "no path found". vinadv checks every answer and refuses a bad one in one line;
`vinadv.planners.check_planner(make(28), 28)` runs every check on a few generated maps (in your own tests, say).

This one is breadth-first search, in NumPy, all B searches at once, level by level: it finds a path with the fewest
moves and reports the cells it expanded. It plans vinadv's `octile` maps, where a diagonal move costs sqrt 2, so its
paths are sometimes longer than the cheapest (on `moore` maps, where every move costs 1, they would be optimal):
something for the attacks to find.
"""

import numpy as np

from vinadv.planners.search import SearchResult

# vinadv's action order: N, S, E, W, NE, NW, SE, SW as (d_row, d_col)
DELTAS = [(-1, 0), (1, 0), (0, 1), (0, -1), (-1, 1), (-1, -1), (1, 1), (1, -1)]


def shifted(x: np.ndarray, dr: int, dc: int) -> np.ndarray:
    """out[:, r, c] = x[:, r - dr, c - dc], False off the grid: what reaches (r, c) by the move (dr, dc)."""
    n = x.shape[1]
    out = np.zeros_like(x)
    out[:, max(dr, 0) : n + min(dr, 0), max(dc, 0) : n + min(dc, 0)] = x[
        :, max(-dr, 0) : n + min(-dr, 0), max(-dc, 0) : n + min(-dc, 0)
    ]
    return out


class BreadthFirst:
    moves = "octile"  # the movement model it plans (the default; "moore" and "news" are the others)
    capabilities = {"expansions": True}  # what it offers beyond paths: its answers carry the expanded cells

    def plan_paths(self, obstacles, starts, goals, corner_cutting=True):
        b, n, _ = obstacles.shape
        rows = np.arange(b)
        free = ~obstacles
        # enter[d][:, r, c]: the move DELTAS[d] into (r, c) is legal (the cell is free; without corner cutting a
        # diagonal move also needs both cells beside it free)
        enter = []
        for dr, dc in DELTAS:
            ok = free.copy()
            if dr and dc and not corner_cutting:
                ok &= shifted(free, 0, dc) & shifted(free, dr, 0)
            enter.append(ok)
        depth = np.full((b, n, n), -1)
        depth[rows, starts[:, 0], starts[:, 1]] = 0
        frontier = depth == 0
        level = 0
        searching = np.ones(b, dtype=bool)
        while frontier.any():
            level += 1
            reach = np.zeros_like(frontier)
            for d, (dr, dc) in enumerate(DELTAS):
                reach |= shifted(frontier, dr, dc) & enter[d]
            frontier = reach & (depth < 0) & searching[:, None, None]
            depth[frontier] = level
            searching &= depth[rows, goals[:, 0], goals[:, 1]] < 0  # a search stops once its goal is reached
        goal_depth = depth[rows, goals[:, 0], goals[:, 1]]
        found = goal_depth >= 0
        # expanded: every cell taken off the queue before the goal's level (all reached cells where it failed)
        last = np.where(found, goal_depth - 1, n * n)
        expanded = (depth >= 0) & (depth <= last[:, None, None])
        # walk back from the goal: a neighbour one level closer, the first in action order
        cells = np.zeros((b, int(goal_depth.max(initial=0)) + 1, 2), dtype=np.int64)
        cur = goals.copy()
        cells[rows, np.maximum(goal_depth, 0)] = cur
        for k in range(int(goal_depth.max(initial=0)), 0, -1):
            walking = found & (goal_depth >= k)
            chosen = np.zeros(b, dtype=bool)
            nxt = cur.copy()
            for d, (dr, dc) in enumerate(DELTAS):
                pr, pc = cur[:, 0] - dr, cur[:, 1] - dc
                inside = (pr >= 0) & (pr < n) & (pc >= 0) & (pc < n)
                prev_depth = depth[rows, pr.clip(0, n - 1), pc.clip(0, n - 1)]
                ok = walking & ~chosen & inside & (prev_depth == k - 1) & enter[d][rows, cur[:, 0], cur[:, 1]]
                nxt[ok] = np.stack([pr[ok], pc[ok]], axis=1)
                chosen |= ok
            cur = np.where(walking[:, None], nxt, cur)
            cells[walking, k - 1] = cur[walking]
        paths = [cells[i, : goal_depth[i] + 1] if found[i] else starts[i : i + 1] for i in range(b)]
        return SearchResult.from_paths(paths, goals, expanded=expanded)


def make(size: int) -> BreadthFirst:
    return BreadthFirst()
