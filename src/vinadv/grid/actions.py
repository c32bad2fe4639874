"""The 8 moves of the grid world, in the action order of the original VIN data (DESIGN.md)."""

from __future__ import annotations

import math

import numpy as np

ACTION_NAMES = ("N", "S", "E", "W", "NE", "NW", "SE", "SW")
#: (d_row, d_col) of each action, shape (8, 2).
ACTION_DELTAS = np.array([(-1, 0), (1, 0), (0, 1), (0, -1), (-1, 1), (-1, -1), (1, 1), (1, -1)], dtype=np.int64)
#: cost of each action: 1 orthogonal, sqrt(2) diagonal, shape (8,).
ACTION_COSTS = np.array([1.0, 1.0, 1.0, 1.0] + [math.sqrt(2.0)] * 4)
N_ACTIONS = 8
SQRT2 = math.sqrt(2.0)
