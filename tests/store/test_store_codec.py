"""Text formats of the store: vectorised codec against plain-Python oracles, round trips, malformed input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from tests.store.oracle import map_text, parse_map, parse_path, path_text
from vinadv.errors import InputError
from vinadv.grid.paths import PackedPaths
from vinadv.store import codec

maps_strategy = st.integers(0, 12).flatmap(
    lambda size: hnp.arrays(bool, st.tuples(st.integers(0, 6), st.just(size), st.just(size)))
)
cell_value = st.one_of(st.integers(0, 30), st.integers(0, 32767))  # small grids mostly, all int16 widths too
paths_strategy = st.lists(st.lists(st.tuples(cell_value, cell_value), max_size=25), max_size=12)


def _pack(paths):
    packed = PackedPaths.pack(paths)
    return packed.cells, packed.offsets


@settings(max_examples=150, deadline=None)
@given(maps_strategy)
def test_maps_match_oracle_and_round_trip(obstacles):
    texts = codec.encode_maps(obstacles)
    assert texts == [map_text(m) for m in obstacles]
    back = codec.decode_maps(texts, size=obstacles.shape[1]) if len(obstacles) else None
    if len(obstacles):
        assert np.array_equal(back, obstacles)
        if obstacles.shape[1]:
            assert np.array_equal(codec.decode_maps(texts), obstacles)  # size inferred from the text
            assert np.array_equal(np.array([parse_map(t) for t in texts]), obstacles)


@pytest.mark.slow  # over a second: the quick tier keeps the module's other tests
@settings(max_examples=200, deadline=None)
@given(paths_strategy)
def test_paths_match_oracle_and_round_trip(paths):
    cells, offsets = _pack(paths)
    texts = codec.encode_paths(cells, offsets)
    assert texts == [path_text(p) for p in paths]
    assert [parse_path(t) for t in texts] == [[tuple(c) for c in p] for p in paths]
    back_cells, back_offsets = codec.decode_paths(texts)
    assert np.array_equal(back_offsets, offsets)
    assert np.array_equal(back_cells, cells)
    assert [p.tolist() for p in PackedPaths(back_cells, back_offsets).unpack()] == [[list(c) for c in p] for p in paths]


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(cell_value, cell_value), max_size=20))
def test_cells_match_oracle(cells):
    arr = np.array(cells, dtype=np.int64).reshape(-1, 2)
    texts = codec.encode_cells(arr)
    assert texts == [f"{r},{c}" for r, c in cells]
    assert np.array_equal(codec.decode_cells(texts), arr)


def test_paper_examples():
    assert codec.encode_maps(np.array([[[0, 1, 1, 0], [1, 0, 0, 1], [0] * 4, [1] * 4]], bool)) == [
        "0110;1001;0000;1111"
    ]
    cells, offsets = codec.decode_paths(["3,4;3,5;4,6", "", "12,0"])
    assert cells.tolist() == [[3, 4], [3, 5], [4, 6], [12, 0]]
    assert offsets.tolist() == [0, 3, 3, 4]
    assert codec.encode_paths(cells, offsets) == ["3,4;3,5;4,6", "", "12,0"]


@pytest.mark.parametrize("text", ["1,2;3", "a,b", "1,,2", "1,2;", ";", "1;2", "1,2,3", "-1,2", "1 ,2", "123456,1"])
def test_malformed_paths_are_refused(text):
    with pytest.raises(InputError, match="path 1"):
        codec.decode_paths(["0,0", text])


@pytest.mark.parametrize(
    "text", ["0110;1001;0000;111", "0110;1001;0000;1112", "0110,1001,0000,1111", "01101001;00001111;"]
)
def test_malformed_maps_are_refused(text):
    with pytest.raises(InputError, match="map 1"):
        codec.decode_maps(["0110;1001;0000;1111", text])


def test_negative_cells_are_refused():
    with pytest.raises(InputError):
        codec.encode_paths(np.array([[-1, 2]]), np.array([0, 1]))


@pytest.mark.parametrize("top", [0, 9, 31, 32, 63, 64, 127, 128, 255, 256, 32767])
def test_every_table_side_and_the_fallback_match_oracle(top):
    # cells up to `top` pick the smallest cached table above it, or (256 and more) the digit-by-digit fallback
    rng = np.random.default_rng(top)
    paths = [[(int(r), int(c)) for r, c in rng.integers(0, top + 1, (k, 2))] for k in (0, 1, 5, 0, 3)]
    paths[2][0] = (top, top)
    cells, offsets = _pack(paths)
    assert codec.encode_paths(cells, offsets) == [path_text(p) for p in paths]
    flat = np.array([c for p in paths for c in p], dtype=np.int64).reshape(-1, 2)
    assert codec.encode_cells(flat) == [f"{r},{c}" for r, c in flat.tolist()]


def test_chunked_encoding_matches_oracle(monkeypatch):
    # a tiny chunk: maps and paths are encoded a few (or one) at a time, whatever the chunk boundaries cut
    monkeypatch.setattr(codec, "_CHUNK_BYTES", 64)
    rng = np.random.default_rng(0)
    for size in (1, 5, 9):  # 1 and 2 maps per chunk, and maps larger than a chunk
        obstacles = rng.random((11, size, size)) < 0.4
        assert codec.encode_maps(obstacles) == [map_text(m) for m in obstacles]
        assert codec.encode_maps(obstacles[:, ::-1, ::-1]) == [map_text(m) for m in obstacles[:, ::-1, ::-1]]
    lengths = [0, 3, 0, 0, 20, 1, 8, 9, 0, 7, 30, 0]  # empty paths, paths longer than a chunk (8 cells)
    for top in (27, 1000):
        paths = [[(int(r), int(c)) for r, c in rng.integers(0, top + 1, (k, 2))] for k in lengths]
        cells, offsets = _pack(paths)
        assert codec.encode_paths(cells, offsets) == [path_text(p) for p in paths]
        assert codec.encode_paths(cells, offsets)[1:4] == codec.encode_paths(*_pack(paths[1:4]))
