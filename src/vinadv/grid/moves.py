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
from typing import TYPE_CHECKING

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.actions import ACTION_COSTS, ACTION_DELTAS

if TYPE_CHECKING:
    from vinadv.npzfile import NpzReader

__all__ = [
    "DEFAULT_MOVES",
    "MOVES",
    "OCTILE_FORMATS",
    "MoveModel",
    "check_moves",
    "move_model",
    "read_moves",
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
        description: one line for messages.
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
#: the file format versions without a `moves` field: read as `octile`
OCTILE_FORMATS = ("vinadv.maps/1", "vinadv.paths/1", "vinadv.pairs/1")
#: the model names, the default first
MOVES = tuple(_MODELS)
DEFAULT_MOVES = MOVES[0]


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
            "moves 'news' has no diagonal moves, so it is refused without corner cutting (there is no corner to cut)",
            "moves",
        )
    return model.name


def require_moves(moves: str, supported: tuple[str, ...], what: str) -> None:
    """Refuse (InputError, one line naming the model) maps of a movement model that `what` (say "the database")
    does not follow yet, instead of silently computing with another model's costs."""
    name = move_model(moves).name
    if name not in supported:
        raise InputError(
            f"the maps use {name!r} moves: {what} follows {' and '.join(repr(m) for m in supported)} moves only"
        )


def read_moves(reader: NpzReader, corner_cutting: bool = True) -> str:
    """The movement model of a file being read: its field `moves`, or `octile` for a file of a format version
    without it (`OCTILE_FORMATS`). A name that is not a model, or
    `news` without corner cutting, raises InputError naming the file and the field."""
    if not reader.has("moves"):
        if reader.format in OCTILE_FORMATS:
            return DEFAULT_MOVES
        raise reader.fail("moves", "is missing")
    name = reader.scalar("moves", "U")
    if name not in MOVES:
        raise reader.fail("moves", f"is {name!r}, expected one of {', '.join(MOVES)}")
    if name == "news" and not corner_cutting:
        raise reader.fail(
            "moves", "is 'news' (no diagonal moves) with corner_cutting False (a 'news' file cuts corners)"
        )
    return name
