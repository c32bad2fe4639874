"""The neighbourhoods the ranking strategies read (`vinadv.attacks.strategies`): the cells near a path (Chebyshev
distance) and the value change to, or across, a cell's free 8-neighbours."""

from __future__ import annotations

import numpy as np


def within_distance(mask: np.ndarray, radius: int) -> np.ndarray:
    """Cells within `radius` king moves (Chebyshev distance) of a True cell of the same map: `(B, N, N)` bool for
    `mask (B, N, N)` bool. A square's dilation is one along the rows, then one along the columns (SciPy's
    `maximum_filter` gives the same but takes longer to import than a whole `vinadv run` spends here)."""
    out = mask.copy()
    for axis in (1, 2):
        grown = out.copy()
        for shift in range(1, radius + 1):
            lead = [slice(None)] * 3
            lag = [slice(None)] * 3
            lead[axis], lag[axis] = slice(shift, None), slice(None, -shift)
            grown[tuple(lead)] |= out[tuple(lag)]
            grown[tuple(lag)] |= out[tuple(lead)]
        out = grown
    return out


def steepness(value: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
    """Largest |value change| from each cell to a free 8-neighbour, `(B, N, N)`."""
    b, n, m = value.shape
    v = np.where(obstacles, np.nan, value.astype(np.float64))
    padded = np.full((b, n + 2, m + 2), np.nan)
    padded[:, 1:-1, 1:-1] = v
    steep = np.zeros((b, n, m))
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr or dc:
                diff = np.abs(padded[:, 1 + dr : 1 + dr + n, 1 + dc : 1 + dc + m] - v)
                steep = np.fmax(steep, diff)
    return np.nan_to_num(steep)


def steepness_across(value: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
    """Largest |value difference| between two free 8-neighbours of each cell, `(B, N, N)` (0 with fewer than two):
    what a path through the cell, were it free, would skip."""
    b, n, m = value.shape
    padded = np.full((b, n + 2, m + 2), np.nan)
    padded[:, 1:-1, 1:-1] = np.where(obstacles, np.nan, value.astype(np.float64))
    hi = np.full((b, n, m), -np.inf)
    lo = np.full((b, n, m), np.inf)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr or dc:
                v = padded[:, 1 + dr : 1 + dr + n, 1 + dc : 1 + dc + m]
                hi = np.fmax(hi, v)
                lo = np.fmin(lo, v)
    return np.where(hi > lo, hi - lo, 0.0)


def chebyshev_distance(mask: np.ndarray) -> np.ndarray:
    """King moves (Chebyshev distance) from each cell to the nearest True cell of the same map, `(B, N, N)` int64 for
    `mask (B, N, N)` bool; `N` on a map with no True cell (further than any cell of the map)."""
    b, n, m = mask.shape
    distance = np.full(mask.shape, max(n, m), np.int64)
    reached = mask.copy()
    for radius in range(max(n, m)):
        distance[reached & (distance > radius)] = radius
        reached = within_distance(reached, 1)
    return distance
