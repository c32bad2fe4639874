"""`NeuralAstarPlanner`: Neural A* as a vinadv search planner, in two modes that give the same search.

- Exact mode (`plan_paths`, what `plan`, `attack`, `run`, `eval` use): the encoder's guidance cost maps (PyTorch, no
  gradients, batched), then the compiled best-first search of `vinadv.planners.classical.astar` with the authors'
  float32 arithmetic (`best_first_search(..., exact=False)`): their heuristic, f, tie rule and neighbour rule on `moore`
  moves with corner cutting.
- Differentiable mode (`differentiable_paths`, `plan_paths_differentiable`): the authors' differentiable A* in
  PyTorch (`vinadv.planners.neural_astar.differentiable`), for gradients (saliency) and training.

Both select the open cell of the largest float32 exp(-f / sqrt(N)), the first in row-major order; they can part only
where two open cells' values are equal in one computation and not in the other (PyTorch's vectorised float32 exp
against the correctly rounded one of the compiled search, and the authors' division by the sum before the argmax,
which can merge two values one unit apart): `vinadv neural-astar compare-modes` counts the searches where they part.

Movement: the authors' neighbour filter opens all 8 neighbours of a cell, a diagonal needing only its destination
free, and every move costs the cell left: the MP dataset's `moore` maps with corner cutting. Maps of another
movement model, or without corner cutting, are refused with one line.

Map size: every layer of the encoder is a 3x3 convolution, so any N x N map is planned; the search divides f by
sqrt(N), as the authors' code does. The shipped weights were trained on 32x32 mazes only.
"""

from __future__ import annotations

import numpy as np
import torch

from vinadv.planners.batching import forward_maps
from vinadv.planners.classical.astar import best_first_search
from vinadv.planners.interface import Capabilities, PlannerError
from vinadv.planners.neural_astar.differentiable import NeuralAstarPaths, authors_heuristic, search_results
from vinadv.planners.neural_astar.model import NeuralAstar
from vinadv.planners.result import check_plan_inputs
from vinadv.planners.search import SearchPlanner, SearchResult
from vinadv.planners.weights import weights_path_checksum

__all__ = ["MOVES", "NeuralAstarPlanner"]

#: the movement model of the authors' search: 8 neighbours, each move costs the guidance cost of the cell left
MOVES = "moore"


class NeuralAstarPlanner(SearchPlanner):
    """Neural A* with a `NeuralAstar` model (encoder and settings) for `size x size` maps (module doc).

    Attributes:
        model: the `NeuralAstar` module (eval mode), on `device`.
        batch_size: maps per encoder forward on a GPU, and per differentiable search (on the CPU the encoder runs
            in batches of `vinadv.planners.batching.forward_batches`, as `TorchPlanner`).

    Capabilities: expansions (the authors' histories), value maps of its own (minus its heuristic map) and gradients
    (the differentiable search, `differentiable_paths`).
    """

    moves = MOVES
    capabilities = Capabilities(value_maps=True, gradients=True, expansions=True, start_values=True)

    def __init__(
        self,
        model: NeuralAstar,
        size: int,
        device: str | torch.device | None = None,
        batch_size: int = 64,
        name: str = "neural-astar",
    ):
        self.name, self.size = name, int(size)
        # None: the CPU, not recorded in `spec()`; a device given is recorded by its type (as `TorchPlanner`)
        self.device = torch.device("cpu" if device is None else device)
        self.device_type = None if device is None else self.device.type
        self.model = model.to(self.device).eval()
        self.batch_size = max(1, int(batch_size))
        self._checksum = weights_path_checksum(model)

    @property
    def config(self) -> dict:
        return self.model.config.to_dict()

    def _check_inputs(self, obstacles, starts, goals, corner_cutting: bool):
        obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
        self._check_size(obstacles)
        if not corner_cutting:
            raise PlannerError(
                f"planner {self.name!r} searches with corner cutting (the authors' neighbour filter opens a diagonal "
                "whose destination is free); the maps forbid it"
            )
        return obstacles, starts, goals

    def guidance(self, obstacles: np.ndarray, starts: np.ndarray | None, goals: np.ndarray) -> np.ndarray:
        """The encoder's guidance cost maps `(B, N, N)` float32 in (0, 1), `batch_size` maps per forward (on the
        CPU, split between threads of one torch thread each, in `forward_batches`); `starts` None: the goal alone is
        marked."""
        b = len(obstacles)
        out = np.empty(obstacles.shape, dtype=np.float32)

        def forward(sl: slice) -> None:
            obs = torch.from_numpy(obstacles[sl].astype(np.float32)).to(self.device)
            s = None if starts is None else torch.from_numpy(starts[sl]).to(self.device)
            g = torch.from_numpy(goals[sl]).to(self.device)
            out[sl] = self.model(obs, s, g).to("cpu", torch.float32).numpy()

        forward_maps(b, self.device, self.batch_size, forward)
        return out

    def plan_paths(
        self, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True
    ) -> SearchResult:
        """The exact mode: guidance cost maps, then the compiled search with the authors' float32 arithmetic."""
        obstacles, starts, goals = self._check_inputs(obstacles, starts, goals, corner_cutting)
        cost = self.guidance(obstacles, starts, goals)
        return best_first_search(
            cost, obstacles, starts, goals, self.model.config.g_ratio, MOVES, True, tmax=1.0, exact=False
        )

    def plan_paths_differentiable(
        self, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True
    ) -> SearchResult:
        """The differentiable mode's search as a `SearchResult` (no gradients; the paths are the chains of parents,
        `[start]` with termination `step_limit` where the goal was not reached), `batch_size` maps at a time (on the
        CPU, split between threads of one torch thread each: the search's many small steps gain nothing from
        PyTorch's own threads and lose much to their synchronisation on a busy machine)."""
        obstacles, starts, goals = self._check_inputs(obstacles, starts, goals, corner_cutting)
        return search_results(self.differentiable_paths.search, obstacles, starts, goals, self.device, self.batch_size)

    @property
    def differentiable_paths(self) -> NeuralAstarPaths:
        """`module(obstacles (B,N,N) float 1/0, starts, goals) -> (B, N, N)` path map, differentiable with respect
        to the obstacles through the encoder (`differentiable.NeuralAstarPaths`)."""
        return NeuralAstarPaths(self.model)

    def value_maps(self, obstacles: np.ndarray, goals: np.ndarray, starts: np.ndarray | None = None) -> np.ndarray:
        """Minus the search's own heuristic map, `-(chebyshev + 0.001 euclid + guidance cost)` (the authors' h),
        `(B, N, N)` float64: larger nearer the goal and on cells the encoder marks cheap, the map the search ranks
        open cells by (with g). The encoder reads the start: with `starts (B, 2)` it is the guidance of those
        searches; without, the start + goal channel holds the goal alone."""
        obstacles = np.ascontiguousarray(obstacles, dtype=bool)
        self._check_size(obstacles)
        obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
        cost = self.guidance(obstacles, starts, goals)
        heuristic = authors_heuristic(torch.from_numpy(goals), obstacles.shape[1]).numpy()
        return -(heuristic.astype(np.float64) + cost.astype(np.float64))
