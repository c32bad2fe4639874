"""Grid worlds: maps, the random generator, exact shortest paths, path utilities."""

from vinadv.grid.actions import ACTION_COSTS, ACTION_DELTAS, ACTION_NAMES, N_ACTIONS
from vinadv.grid.generator import default_obstacle_params, generate_maps, obstacle_fraction
from vinadv.grid.mapset import MAPS_FORMAT, MapSet
from vinadv.grid.paths import pack_paths, path_costs, take_paths, unpack_paths
from vinadv.grid.shortest_paths import (
    expert_paths,
    first_optimal_action,
    optimal_actions,
    shortest_distances,
    valid_moves,
)

__all__ = [
    "ACTION_COSTS", "ACTION_DELTAS", "ACTION_NAMES", "N_ACTIONS", "MAPS_FORMAT", "MapSet",
    "default_obstacle_params", "expert_paths", "first_optimal_action", "generate_maps", "obstacle_fraction",
    "optimal_actions", "pack_paths", "path_costs", "take_paths", "shortest_distances", "unpack_paths", "valid_moves",
]
