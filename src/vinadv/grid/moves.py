"""Movement models: which moves a map set allows and what each costs (DESIGN.md, "Moves").

A map set has one movement model, like its corner-cutting setting:

- `octile` (the default, the original VIN data's): the 8 moves, straight 1, diagonal sqrt 2.
- `moore` (GPPN's and the MP dataset's): the 8 moves, every move costs 1.
- `news` (GPPN's other model): the 4 straight moves N, S, E, W, cost 1.

A model's actions are the first `n_actions` of `vinadv.grid.actions.ACTION_DELTAS` (news: N, S, E, W are actions
0..3 of the 8-action order), so an action index means the same move in every model. Corner cutting concerns
diagonal moves only: `news` has none, so `news` without corner cutting is refused (`check_moves`) rather than
stored as a setting that means nothing.

Optimal move count: every move of `moore` and `news` costs 1, so an optimal path's move count L is its cost; on
`octile` an optimal cost `a + b*sqrt(2)` fixes the integers a (straight) and b (diagonal moves), so L = a + b.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.actions import ACTION_COSTS, ACTION_DELTAS

__all__ = [
    "DEFAULT_MOVES",
    "MOVES",
    "MoveModel",
    "check_moves",
    "move_model",
    "require_moves",
]


@dataclass(frozen=True, eq=False)
class MoveModel:
    """One movement model.

    Attributes:
        name: "octile", "moore" or "news".
        deltas: `(A, 2)` int64 `(d_row, d_col)` of each action, the first A of `ACTION_DELTAS`.
        costs: `(A,)` float64 cost of each action.
        diagonal_cost: what a diagonal displacement of one cell costs at least in this model (sqrt 2, 1, or 2 on
            `news`: two straight moves); the A* heuristics use it (`(max - min) + min * diagonal_cost` over the row
            and column distances: octile, Chebyshev or Manhattan distance).
        description: one line for messages and `maps show`.
    """

    name: str
    deltas: np.ndarray
    costs: np.ndarray
    diagonal_cost: float
    description: str

    @property
    def n_actions(self) -> int:
        return int(len(self.deltas))

    @property
    def unit_costs(self) -> bool:
        """Whether every move costs 1 (then an optimal path's move count is its cost)."""
        return bool(np.all(self.costs == 1.0))


def _model(name: str, n_actions: int, costs: np.ndarray, diagonal_cost: float, description: str) -> MoveModel:
    # writeable arrays, as ACTION_DELTAS: Numba compiles one specialisation per array type (read-only is another)
    deltas = np.ascontiguousarray(ACTION_DELTAS[:n_actions])
    costs = np.ascontiguousarray(costs, dtype=np.float64)
    return MoveModel(name, deltas, costs, float(diagonal_cost), description)


_MODELS = {
    "octile": _model("octile", 8, ACTION_COSTS, math.sqrt(2.0), "8 moves, straight 1, diagonal sqrt 2"),
    "moore": _model("moore", 8, np.ones(8), 1.0, "8 moves, every move costs 1"),
    "news": _model("news", 4, np.ones(4), 2.0, "4 moves (N, S, E, W), cost 1"),
}
#: the model names, default first
MOVES = tuple(_MODELS)
DEFAULT_MOVES = "octile"


def move_model(moves: str | MoveModel = DEFAULT_MOVES) -> MoveModel:
    """The `MoveModel` named `moves` (a model passes through); an unknown name raises InputError naming `moves`."""
    if isinstance(moves, MoveModel):
        return moves
    model = _MODELS.get(moves) if isinstance(moves, str) else None
    if model is None:
        raise InputError(f"moves {moves!r}: expected one of {', '.join(MOVES)}", "moves")
    return model


def check_moves(moves: str, corner_cutting: bool = True) -> str:
    """`moves` if it names a model and fits `corner_cutting`, else InputError: `news` has no diagonal moves, so
    corner cutting off is refused with it."""
    model = move_model(moves)
    if model.name == "news" and not corner_cutting:
        raise InputError(
            "moves 'news' has no diagonal moves, so corner_cutting off means nothing with it: keep corner cutting on",
            "moves",
            "corner_cutting",
        )
    return model.name


def require_moves(moves: str, supported: tuple[str, ...], what: str) -> None:
    """Refuse (InputError naming `moves`) maps of a movement model that `what` (say "the database") does not
    follow yet, instead of silently computing with another model's costs."""
    name = move_model(moves).name
    if name not in supported:
        raise InputError(
            f"moves {name!r}: {what} supports {' and '.join(repr(m) for m in supported)} moves only", "moves"
        )
