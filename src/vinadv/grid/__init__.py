"""Grid worlds: maps, movement models, the random generator, exact shortest paths, packed paths and path pairs,
flips/rotations."""

from vinadv.grid.actions import ACTION_COSTS, ACTION_DELTAS, ACTION_NAMES, N_ACTIONS
from vinadv.grid.generator import default_obstacle_params, generate_maps, obstacle_fraction
from vinadv.grid.mapset import MAPS_FORMAT, MapSet
from vinadv.grid.moves import DEFAULT_MOVES, MOVES, MoveModel, check_moves, move_model
from vinadv.grid.pairs import PathPairs
from vinadv.grid.paths import PackedPaths
from vinadv.grid.shortest_paths import (
    expert_paths,
    first_optimal_action,
    optimal_actions,
    shortest_distances,
    valid_moves,
)

__all__ = [
    "ACTION_COSTS",
    "ACTION_DELTAS",
    "ACTION_NAMES",
    "N_ACTIONS",
    "DEFAULT_MOVES",
    "MAPS_FORMAT",
    "MOVES",
    "MapSet",
    "MoveModel",
    "check_moves",
    "default_obstacle_params",
    "expert_paths",
    "first_optimal_action",
    "generate_maps",
    "move_model",
    "obstacle_fraction",
    "optimal_actions",
    "PackedPaths",
    "PathPairs",
    "shortest_distances",
    "valid_moves",
]
