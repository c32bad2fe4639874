"""The avivt layout: test and training layouts, on our maps and on the real files."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io

from tests.interop.conftest import real_file
from tests.interop.formats.layouts import assert_same_maps, trajectories, write_avivt_test, write_avivt_train
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import PackedPaths
from vinadv.interop import import_maps, read_maps


def test_avivt_test_layout(tmp_path, small_maps):
    write_avivt_test(tmp_path / "a.mat", small_maps, trajectories(small_maps))
    got, info = read_maps(tmp_path / "a.mat", "avivt")
    assert info["layout"] == "test" and info["maps"] == 12
    assert_same_maps(got, small_maps)


def test_avivt_training_layout(tmp_path, small_maps):
    write_avivt_train(tmp_path / "a.mat", small_maps, trajectories(small_maps, keep=lambda i, s: (i, s) != (3, 2)))
    got, info = read_maps(tmp_path / "a.mat", "avivt")
    assert info["layout"] == "train"
    assert_same_maps(got, small_maps, counts=[2 if i == 3 else 3 for i in range(12)])


def test_real_vin_paper_test_maps():
    got, info = read_maps(real_file("gridworld_28_test.mat"), "avivt")
    assert (info["maps"], info["size"], info["trajectories"]) == (1000, 28, 1000)
    # read column-major, every path stays on free cells and ends at the goal; all are optimal under our model
    assert info["file_paths_optimal"] == 1000
    raw = scipy.io.loadmat(real_file("gridworld_28_test.mat"))
    for i in (0, 17, 999):  # spot checks against the raw arrays, read here by hand
        path = raw["all_states_xy"][i, 0].astype(int) - 1
        np.testing.assert_array_equal(got.starts[i, 0], path[0])
        assert raw["all_value_data"][i, path[-1][1] * 28 + path[-1][0]] == 10
        assert got.expert_costs[i, 0] == pytest.approx(float(PackedPaths.pack([path]).costs()[0]))
    assert got.obstacles[:, 0].all() and got.obstacles[:, :, -1].all()
    assert 0.25 < got.obstacles.mean() < 0.4


def test_real_8x8_training_layout():
    got, info = read_maps(real_file("gridworld_8.mat"), "avivt")
    raw = scipy.io.loadmat(real_file("gridworld_8.mat"))
    assert info["samples"] == len(raw["label_data"]) == 70924
    # every sample is one step: samples = sum over trajectories of (cells - 1)
    assert info["file_paths_optimal"] == info["trajectories"]
    # all optimal, so our expert paths have the file's number of moves: samples = sum of (cells - 1)
    real = got.start_mask.reshape(-1)
    assert info["samples"] == int(got.expert.lengths[real].sum() - real.sum())
    assert got.size == 8 and got.start_mask.sum() == info["trajectories"]


def test_real_8x8_batched_arrays_alone_give_maps_with_drawn_starts(tmp_path):
    raw = scipy.io.loadmat(real_file("gridworld_8.mat"))
    scipy.io.savemat(
        tmp_path / "b.mat",
        {k: raw[k] for k in ("batch_im_data", "batch_value_data", "state_x_data", "state_y_data", "batch_label_data")},
    )
    per_sample = import_maps(real_file("gridworld_8.mat"), "avivt")
    got, info = read_maps(tmp_path / "b.mat", "avivt", starts=2, seed=4)
    assert "starts drawn" in info["layout"] and info["maps"] == len(per_sample)
    np.testing.assert_array_equal(got.obstacles, per_sample.obstacles)  # same maps, same order, both readings
    np.testing.assert_array_equal(got.goals, per_sample.goals)


def test_an_empty_mat_file_is_one_line(tmp_path):
    (tmp_path / "empty.mat").write_bytes(b"")
    with pytest.raises(InputError, match="empty.mat: not a readable MATLAB .mat file"):
        read_maps(tmp_path / "empty.mat", "avivt")


@pytest.mark.parametrize(
    "write,renamed",
    [
        (write_avivt_test, "all_im_data"),
        (write_avivt_test, "all_value_data"),
        (write_avivt_train, "im_data"),
        (write_avivt_train, "state_xy_data"),
    ],
)
def test_a_missing_array_is_named_for_the_layout_the_file_has(tmp_path, small_maps, write, renamed):
    write(tmp_path / "a.mat", small_maps, trajectories(small_maps))
    arrays = {k: v for k, v in scipy.io.loadmat(tmp_path / "a.mat").items() if not k.startswith("__")}
    arrays["renamed_" + renamed] = arrays.pop(renamed)
    scipy.io.savemat(tmp_path / "b.mat", arrays)
    with pytest.raises(InputError, match=f"array '{renamed}' is missing"):
        read_maps(tmp_path / "b.mat", "avivt")


def test_a_file_of_neither_layout_names_both(tmp_path):
    scipy.io.savemat(tmp_path / "c.mat", {"something": np.zeros((2, 64))})
    with pytest.raises(InputError, match="none of the arrays of avivt's layouts .*all_im_data.*im_data"):
        read_maps(tmp_path / "c.mat", "avivt")


def test_a_file_of_no_maps_is_read_but_not_imported(tmp_path, capsys):
    paths = np.empty((0, 1), dtype=object)  # a MATLAB cell array of no paths
    scipy.io.savemat(
        tmp_path / "z.mat",
        {"all_im_data": np.zeros((0, 64)), "all_value_data": np.zeros((0, 64)), "all_states_xy": paths},
    )
    assert len(read_maps(tmp_path / "z.mat", "avivt")[0]) == 0
    out = tmp_path / "z.npz"
    assert main(["maps", "import", str(tmp_path / "z.mat"), "--format", "avivt", "--out", str(out), "--quiet"]) == 2
    assert capsys.readouterr().err == f"vinadv: error: {tmp_path / 'z.mat'}: no maps to import\n"
    assert not out.exists()
