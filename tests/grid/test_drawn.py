"""Maps drawn by hand (`MapSet.from_ascii`, `vinadv.grid.drawn`): what the characters mean, padding, the movement
model and corner cutting asked for, what is refused, and random text (loaded or one line, never anything else)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.grid.oracle import brute_distances
from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet

DRAWING = """
#######
#S..#G#
#.#.#.#
#.#...#
#######
"""


def test_the_characters_padding_and_expert_path():
    maps = MapSet.from_ascii(DRAWING)
    assert len(maps) == 1 and maps.size == 7 and maps.n_starts == 1
    assert tuple(maps.goals[0]) == (1, 5) and tuple(maps.starts[0, 0]) == (1, 1)
    assert maps.obstacles[0, 0].all() and maps.obstacles[0, 5:].all()  # two rows of padding below
    assert maps.obstacles[0, 2, 2] and not maps.obstacles[0, 1, 2]
    best = brute_distances(maps.obstacles[0].tolist(), (1, 5))
    assert maps.expert_costs[0, 0] == pytest.approx(best[(1, 1)][0], abs=1e-12)
    np.testing.assert_array_equal(maps.expert_path(0)[[0, -1]], [[1, 1], [1, 5]])


def test_the_padding_is_frozen_and_no_attack_edits_it():
    from vinadv.attacks.validity import removable_cells, valid_cells  # noqa: PLC0415 (this test only)

    maps = MapSet.from_ascii(DRAWING, pad_to=9)  # 5x7 drawn, padded to 9x9
    expected = np.ones((9, 9), dtype=bool)
    expected[:5, :7] = False
    np.testing.assert_array_equal(maps.frozen[0], expected)
    add = valid_cells(maps.obstacles, maps.starts[:, 0], maps.goals, frozen=maps.frozen)
    remove = removable_cells(maps.obstacles, maps.starts[:, 0], maps.goals, frozen=maps.frozen)
    assert not (add | remove)[0][expected].any() and (add | remove)[0].any()
    assert MapSet.from_ascii("S.\n.G\n..", pad_to=None).frozen is not None  # 3x2 made square: a column frozen
    assert MapSet.from_ascii("S..\n...\n..G").frozen is None  # square already: nothing padded


def test_pad_to_moves_and_corner_cutting(tmp_path):
    maps = MapSet.from_ascii("S.@\n.@.\n..G", pad_to=10, corner_cutting=False, moves="moore")
    assert maps.size == 10 and maps.obstacles[0, 3:].all() and maps.obstacles[0, :, 3:].all()
    assert (maps.moves, maps.corner_cutting) == ("moore", False) and maps.expert_costs[0, 0] == 4
    maps.save(tmp_path / "m.npz")
    back = MapSet.load(tmp_path / "m.npz")
    np.testing.assert_array_equal(back.obstacles, maps.obstacles)
    two = MapSet.from_ascii("S.S\n...\n..G")
    assert two.n_starts == 2 and two.starts[0].tolist() == [[0, 0], [0, 2]]


@pytest.mark.parametrize(
    "text, kwargs, expected",
    [
        ("S.x\n..G", {}, "line 1 column 3 is 'x'"),
        ("S..\n.G", {}, "line 2 has 2 characters"),
        ("S..\n...", {}, "has 0 goals"),
        ("G..\n...", {}, "has no start"),
        ("S#.\n##G", {}, "the start \\(0, 0\\) cannot reach the goal"),
        ("S..\n..G", {"pad_to": 2}, "pad_to must be in 3..4096"),
        ("SG", {}, "smaller than 3x3"),
        ("S..\n..G", {"moves": "news", "corner_cutting": False}, "moves 'news'"),
        ("\n\n", {}, "no rows drawn"),
    ],
)
def test_what_is_refused_in_one_line(text, kwargs, expected):
    with pytest.raises(InputError, match=expected) as err:
        MapSet.from_ascii(text, **kwargs)
    assert "\n" not in str(err.value)


FUZZ = settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])


@FUZZ
@given(text=st.text(alphabet="#@.SG\n x\r\t", max_size=60))
def test_random_drawings_load_or_give_one_line(text):
    try:
        maps = MapSet.from_ascii(text)
    except InputError as exc:
        assert str(exc) and "\n" not in str(exc), repr(exc)
    else:
        assert len(maps) == 1 and np.isfinite(maps.expert_costs).all()
