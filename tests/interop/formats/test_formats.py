"""`read_maps` and `export_maps` over the layouts: refusals, splits, the CLI, the round trip."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io

from tests.interop.formats.layouts import (
    assert_same_maps,
    gppn_arrays,
    kentsommer_arrays,
    trajectories,
    write_avivt_test,
    write_gppn,
    write_kentsommer,
)
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import MapSet, generate_maps
from vinadv.interop import import_maps


def _flip(arrays, index, channel=None):
    out = [a.copy() for a in arrays]
    if channel is None:
        out[index] = 1 - out[index]
    else:
        out[index][:, channel] = 1 - out[index][:, channel]
    return out


def test_other_polarity_wrong_shape_and_missing_arrays_are_refused(tmp_path, small_maps):
    trajs = trajectories(small_maps)
    k = kentsommer_arrays(small_maps, trajs)
    empty = kentsommer_arrays(small_maps, [])
    cases = {
        "polarity.npz": (_flip(empty, 0, 0) + _flip(k, 0, 0), r"'arr_4' has the goal on an obstacle.*polarity"),
        "shape.npz": (empty + [k[0][:, :1]] + k[1:], r"'arr_4' has shape .*expected \(m, 2, s, s\)"),
        "missing.npz": (empty + k[:3], "array 'arr_7' is missing"),
    }
    for name, (arrays, message) in cases.items():
        np.savez(tmp_path / name, *arrays)
        with pytest.raises(InputError, match=f"{name}: array {message}" if "missing" not in name else message):
            import_maps(tmp_path / name, "kentsommer")
    write_avivt_test(tmp_path / "a.mat", small_maps, trajs)
    raw = scipy.io.loadmat(tmp_path / "a.mat")
    scipy.io.savemat(
        tmp_path / "p.mat",
        {**{k: v for k, v in raw.items() if not k.startswith("__")}, "all_im_data": 1 - raw["all_im_data"]},
    )
    with pytest.raises(InputError, match=r"p\.mat: array 'all_im_data' has the goal on an obstacle.*1 = free"):
        import_maps(tmp_path / "p.mat", "avivt")
    g = gppn_arrays(small_maps.obstacles, small_maps.goals)
    np.savez(tmp_path / "g.npz", *[a[:0] for a in g] * 2, 1 - g[0], g[1], g[2])
    with pytest.raises(InputError, match="'arr_6' has the goal on an obstacle.*polarity"):
        import_maps(tmp_path / "g.npz", "gppn")
    with pytest.raises(InputError, match="split must be one of train, test, all"):
        import_maps(tmp_path / "g.npz", "kentsommer", split="valid")


def test_cli_import_exit_2_names_the_array(tmp_path, small_maps, capsys):
    np.savez(tmp_path / "bad.npz", *kentsommer_arrays(small_maps, [])[:3])
    code = main(
        [
            "maps",
            "import",
            "--format",
            "kentsommer",
            "--split",
            "train",
            str(tmp_path / "bad.npz"),
            "--out",
            str(tmp_path / "m.npz"),
        ]
    )
    assert code == 2 and "bad.npz: array 'arr_3' is missing" in capsys.readouterr().err


@pytest.mark.parametrize(
    "fmt,split",
    [("kentsommer", "test"), ("kentsommer", "train"), ("avivt", "test"), ("avivt", "train"), ("gppn", "valid")],
)
def test_export_then_import_gives_back_the_maps(tmp_path, small_maps, fmt, split, capsys):
    maps = small_maps
    maps.save(tmp_path / "in.npz")
    out = tmp_path / ("out.mat" if fmt == "avivt" else "out.npz")
    assert (
        main(
            ["maps", "export", "--format", fmt, str(tmp_path / "in.npz"), "--out", str(out), "--split", split, "--json"]
        )
        == 0
    )
    args = ["maps", "import", "--format", fmt, str(out), "--out", str(tmp_path / "back.npz"), "--json"]
    if fmt != "avivt":
        args += ["--split", split]
    if fmt == "gppn":  # no starts in GPPN files: compare the maps and their policies, not the starts
        assert main(args + ["--starts", "2"]) == 0
        back = MapSet.load(tmp_path / "back.npz")
        np.testing.assert_array_equal(back.obstacles, maps.obstacles)
        np.testing.assert_array_equal(back.goals, maps.goals)
        written = np.load(out)
        want = gppn_arrays(maps.obstacles, maps.goals)
        for i, arr in enumerate(want):
            np.testing.assert_array_equal(written[f"arr_{3 + i}"], arr)
        return
    assert main(args) == 0
    back = MapSet.load(tmp_path / "back.npz")
    assert_same_maps(back, maps)
    np.testing.assert_array_equal(back.expert.cells, maps.expert.cells)


def test_empty_splits(tmp_path, small_maps):
    write_kentsommer(tmp_path / "k.npz", small_maps, [], trajectories(small_maps))
    assert len(import_maps(tmp_path / "k.npz", "kentsommer", split="train")) == 0
    assert_same_maps(import_maps(tmp_path / "k.npz", "kentsommer", split="all"), small_maps)
    write_gppn(tmp_path / "g.npz", small_maps.obstacles, small_maps.goals, split="valid")
    assert len(import_maps(tmp_path / "g.npz", "gppn", split="test")) == 0
    got = import_maps(tmp_path / "g.npz", "gppn", split="all", starts=2)
    np.testing.assert_array_equal(got.obstacles, small_maps.obstacles)


@pytest.mark.parametrize(
    ("fmt", "moves", "held"),
    [("kentsommer", "moore", "'octile'"), ("avivt", "news", "'octile'"), ("mpd", "octile", "'moore'")],
)
def test_export_refuses_maps_of_other_movement_models(tmp_path, fmt, moves, held, capsys):
    generate_maps(3, 10, seed=1, n_starts=2, moves=moves).save(tmp_path / "m.npz")
    out = tmp_path / ("x.mat" if fmt == "avivt" else "x.npz")
    assert main(["maps", "export", str(tmp_path / "m.npz"), "--format", fmt, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"the maps use '{moves}' moves: export to {fmt} follows {held} moves only" in err and not out.exists()
