"""Movement models: names, action sets, costs and the corner-cutting rule."""

import math

import numpy as np
import pytest

from vinadv.errors import InputError
from vinadv.grid import ACTION_COSTS, ACTION_DELTAS, DEFAULT_MOVES, MOVES, check_moves, move_model
from vinadv.grid.moves import require_moves


def test_models_are_prefixes_of_the_action_order_with_their_costs():
    assert MOVES == ("octile", "moore", "news") and DEFAULT_MOVES == "octile"
    octile, moore, news = (move_model(m) for m in MOVES)
    assert np.array_equal(octile.deltas, ACTION_DELTAS)
    assert octile.costs.tobytes() == ACTION_COSTS.tobytes() and octile.diagonal_cost == math.sqrt(2)
    assert np.array_equal(moore.deltas, ACTION_DELTAS) and (moore.costs == 1).all() and moore.diagonal_cost == 1
    assert np.array_equal(news.deltas, ACTION_DELTAS[:4]) and news.n_actions == 4 and (news.costs == 1).all()
    assert [m.unit_costs for m in (octile, moore, news)] == [False, True, True]
    assert move_model(moore) is moore


def test_unknown_names_and_news_without_corner_cutting_are_refused():
    with pytest.raises(InputError, match="moves 'hex': expected one of octile, moore, news") as err:
        move_model("hex")
    assert err.value.parameters == ("moves",)
    for moves in MOVES:
        assert check_moves(moves, True) == moves
    assert check_moves("moore", False) == "moore"
    with pytest.raises(InputError, match="'news' has no diagonal moves, so it is refused without corner cutting"):
        check_moves("news", False)


def test_require_moves_names_the_value_and_what_refuses_it():
    require_moves("octile", ("octile",), "the database")
    with pytest.raises(InputError, match="^the maps use 'moore' moves: the database follows 'octile' moves only$"):
        require_moves("moore", ("octile",), "the database")
