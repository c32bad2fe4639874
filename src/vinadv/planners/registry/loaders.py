"""The loaders of vinadv's registered planners, named by their declarations as `"module:function"`
(`vinadv.planners.registry.declarations`). Each is `load(size, weights, corner_cutting, device, **kwargs)`:
`weights` a file (None: the planner's default), `device` a checked device name or None, `name` the registered name
the planner is made with (no renaming after load). Each imports its planner's modules when called.
"""

from __future__ import annotations

from vinadv.grid.actions import N_ACTIONS
from vinadv.planners.interface import Planner, TorchPlanner
from vinadv.planners.vin.planner import VINPlanner
from vinadv.planners.weights import check_action_count, check_trained_size, trained_moves, weights_checksum


def load_vin(size: int, weights: str | None, corner_cutting: bool, device: str | None, name: str = "vin") -> Planner:
    from vinadv.planners.vin.weights import load_vin_weights  # noqa: PLC0415

    loaded = load_vin_weights(weights, size=size)
    check_trained_size(loaded.path, loaded.record, size, "VIN")
    return VINPlanner(loaded, size=size, device=device, name=name)  # its `moves` from the record: checked on load


def load_gppn(size: int, weights: str | None, corner_cutting: bool, device: str | None, name: str = "gppn") -> Planner:
    from vinadv.planners.gppn import load_gppn as read_gppn  # noqa: PLC0415 (PyTorch: the VIN loads without it)
    from vinadv.planners.padding import ActionPadding  # noqa: PLC0415 (PyTorch, as above)

    model = read_gppn(weights, size=size)
    if device is not None:
        model = model.to(device)
    check_trained_size(model.weights_path, model.record, size, "GPPN")
    moves = trained_moves(model.weights_path, model.record)
    check_action_count(model.weights_path, model.config.n_actions, moves, "GPPN")
    planner = TorchPlanner(
        model if model.config.n_actions == N_ACTIONS else ActionPadding(model),  # news: 4 actions, -inf on the rest
        name,
        size,
        checksum=weights_checksum(model.weights_path),
        config=model.config.to_dict(),
        device=device,
    )
    planner.moves = moves  # the model it was trained on: `load_planner` refuses maps of another
    return planner


def load_neural_astar(
    size: int, weights: str | None, corner_cutting: bool, device: str | None, name: str = "neural-astar"
) -> Planner:
    from vinadv.planners.neural_astar.model import load_neural_astar as read_neural_astar  # noqa: PLC0415 (PyTorch)
    from vinadv.planners.neural_astar.planner import NeuralAstarPlanner  # noqa: PLC0415 (PyTorch, as above)

    return NeuralAstarPlanner(read_neural_astar(weights), size, device=device, name=name)


def load_optimal(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    from vinadv.planners.classical.optimal import OptimalPlanner  # noqa: PLC0415

    return OptimalPlanner(size, corner_cutting)


def load_astar(size: int, weights: str | None, corner_cutting: bool, device: str | None) -> Planner:
    from vinadv.planners.classical.astar import AStarPlanner  # noqa: PLC0415

    return AStarPlanner(size)  # the move rule comes with each search (`plan_paths`' corner_cutting)


def load_wastar(size: int, weights: str | None, corner_cutting: bool, device: str | None, w: float) -> Planner:
    from vinadv.planners.classical.astar import WeightedAStarPlanner  # noqa: PLC0415

    return WeightedAStarPlanner(size, w=w)
