"""Import and export of the kentsommer, avivt and GPPN layouts.

The writers here follow the layouts as the issue and README state them, cell by cell in plain Python, so the
importers are checked against an independent reading of the layout, not against the exporters.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.io

from tests.grid.oracle import brute_distances
from tests.interop.conftest import real_file
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import MapSet, PackedPaths, generate_maps
from vinadv.interop import export_maps, import_maps, read_maps

# (d_row, d_col) in vinadv's order N,S,E,W,NE,NW,SE,SW and in GPPN's N,E,W,S,NE,NW,SE,SW, written out again here.
OURS = [(-1, 0), (1, 0), (0, 1), (0, -1), (-1, 1), (-1, -1), (1, 1), (1, -1)]
GPPN = [(-1, 0), (0, 1), (0, -1), (1, 0), (-1, 1), (-1, -1), (1, 1), (1, -1)]


def trajectories(maps, keep=None):
    """[(map, path list of (r, c))] of every start, in order; `keep(i, s)` may leave some out."""
    out = []
    for i in range(len(maps)):
        for s in range(maps.n_starts):
            if keep is None or keep(i, s):
                out.append((i, [tuple(map(int, c)) for c in maps.expert_path(i, s)]))
    return out


def kentsommer_arrays(maps, trajs, prior=0.0):
    x, s1, s2, labels = [], [], [], []
    n = maps.size
    for i, path in trajs:
        for (r, c), (r2, c2) in zip(path[:-1], path[1:]):
            img = np.zeros((2, n, n), np.float32)
            img[0] = maps.obstacles[i]
            img[1] = prior
            img[1, maps.goals[i, 0], maps.goals[i, 1]] = 10
            x.append(img)
            s1.append([r])
            s2.append([c])
            labels.append([OURS.index((r2 - r, c2 - c))])
    return [
        np.array(x).reshape(-1, 2, n, n),
        np.array(s1).reshape(-1, 1),
        np.array(s2).reshape(-1, 1),
        np.array(labels).reshape(-1, 1),
    ]


def write_kentsommer(path, maps, train_trajs, test_trajs, prior=0.0):
    np.savez(path, *kentsommer_arrays(maps, train_trajs, prior), *kentsommer_arrays(maps, test_trajs, prior))


def write_avivt_test(path, maps, trajs):
    n = maps.size
    im, value, paths = [], [], np.empty((len(trajs), 1), dtype=object)
    for row, (i, path_cells) in enumerate(trajs):
        free = np.zeros(n * n, np.uint8)
        val = np.full(n * n, -1, np.int16)
        for r in range(n):
            for c in range(n):
                free[c * n + r] = 0 if maps.obstacles[i, r, c] else 1  # column-major, as MATLAB unrolls
        val[maps.goals[i, 1] * n + maps.goals[i, 0]] = 10
        im.append(free)
        value.append(val)
        paths[row, 0] = np.array(path_cells, np.uint8) + 1
    scipy.io.savemat(path, {"all_im_data": np.array(im), "all_value_data": np.array(value), "all_states_xy": paths})


def write_avivt_train(path, maps, trajs):
    n = maps.size
    im, value, xy, labels = [], [], [], []
    for i, path_cells in trajs:
        for (r, c), (r2, c2) in zip(path_cells[:-1], path_cells[1:]):
            im.append([0 if maps.obstacles[i, rr, cc] else 1 for rr in range(n) for cc in range(n)])  # row-major
            value.append([10 if (rr, cc) == tuple(maps.goals[i]) else 0 for rr in range(n) for cc in range(n)])
            xy.append([r, c])
            labels.append([OURS.index((r2 - r, c2 - c))])
    scipy.io.savemat(
        path,
        {
            k: np.array(v, np.uint8)
            for k, v in dict(im_data=im, value_data=value, state_xy_data=xy, label_data=labels).items()
        },
    )


def gppn_policy(obstacles, goal):
    """One-hot (8, 1, n, n): BFS with every Moore move of cost 1, the lowest GPPN index among optimal actions."""
    n = len(obstacles)
    dist = {tuple(goal): 0}
    frontier = [tuple(goal)]
    while frontier:
        nxt = []
        for r, c in frontier:
            for dr, dc in GPPN:
                rr, cc = r + dr, c + dc
                if 0 <= rr < n and 0 <= cc < n and not obstacles[rr][cc] and (rr, cc) not in dist:
                    dist[(rr, cc)] = dist[(r, c)] + 1
                    nxt.append((rr, cc))
        frontier = nxt
    policy = np.zeros((8, 1, n, n), np.float32)
    for (r, c), d in dist.items():
        for a, (dr, dc) in enumerate(GPPN):
            if d > 0 and dist.get((r + dr, c + dc), math.inf) == d - 1 and 0 <= r + dr < n and 0 <= c + dc < n:
                policy[a, 0, r, c] = 1
                break
    return policy


def gppn_arrays(obstacles, goals):
    n = obstacles.shape[1]
    goal_maps = np.zeros((len(goals), 1, n, n), np.float32)
    for i, (r, c) in enumerate(goals):
        goal_maps[i, 0, r, c] = 1
    return [
        (~obstacles).astype(np.float32),
        goal_maps,
        np.array([gppn_policy(o, g) for o, g in zip(obstacles, goals)]).reshape(-1, 8, 1, n, n),
    ]


def write_gppn(path, obstacles, goals, split="test"):
    n = obstacles.shape[1]
    empty = [np.zeros((0, n, n)), np.zeros((0, 1, n, n)), np.zeros((0, 8, 1, n, n))]
    parts = {"train": empty, "valid": empty, "test": empty}
    parts[split] = gppn_arrays(obstacles, goals)
    np.savez(path, *parts["train"], *parts["valid"], *parts["test"])


def assert_same_maps(got: MapSet, want: MapSet, counts=None):
    np.testing.assert_array_equal(got.obstacles, want.obstacles)
    np.testing.assert_array_equal(got.goals, want.goals)
    mask = got.start_mask
    if counts is not None:
        np.testing.assert_array_equal(mask.sum(axis=1), counts)
    np.testing.assert_array_equal(got.starts[mask], want.starts[:, : got.n_starts][mask])
    np.testing.assert_allclose(got.expert_costs[mask], want.expert_costs[:, : got.n_starts][mask])


# ---------------------------------------------------------------------------------------------------- kentsommer


@pytest.mark.parametrize("prior", [0.0, -1.0])
def test_kentsommer_samples_regroup_into_maps_and_trajectories(tmp_path, small_maps, prior):
    train = trajectories(small_maps, keep=lambda i, s: i < 4)
    test = trajectories(small_maps, keep=lambda i, s: i >= 4)
    write_kentsommer(tmp_path / "k.npz", small_maps, train, test, prior)
    got, info = read_maps(tmp_path / "k.npz", "kentsommer", split="test")
    assert info["maps"] == 8 and info["trajectories"] == 8 * 3 and got.start_counts is None
    assert info["file_paths_optimal"] == 24
    rest = generate_maps(12, 10, seed=5, n_starts=3)
    idx = np.arange(4, 12)
    want = MapSet(
        obstacles=rest.obstacles[idx],
        goals=rest.goals[idx],
        starts=rest.starts[idx],
        expert_costs=rest.expert_costs[idx],
        expert=rest.expert,
    )
    assert_same_maps(got, want)
    everything = import_maps(tmp_path / "k.npz", "kentsommer", split="all")
    assert_same_maps(everything, small_maps)


def test_kentsommer_maps_with_fewer_trajectories_are_padded_not_dropped(tmp_path, small_maps):
    # map 2 keeps 1 trajectory, map 5 two, the others 3
    keep = {2: 1, 5: 2}
    trajs = trajectories(small_maps, keep=lambda i, s: s < keep.get(i, 3))
    write_kentsommer(tmp_path / "k.npz", small_maps, [], trajs)
    got, info = read_maps(tmp_path / "k.npz", "kentsommer")
    counts = [keep.get(i, 3) for i in range(len(small_maps))]
    assert info["maps_padded"] == 2 and got.n_starts == 3
    assert_same_maps(got, small_maps, counts=counts)
    np.testing.assert_array_equal(got.start_counts, counts)
    # padding is explicit: the goal, cost 0, and kept through save/load
    np.testing.assert_array_equal(got.starts[2, 1], got.goals[2])
    assert got.expert_costs[2, 1] == 0
    got.save(tmp_path / "m.npz")
    np.testing.assert_array_equal(MapSet.load(tmp_path / "m.npz").start_counts, counts)


def test_kentsommer_consecutive_trajectories_are_split_by_the_move_rule(tmp_path):
    # two trajectories on one map where the second starts next to where the first one was: only the labelled
    # move decides where a trajectory ends
    obstacles = np.zeros((1, 6, 6), bool)
    obstacles[0, [0, -1], :] = obstacles[0, :, [0, -1]] = True
    maps = MapSet(
        obstacles=obstacles,
        goals=np.array([[1, 4]]),
        starts=np.zeros((1, 0, 2), int),
        expert_costs=np.zeros((1, 0)),
        expert=PackedPaths.empty(),
    )
    trajs = [(0, [(4, 1), (3, 2), (2, 3), (1, 4)]), (0, [(3, 1), (2, 2), (1, 3), (1, 4)])]
    write_kentsommer(tmp_path / "k.npz", maps, [], trajs)
    got = import_maps(tmp_path / "k.npz", "kentsommer")
    np.testing.assert_array_equal(got.starts[0], [[4, 1], [3, 1]])


# ------------------------------------------------------------------------------------------------------- avivt


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


# -------------------------------------------------------------------------------------------------------- gppn


def test_gppn_borderless_mazes_get_seeded_starts(tmp_path, small_maps):
    from tests.interop.conftest import borderless

    obstacles = borderless(small_maps, seed=1)
    write_gppn(tmp_path / "g.npz", obstacles, small_maps.goals)
    got, info = read_maps(tmp_path / "g.npz", "gppn", starts=4, seed=3)
    again = import_maps(tmp_path / "g.npz", "gppn", starts=4, seed=3)
    np.testing.assert_array_equal(got.starts, again.starts)
    np.testing.assert_array_equal(got.obstacles, obstacles)
    np.testing.assert_array_equal(got.goals, small_maps.goals)
    assert "sqrt 2" in info["movement"]
    for i in range(len(got)):
        dist = brute_distances(obstacles[i].tolist(), tuple(got.goals[i]))
        real = [tuple(s) for s in got.starts[i][got.start_mask[i]]]
        assert len(set(real)) == len(real)
        for s, cell in enumerate(real):
            cost, moves = dist[cell]
            assert moves >= 2 and got.expert_costs[i, s] == pytest.approx(cost)


def test_gppn_4_actions_and_orientations_are_refused(tmp_path, small_maps):
    arrays = gppn_arrays(small_maps.obstacles, small_maps.goals)
    n = small_maps.size
    empty = [np.zeros((0, n, n)), np.zeros((0, 1, n, n)), np.zeros((0, 8, 1, n, n))]
    np.savez(tmp_path / "news.npz", *empty, *empty, arrays[0], arrays[1], arrays[2][:, :4])
    with pytest.raises(InputError, match=r"news\.npz: array 'arr_8' has 4 actions.*8 moves"):
        import_maps(tmp_path / "news.npz", "gppn")
    np.savez(tmp_path / "orient.npz", *empty, *empty, arrays[0], np.repeat(arrays[1], 2, axis=1), arrays[2])
    with pytest.raises(InputError, match="arr_7' has 2 orientations"):
        import_maps(tmp_path / "orient.npz", "gppn")


# ------------------------------------------------------------------------------------------- refusals, CLI, round trip


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


def test_padded_maps_survive_export_and_import(tmp_path, small_maps):
    keep = {0: 1, 7: 2}
    write_kentsommer(tmp_path / "k.npz", small_maps, [], trajectories(small_maps, lambda i, s: s < keep.get(i, 3)))
    padded = import_maps(tmp_path / "k.npz", "kentsommer")
    for fmt, name in (("kentsommer", "k2.npz"), ("avivt", "a.mat")):
        export_maps(padded, tmp_path / name, fmt)
        back = import_maps(tmp_path / name, fmt)
        np.testing.assert_array_equal(back.start_counts, padded.start_counts)
        assert_same_maps(back, padded, counts=padded.start_counts)


def test_evaluation_leaves_padded_starts_out(tmp_path, small_maps):
    from vinadv.planners.evaluation import evaluate_vin
    from vinadv.planners.reference import plan_reference
    from vinadv.planners.testing import planning_vin

    keep = {1: 1, 4: 2, 9: 1}
    write_kentsommer(tmp_path / "k.npz", small_maps, [], trajectories(small_maps, lambda i, s: s < keep.get(i, 3)))
    padded = import_maps(tmp_path / "k.npz", "kentsommer")
    model = planning_vin(10, seed=2)
    metrics = evaluate_vin(model, padded)
    real = [(i, s) for i in range(len(padded)) for s in range(keep.get(i, 3))]
    assert metrics["rollouts"] == len(real) == sum(metrics["terminations"].values())
    idx = np.array([i for i, _ in real])
    ref = plan_reference(
        padded.obstacles[idx], np.array([padded.starts[i, s] for i, s in real]), padded.goals[idx], model
    )
    assert metrics["success_rate"] == pytest.approx(ref.reached.mean())


def test_the_files_optimal_paths_are_kept_and_others_replaced(tmp_path):
    # 5x5 rooms, from (3, 1) to the goal (1, 3). Map 0: the file's N,N,E,E costs 4, not optimal (NE,NE costs
    # 2 sqrt 2): replaced. Map 1, centre blocked: the file's E,NE,N is optimal (2 + sqrt 2), and vinadv's tie-break
    # (lowest action index first) would take N,NE,E instead: kept as the file has it.
    obstacles = np.zeros((2, 5, 5), bool)
    obstacles[:, [0, -1], :] = obstacles[:, :, [0, -1]] = True
    obstacles[1, 2, 2] = True  # the diagonal is blocked on map 1: the optimal paths cost 2 + sqrt 2
    goals = np.array([[1, 3], [1, 3]])
    maps = MapSet(
        obstacles=obstacles,
        goals=goals,
        starts=np.zeros((2, 0, 2), int),
        expert_costs=np.zeros((2, 0)),
        expert=PackedPaths.empty(),
    )
    detour = [(3, 1), (2, 1), (1, 1), (1, 2), (1, 3)]
    optimal_1 = [(3, 1), (3, 2), (2, 3), (1, 3)]  # E, NE, N on map 1: 2 + sqrt 2
    write_kentsommer(tmp_path / "k.npz", maps, [], [(0, detour), (1, optimal_1)])
    got, info = read_maps(tmp_path / "k.npz", "kentsommer")
    assert info["file_paths_optimal"] == 1
    np.testing.assert_array_equal(got.expert_path(0), [(3, 1), (2, 2), (1, 3)])  # replaced by vinadv's
    np.testing.assert_array_equal(got.expert_path(1), optimal_1)  # kept
    assert got.expert_costs[0, 0] == pytest.approx(2 * math.sqrt(2))
    assert got.expert_costs[1, 0] == pytest.approx(2 + math.sqrt(2))


def test_empty_splits(tmp_path, small_maps):
    write_kentsommer(tmp_path / "k.npz", small_maps, [], trajectories(small_maps))
    assert len(import_maps(tmp_path / "k.npz", "kentsommer", split="train")) == 0
    assert_same_maps(import_maps(tmp_path / "k.npz", "kentsommer", split="all"), small_maps)
    write_gppn(tmp_path / "g.npz", small_maps.obstacles, small_maps.goals, split="valid")
    assert len(import_maps(tmp_path / "g.npz", "gppn", split="test")) == 0
    got = import_maps(tmp_path / "g.npz", "gppn", split="all", starts=2)
    np.testing.assert_array_equal(got.obstacles, small_maps.obstacles)


def test_gppn_policy_taking_illegal_moves_is_refused(tmp_path, small_maps):
    arrays = gppn_arrays(small_maps.obstacles, small_maps.goals)
    empty = [a[:0] for a in arrays]
    # walls and walled-off cells may hold anything: a one-hot at a wall cell is accepted
    wall = np.argwhere(small_maps.obstacles[0])[0]
    arrays[2][0, :, 0, wall[0], wall[1]] = 0
    arrays[2][0, 0, 0, wall[0], wall[1]] = 1
    np.savez(tmp_path / "ok.npz", *empty, *empty, *arrays)
    assert len(import_maps(tmp_path / "ok.npz", "gppn")) == len(small_maps)
    # a start-able cell next to the border wall whose policy points north, into the wall, is refused
    r, c = 1, int(np.flatnonzero(~small_maps.obstacles[0, 1])[0])
    arrays[2][0, :, 0, r, c] = 0
    arrays[2][0, 0, 0, r, c] = 1  # GPPN index 0 = N
    np.savez(tmp_path / "bad.npz", *empty, *empty, *arrays)
    with pytest.raises(InputError, match="'arr_8' takes an action into a wall"):
        import_maps(tmp_path / "bad.npz", "gppn")


def test_start_counts_field_is_validated(tmp_path, small_maps):
    maps = MapSet(**{**small_maps.__dict__, "start_counts": np.full(len(small_maps), 4)})
    maps.save(tmp_path / "m.npz")
    with pytest.raises(InputError, match=r"field 'start_counts' has a count outside 1\.\.3"):
        MapSet.load(tmp_path / "m.npz")
    data = dict(np.load(tmp_path / "m.npz"))
    data["start_counts"] = data["start_counts"][:3]
    np.savez(tmp_path / "short.npz", **data)
    with pytest.raises(InputError, match="field 'start_counts' has shape"):
        MapSet.load(tmp_path / "short.npz")
