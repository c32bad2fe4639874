"""Brute-force oracles written straight from DESIGN.md, independent of vinadv's code.

Movement models (`moves`): "octile" (8 moves, diagonal sqrt 2), "moore" (8 moves, all cost 1), "news" (the first 4
moves N, S, E, W, cost 1).
"""

import math

DELTAS = [(-1, 0), (1, 0), (0, 1), (0, -1), (-1, 1), (-1, -1), (1, 1), (1, -1)]
MOVES = ("octile", "moore", "news")


def step_cost(a, moves="octile"):
    """What action `a` costs under `moves`."""
    dr, dc = DELTAS[a]
    return math.sqrt(2) if dr and dc and moves == "octile" else 1.0


def legal(obstacles, r, c, a, corner_cutting=True, moves="octile"):
    if moves == "news" and a >= 4:
        return False
    n, m = len(obstacles), len(obstacles[0])
    dr, dc = DELTAS[a]
    nr, nc = r + dr, c + dc
    if not (0 <= nr < n and 0 <= nc < m) or obstacles[nr][nc]:
        return False
    if not corner_cutting and dr and dc and (obstacles[r + dr][c] or obstacles[r][c + dc]):
        return False
    return True


def brute_distances(obstacles, goal, corner_cutting=True, moves="octile"):
    """Bellman-Ford over (cost, moves) pairs until nothing changes: slow and obviously right."""
    n, m = len(obstacles), len(obstacles[0])
    inf = (math.inf, -1)
    best = {(r, c): inf for r in range(n) for c in range(m)}
    if not obstacles[goal[0]][goal[1]]:
        best[tuple(goal)] = (0.0, 0)
    changed = True
    while changed:
        changed = False
        for r in range(n):
            for c in range(m):
                if obstacles[r][c]:
                    continue
                for a, (dr, dc) in enumerate(DELTAS):
                    if not legal(obstacles, r, c, a, corner_cutting, moves):
                        continue
                    cost, count = best[(r + dr, c + dc)]
                    step = step_cost(a, moves)
                    if cost + step < best[(r, c)][0] - 1e-9:
                        best[(r, c)] = (cost + step, count + 1)
                        changed = True
    return best


def optimal_action_mask(obstacles, goal, corner_cutting=True, moves="octile"):
    """`[r][c][a]`: whether action `a` is optimal at cell (r, c) (False at obstacles, the goal and cells that cannot
    reach it): a legal move to a cell whose brute-force cost plus the move's cost is the cell's own."""
    n, m = len(obstacles), len(obstacles[0])
    best = brute_distances(obstacles, goal, corner_cutting, moves)
    mask = [[[False] * len(DELTAS) for _ in range(m)] for _ in range(n)]
    for r in range(n):
        for c in range(m):
            cost = best[(r, c)][0]
            if obstacles[r][c] or (r, c) == tuple(goal) or not math.isfinite(cost):
                continue
            for a, (dr, dc) in enumerate(DELTAS):
                if legal(obstacles, r, c, a, corner_cutting, moves):
                    mask[r][c][a] = abs(best[(r + dr, c + dc)][0] + step_cost(a, moves) - cost) < 1e-9
    return mask


def reachable(obstacles, start, goal, corner_cutting=True, moves="octile") -> bool:
    """Whether `start` reaches `goal` on `obstacles` (rows of bools: nested lists or a 2-D array): a flood fill from
    `start` over the legal moves (the attack oracles call it for every cell of a map; costs are not needed)."""
    rows = [[bool(cell) for cell in row] for row in obstacles]
    start, goal = (int(start[0]), int(start[1])), (int(goal[0]), int(goal[1]))
    if rows[start[0]][start[1]] or rows[goal[0]][goal[1]]:
        return False
    seen, todo = {start}, [start]
    while todo:
        r, c = todo.pop()
        if (r, c) == goal:
            return True
        for a, (dr, dc) in enumerate(DELTAS):
            if (r + dr, c + dc) not in seen and legal(rows, r, c, a, corner_cutting, moves):
                seen.add((r + dr, c + dc))
                todo.append((r + dr, c + dc))
    return False
