"""The MP dataset layout (Neural A*'s benchmark): the start-drawing rule against a plain implementation, the real
families' distances against vinadv's `moore` expert costs, export and import round trips, what is refused."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.fault_files import forge_npy_header
from tests.grid.oracle import brute_distances
from tests.interop.conftest import mpd_file
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.grid.mapset import MapSet
from vinadv.grid.shortest_paths import shortest_distances
from vinadv.interop import export_maps, import_maps, read_maps
from vinadv.interop.formats import files
from vinadv.interop.formats.mpd import draw_starts, start_bands

FAMILIES = ("mazes", "forest", "alternating_gaps", "multiple_bugtraps", "shifting_gaps", "single_bugtrap")


def plain_percentile(values, q):
    """NumPy's default ('linear') percentile, from its definition: position q/100 * (m - 1) in the sorted values,
    interpolated between its two neighbours."""
    v = sorted(values)
    pos = q / 100 * (len(v) - 1)
    lo = math.floor(pos)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (v[hi] - v[lo]) * (pos - lo)


def plain_bands(stored):
    """The Neural A* loader's bands of one map (55-70, 70-85, 85-100 percent of the distance), as sets of flat
    indices: over the values above the map's minimum, the 45th, 30th, 15th and 0th percentiles of the negative
    distance bound them, inclusive."""
    flat = [float(x) for x in np.asarray(stored).reshape(-1)]
    low = min(flat)
    values = [x for x in flat if x > low]
    if not values:
        return [set(), set(), set()]
    th = [plain_percentile(values, q) for q in (45, 30, 15, 0)]
    return [{i for i, x in enumerate(flat) if x > low and th[r + 1] <= x <= th[r]} for r in range(3)]


def random_stored(rng, n, size):
    """Negative distances as the MP files hold them: obstacles at -size*size, the rest -d for small d."""
    stored = -rng.integers(0, 12, size=(n, size, size)).astype(np.float64)
    stored[rng.random((n, size, size)) < 0.3] = -size * size
    stored[0] = -size * size  # one cell above the minimum (the goal alone): it is every band
    stored[0, 1, 1] = 0.0
    stored[1, :, :] = -3.0  # every value equal: nothing above the minimum
    stored[2] = -size * size
    stored[2, 0, :2] = (-1.0, -5.0)  # two values: bands that fall between them are empty
    return stored


def test_start_bands_match_a_plain_implementation_of_the_loader_rule():
    rng = np.random.default_rng(7)
    stored = random_stored(rng, 40, 7)
    bands = start_bands(stored)
    for i in range(len(stored)):
        want = plain_bands(stored[i])
        assert [set(np.flatnonzero(bands[i, r])) for r in range(3)] == want
    assert [set(np.flatnonzero(b)) for b in bands[0]] == [{8}] * 3 and not bands[1].any()


def plain_draw(stored, k, seed):
    """The documented draw, one map and one start at a time: the loader's rule (a non-empty band at random, then a
    cell of it) for every slot from `rng.random((n, k, 2))`; then, round after round, every slot that repeats an
    earlier slot of its map (maps with at least k band cells) is drawn again, in (map, slot) order, from two more
    uniforms each; a map with fewer band cells than k gets them all, in order. Returns (starts, counts) as lists."""
    rng = np.random.default_rng(seed)
    sets = [[sorted(b) for b in plain_bands(m)] for m in stored]
    u = rng.random((len(stored), k, 2))

    def pick(i, a, b):
        nonempty = [band for band in sets[i] if band]
        band = nonempty[min(int(a * len(nonempty)), len(nonempty) - 1)]
        return band[min(int(b * len(band)), len(band) - 1)]

    union = [sorted(set().union(*map(set, s))) for s in sets]
    drawn = [[pick(i, *u[i, j]) if union[i] else 0 for j in range(k)] for i in range(len(stored))]
    while True:
        repeats = [
            (i, j) for i in range(len(stored)) if len(union[i]) >= k for j in range(k) if drawn[i][j] in drawn[i][:j]
        ]
        if not repeats:
            break
        for i, j in repeats:
            a, b = rng.random(2)
            drawn[i][j] = pick(i, a, b)
    counts = [min(len(c), k) for c in union]
    for i, c in enumerate(union):
        if len(c) < k:
            drawn[i] = [c[j] if j < len(c) else 0 for j in range(k)]
    return drawn, counts


@pytest.mark.parametrize("k", [1, 4, 9])
def test_drawn_starts_follow_the_plain_rule_distinct_per_map(k):
    rng = np.random.default_rng(3)
    stored = random_stored(rng, 30, 6)
    stored[3] = -36.0  # three cells above the minimum, of which only -3 lies in a band (85-100): padded at k > 1
    stored[3, 0, :3] = (-1.0, -2.0, -3.0)
    drawn, counts = draw_starts(start_bands(stored), k, np.random.default_rng(11))
    want, want_counts = plain_draw(stored, k, 11)
    assert drawn.tolist() == want and counts.tolist() == want_counts
    for i in range(len(stored)):  # the real starts of a map differ
        assert len(set(drawn[i, : counts[i]].tolist())) == counts[i]
    assert counts[1] == 0 and counts[3] == 1 and drawn[3, 0] == 2


def test_many_starts_import_distinct_and_the_file_loads(tmp_path):
    export_maps(generate_maps(4, 12, seed=3, n_starts=1, moves="moore"), tmp_path / "mp.npz", "mpd", split="test")
    out = tmp_path / "m.npz"
    args = ["maps", "import", "--format", "mpd", str(tmp_path / "mp.npz"), "--split", "test", "--starts", "10"]
    assert main([*args, "--out", str(out), "--json"]) == 0
    maps = MapSet.load(out)  # refused a file with a repeated start before
    assert maps.n_starts == 10 and len(maps) == 4
    for i in range(len(maps)):
        real = maps.starts[i][maps.start_mask[i]]
        assert len({tuple(c) for c in real.tolist()}) == len(real) == 10  # 12x12 maps: enough band cells


def _check_family(family: str, split: str, starts: int = 2, seed: int = 5):
    maps, info = read_maps(mpd_file(family), "mpd", split=split, starts=starts, seed=seed)
    assert maps.moves == "moore" and maps.corner_cutting and maps.seed == seed and info["maps_left_out_no_start"] == 0
    assert len(maps) == {"train": 800, "valid": 100, "test": 100}[split] and maps.starts.shape[1] == starts
    stored = -np.load(mpd_file(family))[f"arr_{ {'train': 3, 'valid': 7, 'test': 11}[split] }"][:, 0]
    costs = stored[np.arange(len(maps))[:, None], maps.starts[..., 0], maps.starts[..., 1]]
    np.testing.assert_array_equal(maps.expert_costs, costs)  # the file's own distances at the drawn starts
    return maps


def test_one_family_imports_clean_its_corner_cutting_read_from_the_data():
    maps = _check_family("mazes", "test")
    again = import_maps(mpd_file("mazes"), "mpd", split="test", starts=2, seed=5)
    np.testing.assert_array_equal(maps.starts, again.starts)
    # the data decides corner cutting: every distance is vinadv's with it (checked on import), and without it some
    # map differs (the generator's diagonal needs only its destination free)
    with_cc, _ = shortest_distances(maps.obstacles, maps.goals, True, "moore")
    without, _ = shortest_distances(maps.obstacles, maps.goals, False, "moore")
    assert (with_cc != without).any()
    # a plain Bellman-Ford agrees on one map (an oracle independent of the import's Dijkstra)
    best = brute_distances(maps.obstacles[0].tolist(), tuple(maps.goals[0]), moves="moore")
    assert maps.expert_costs[0, 0] == best[tuple(maps.starts[0, 0])][0]


@pytest.mark.slow
@pytest.mark.parametrize("family", FAMILIES)
def test_every_shared_family_imports_clean_on_every_split(family):
    for split in ("train", "valid", "test"):
        _check_family(family, split, starts=1, seed=0)


def test_a_distance_that_is_not_moores_is_one_line_naming_the_array(tmp_path):
    with np.load(mpd_file("forest")) as f:
        test = [f[f"arr_{i}"] for i in range(8, 12)]
    arrays = [a[:0] for a in test] + [a[:10] for a in test] + test  # valid: the test split's first 10 maps
    arrays[11] = arrays[11].copy()
    free = np.argwhere(arrays[8][3] == 1)[5]
    arrays[11][3, 0, free[0], free[1]] -= 1
    np.savez(tmp_path / "bad.npz", *arrays)
    with pytest.raises(InputError, match=r"bad\.npz: array 'arr_11' has .* at map 3 cell .*moore distance says") as err:
        import_maps(tmp_path / "bad.npz", "mpd")
    assert "\n" not in str(err.value)
    assert len(import_maps(tmp_path / "bad.npz", "mpd", split="valid")) == 10  # another split is not read


def test_export_then_import_keeps_moore_maps_and_refuses_others(tmp_path):
    maps = generate_maps(6, 12, seed=2, n_starts=1, moves="moore")
    info = export_maps(maps, tmp_path / "m.npz", "mpd", split="valid")
    assert info["maps"] == 6 and info["split"] == "valid"
    with np.load(tmp_path / "m.npz") as f:
        assert [f[f"arr_{i}"].shape[0] for i in range(12)] == [0] * 4 + [6] * 4 + [0] * 4
        dist = -f["arr_7"][:, 0]
    back = import_maps(tmp_path / "m.npz", "mpd", split="valid", starts=3, seed=1)
    np.testing.assert_array_equal(back.obstacles, maps.obstacles)
    np.testing.assert_array_equal(back.goals, maps.goals)
    for i in range(len(maps)):  # the distances written are a plain Bellman-Ford's, -144 where unreached
        best = brute_distances(maps.obstacles[i].tolist(), tuple(maps.goals[i]), moves="moore")
        for (r, c), (cost, _) in best.items():
            assert dist[i, r, c] == (cost if math.isfinite(cost) else 144)
    with pytest.raises(InputError, match="the MP layout's moves cut corners"):
        export_maps(generate_maps(2, 10, seed=1, corner_cutting=False, moves="moore"), tmp_path / "x.npz", "mpd")


def test_the_command_imports_a_split_and_refuses_another_model(tmp_path, capsys):
    out = tmp_path / "m.npz"
    line = ["maps", "import", "--format", "mpd", str(mpd_file("mazes")), "--split", "test", "--out", str(out)]
    assert main([*line, "--starts", "2", "--seed", "4", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["moves"] == "moore" and summary["maps"] == 100 and summary["starts_seed"] == 4
    assert main([*line, "--moves", "octile"]) == 2
    assert "--moves 'octile': format mpd holds moore maps" in capsys.readouterr().err
    assert main([*line[:-2], "--split", "all", "--out", str(tmp_path / "x.npz")]) == 2


# ------------------------------------------------------------------------------------------- bounds (issue 45)


@pytest.fixture
def small_mp(tmp_path):
    """An MP file of 4 moore 12x12 maps in its test split."""
    path = tmp_path / "mp.npz"
    export_maps(generate_maps(4, 12, seed=3, n_starts=1, moves="moore"), path, "mpd", split="test")
    return path


def test_an_empty_split_reads_as_no_maps_and_the_command_says_so(small_mp, tmp_path, capsys):
    """A split of 0 maps was a traceback (a reshape of 0 maps); it reads as none, as the other layouts' empty splits,
    and `maps import` says there is nothing to import."""
    maps, info = read_maps(small_mp, "mpd", split="valid", starts=3)
    assert len(maps) == 0 and maps.size == 12 and info["maps"] == 0 and info["maps_left_out_no_start"] == 0
    out = tmp_path / "m.npz"
    assert main(["maps", "import", "--format", "mpd", str(small_mp), "--split", "valid", "--out", str(out)]) == 2
    assert capsys.readouterr().err.strip().endswith("mp.npz: no maps to import (split valid)") and not out.exists()


@pytest.mark.parametrize("starts", [145, 10**9])
def test_starts_past_a_maps_cells_are_one_line_before_any_draw(small_mp, tmp_path, capsys, starts):
    """`--starts` 10^9 tried to allocate terabytes, 145 on 12x12 maps broke a broadcast: more starts than a map has
    cells is refused, naming the flag; as many as its cells is the padded import."""
    with pytest.raises(InputError, match=f"n_starts {starts}: more than the 144 cells of the file's 12x12 maps"):
        read_maps(small_mp, "mpd", starts=starts)
    line = ["maps", "import", "--format", "mpd", str(small_mp), "--out", str(tmp_path / "m.npz"), "--quiet"]
    assert main([*line, "--starts", str(starts)]) == 2
    assert f"vinadv: error: --starts {starts}: more than the 144 cells" in capsys.readouterr().err
    maps, info = read_maps(small_mp, "mpd", starts=144, seed=2)
    assert maps.n_starts == 144 and info["maps_padded"] == 4
    for i in range(len(maps)):  # every band cell once, the rest padded
        real = maps.starts[i][maps.start_mask[i]]
        assert len({tuple(c) for c in real.tolist()}) == len(real) < 144


@pytest.mark.parametrize(
    ("name", "shape", "dtype"),
    [("arr_11", (100000, 1, 1000, 512), None), ("arr_8", (4, 12, 13), None), ("arr_10", (4, 8, 1, 12, 12), "<c16")],
)
def test_a_forged_npy_header_is_refused_before_numpy_allocates(small_mp, tmp_path, name, shape, dtype):
    """A header claiming 381 GiB over a few KiB of data made NumPy allocate what it claims (a MemoryError): the
    headers are read first, and an array that claims more than its archive holds is one line naming it."""
    forged = forge_npy_header(small_mp, tmp_path / "forged.npz", name, shape, dtype)
    with pytest.raises(InputError, match=rf"forged\.npz: array '{name}' has a header that claims shape") as err:
        read_maps(forged, "mpd")
    assert "but the archive holds" in str(err.value) and "\n" not in str(err.value)
    if shape[0] == 100000:
        assert "(381.5 GiB)" in str(err.value)


def test_arrays_that_need_more_than_half_the_memory_are_refused(small_mp, monkeypatch):
    monkeypatch.setattr(files, "available_memory", lambda: 20_000)
    with pytest.raises(InputError, match=r"mp\.npz: the arrays read need .* more than half the 19\.5 KiB available"):
        read_maps(small_mp, "mpd")
