"""`TransPathPlanner`: TransPath's two models as vinadv search planners, `transpath-cf` and `transpath-focal`.

Two modes that give the same search, named as Neural A*'s:

- Exact mode (`plan_paths`, what `plan`, `attack`, `run`, `eval` use), the compiled replica: the network's outputs
  (PyTorch, no gradients, batched), then the compiled search of `vinadv.planners.transpath.search` in the authors'
  float32 arithmetic (their octile heuristic, their f, selection and tie rule).
- Differentiable mode (`differentiable_paths`, `plan_paths_differentiable`): the network, then the authors' search
  in PyTorch (`vinadv.planners.transpath.differentiable`), for gradients (the saliency attack).

They can part only where two open cells' values are equal in one computation and not in the other (PyTorch's
vectorised float32 exp against the correctly rounded one, the division by the sum before the argmax): counted by
`tests/planners/transpath` and `perf/transpath_faithfulness.py`.

Movement: octile moves (the authors' cost filter: 1 and sqrt 2). The authors' search cuts corners; on maps without
corner cutting this one keeps the maps' rule (a diagonal also needs both cells beside it free).

Map size: 64x64 only (the model's positional embeddings are 8x8 after three halvings); other sizes are refused.
"""

from __future__ import annotations

import numpy as np
import torch

from vinadv.planners.batching import forward_maps
from vinadv.planners.interface import Capabilities, PlannerError
from vinadv.planners.neural_astar.differentiable import search_results
from vinadv.planners.result import check_plan_inputs
from vinadv.planners.search import SearchPlanner, SearchResult
from vinadv.planners.transpath.differentiable import TransPathPaths
from vinadv.planners.transpath.model import SIZE, TransPath
from vinadv.planners.transpath.search import F_W, K_FLOOR, octile_heuristic, transpath_search
from vinadv.planners.weights import weights_path_checksum

__all__ = ["MOVES", "NAMES", "TransPathPlanner"]

#: the movement model of the authors' search: 8 neighbours, orthogonal cost 1, diagonal sqrt 2
MOVES = "octile"
#: the registered planner of each mode
NAMES = {"cf": "transpath-cf", "f": "transpath-focal"}


def check_size(name: str, size: int) -> int:
    if int(size) != SIZE:
        raise PlannerError(
            f"planner {name!r} is for {SIZE}x{SIZE} maps only (its positional embeddings are 8x8), not {size}x{size}"
        )
    return SIZE


class TransPathPlanner(SearchPlanner):
    """TransPath with a `TransPath` model of mode `cf` (A* with the octile heuristic divided by the predicted
    correction factor) or `f` (focal search on the predicted focal values, `f_w` 100) for 64x64 maps (module doc).

    Capabilities: expansions (the authors' histories), value maps of its own (`cf`: minus its heuristic,
    `-octile / max(k, 0.1)`; `f`: the focal values) and gradients (the differentiable search, `differentiable_paths`).
    """

    moves = MOVES
    capabilities = Capabilities(value_maps=True, gradients=True, expansions=True, start_values=True)
    vanilla_ratios = True

    def __init__(
        self,
        model: TransPath,
        size: int = SIZE,
        device: str | torch.device | None = None,
        batch_size: int = 64,
        name: str | None = None,
    ):
        self.name = name or NAMES[model.mode]
        self.size = check_size(self.name, size)
        self.mode = model.mode
        self.device = torch.device("cpu" if device is None else device)
        self.device_type = None if device is None else self.device.type
        self.model = model.to(self.device).eval()
        self.batch_size = max(1, int(batch_size))
        self.f_w = F_W
        self._checksum = weights_path_checksum(model)

    @property
    def config(self) -> dict:
        return {"mode": self.mode, **({"f_w": self.f_w} if self.mode == "f" else {})}

    def outputs(self, obstacles: np.ndarray, starts: np.ndarray | None, goals: np.ndarray) -> tuple[np.ndarray, ...]:
        """The network's `(output + 1) / 2` `(B, 64, 64)` float32 (correction factors or focal values), and, for the
        focal model, their float32 exp as PyTorch computes it (the search's keys), `batch_size` maps per forward."""
        b = len(obstacles)
        out = np.empty(obstacles.shape, dtype=np.float32)
        exp = np.empty(obstacles.shape, dtype=np.float32) if self.mode == "f" else None

        def forward(sl: slice) -> None:
            obs = torch.from_numpy(obstacles[sl].astype(np.float32)).to(self.device)
            s = None if starts is None else torch.from_numpy(starts[sl]).to(self.device)
            g = torch.from_numpy(goals[sl]).to(self.device)
            y = self.model(obs, s, g).to("cpu", torch.float32)  # (b, 1, 64, 64), as the authors' tensors
            out[sl] = y[:, 0].numpy()
            if exp is not None:
                exp[sl] = torch.exp(y)[:, 0].numpy()

        forward_maps(b, self.device, self.batch_size, forward)
        return out, exp

    def _check_inputs(self, obstacles, starts, goals):
        obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
        self._check_size(obstacles)
        return obstacles, starts, goals

    def plan_paths(
        self, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True
    ) -> SearchResult:
        """The exact mode, the compiled replica: the network's outputs, then the compiled search (module doc)."""
        obstacles, starts, goals = self._check_inputs(obstacles, starts, goals)
        out, exp = self.outputs(obstacles, starts, goals)
        return transpath_search(out, obstacles, starts, goals, self.mode, corner_cutting, self.f_w, exp)

    def plan_paths_differentiable(
        self, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True
    ) -> SearchResult:
        """The differentiable mode's search as a `SearchResult` (no gradients), `batch_size` maps at a time, keeping
        the maps' rule (`vinadv.planners.neural_astar.differentiable.search_results`)."""
        obstacles, starts, goals = self._check_inputs(obstacles, starts, goals)
        search = self.differentiable_module(corner_cutting).search
        return search_results(search, obstacles, starts, goals, self.device, self.batch_size)

    def differentiable_module(self, corner_cutting: bool = True) -> TransPathPaths:
        """The differentiable search's path-map module keeping the maps' rule `corner_cutting`."""
        return TransPathPaths(self.model, self.f_w, corner_cutting)

    @property
    def differentiable_paths(self) -> TransPathPaths:
        """`module(obstacles (B,64,64) float 1/0, starts, goals) -> (B, 64, 64)` path map, differentiable with respect
        to the obstacles through the network (`differentiable.TransPathPaths`), searching as the authors (corners
        cut): the saliency attack's ranking signal, whatever the maps' rule."""
        return self.differentiable_module(True)

    def value_maps(self, obstacles: np.ndarray, goals: np.ndarray, starts: np.ndarray | None = None) -> np.ndarray:
        """`(B, 64, 64)` float64, larger where the search goes first: `cf`, minus its heuristic `-octile / max(k,
        0.1)`; `f`, the focal values (read with the start: with `starts (B, 2)` those searches', without, the start +
        goal channel holds the goal alone)."""
        obstacles = np.ascontiguousarray(obstacles, dtype=bool)
        self._check_size(obstacles)
        obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
        out, _ = self.outputs(obstacles, starts, goals)
        if self.mode == "f":
            return out.astype(np.float64)
        octile = octile_heuristic(goals, obstacles.shape[1])
        return -(octile / np.where(out > K_FLOOR, out, K_FLOOR)).astype(np.float64)


def load(
    size: int, weights: str | None, corner_cutting: bool, device: str | None, mode: str = "cf", name: str = ""
) -> TransPathPlanner:
    """The registry's loader of `transpath-cf` (`mode` "cf") and `transpath-focal` (`mode` "f"): the shipped
    conversion of the authors' weights, or `weights` (a vinadv.transpath/1 file of that mode)."""
    from vinadv.planners.transpath.model import load_transpath  # noqa: PLC0415 (beside the planner)

    check_size(name or NAMES[mode], size)
    return TransPathPlanner(load_transpath(weights, mode), size, device=device, name=name or NAMES[mode])
