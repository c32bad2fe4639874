"""The planner interface: the generic rollout against the per-step reference rule and the VIN engine, every
registered planner batched vs one by one, and planners that break the contract refused by name."""

import numpy as np
import pytest
import torch
from torch import nn

from tests.grid.oracle import brute_distances
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps, optimal_actions, shortest_distances
from vinadv.grid.shortest_paths import valid_moves
from vinadv.planners.classical.optimal import OptimalPlanner
from vinadv.planners.gppn import GPPN, GPPNConfig
from vinadv.planners.interface import PlannerError, TorchPlanner, check_logits
from vinadv.planners.registry import load_custom
from vinadv.planners.result import step_limits
from vinadv.planners.rollout import multi_start_limits, rollout_logits
from vinadv.planners.symmetric import DihedralAverage
from vinadv.planners.vin import make_input
from vinadv.planners.vin.engine import plan_maps as engine_plan_maps
from vinadv.planners.vin.planner import VINPlanner
from vinadv.planners.vin.reference import rollout
from vinadv.testing.planners import planning_vin
from vinadv.vocabulary import COLLISION


def assert_same(a, b):
    assert a.paths == b.paths
    np.testing.assert_array_equal(a.termination, b.termination)
    np.testing.assert_array_equal(a.reached, b.reached)


@pytest.mark.parametrize("corner_cutting", [True, False])
def test_rollout_follows_the_reference_rule_on_arbitrary_logits(corner_cutting):
    # random logits: every ending occurs; the oracle is the reference planner's per-step Python rule
    maps = generate_maps(60, 12, seed=7, n_starts=3, corner_cutting=corner_cutting)
    rng = np.random.default_rng(0)
    logits = rng.normal(size=(60, 8, 12, 12)).astype(np.float32)
    logits[:20] = np.round(logits[:20])  # many exact ties: the lowest index must win
    got = rollout_logits(logits, maps.obstacles, maps.goals, maps.starts, corner_cutting)
    seen = set()
    for b in range(60):
        for s in range(3):
            limit = step_limits(
                maps.obstacles[b : b + 1], maps.starts[b : b + 1, s], maps.goals[b : b + 1], corner_cutting
            )[0]

            def action_at(r, c, b=b):
                return int(np.argmax(logits[b, :, r, c]))  # the first of tied maxima

            path, term = rollout(
                action_at, maps.obstacles[b], maps.starts[b, s], maps.goals[b], int(limit), corner_cutting
            )
            t = b * 3 + s
            np.testing.assert_array_equal(got.paths[t], np.array(path).reshape(-1, 2))
            assert got.termination[t] == term
            seen.add(term)
    assert {0, 1, 2} <= seen  # goal, collision, loop at least


@pytest.mark.parametrize("moves", ["octile", "moore", "news"])
def test_rollout_follows_the_movement_model(moves):
    """On expert logits of the maps' model the rollout walks the expert paths; on `news` it never takes a diagonal
    however high its logit (the argmax is over the model's actions); the step limits are 2 L of the model (plain-
    Python oracle)."""
    maps = generate_maps(30, 10, seed=4, n_starts=3, moves=moves)
    dist, _ = shortest_distances(maps.obstacles, maps.goals, True, moves)
    logits = optimal_actions(dist, maps.obstacles, True, moves).transpose(0, 3, 1, 2).astype(np.float32)
    if moves == "news":
        logits[:, 4:] = 5.0
    got = rollout_logits(logits, maps.obstacles, maps.goals, maps.starts, moves=moves)
    assert got.paths == maps.expert and got.reached.all()
    limits = multi_start_limits(maps.obstacles, maps.goals, maps.starts, True, moves)
    for b in range(5):
        best = brute_distances(maps.obstacles[b].tolist(), tuple(maps.goals[b]), True, moves)
        for s in range(3):
            assert limits[b, s] == 2 * best[tuple(maps.starts[b, s])][1]
            assert (
                step_limits(maps.obstacles[b : b + 1], maps.starts[b : b + 1, s], maps.goals[b : b + 1], True, moves)[0]
                == limits[b, s]
            )


def test_step_limit_ending():
    # a policy that walks a cycle of 4 distinct cells is a loop; one that snakes forever hits the limit
    obstacles = np.zeros((1, 7, 7), bool)
    obstacles[0, [0, -1], :] = obstacles[0, :, [0, -1]] = True
    logits = np.zeros((1, 8, 7, 7), np.float32)
    logits[0, 2] = 1.0  # East everywhere: from (3, 1) towards a goal on row 1 it never turns
    res = rollout_logits(logits, obstacles, np.array([[1, 5]]), np.array([[[3, 1]]]), limits=np.array([[3]]))
    assert res.termination_names[0] == "step_limit" and len(res.paths[0]) == 4


def _vin_logits_per_map(model, obstacles, goals):
    with torch.no_grad():
        return model.action_logits(make_input(obstacles, goals)).permute(0, 3, 1, 2).numpy()


@pytest.mark.parametrize("size", [16, 28])
def test_generic_rollout_on_vin_logits_gives_the_engines_paths(size):
    maps = generate_maps(40, size, seed=3, n_starts=2)
    model = planning_vin(size, seed=1)
    logits = _vin_logits_per_map(model, maps.obstacles, maps.goals)
    generic = rollout_logits(logits, maps.obstacles, maps.goals, maps.starts)
    engine = engine_plan_maps(maps.obstacles, maps.goals, maps.starts, model)
    # exact equality wherever no cell of the engine's path is a near tie (batched torch rounds differently)
    top2 = np.sort(logits, axis=1)[:, -2:]
    gap = top2[:, 1] - top2[:, 0]
    compared = 0
    for t in range(len(engine)):
        b = t // 2
        cells = engine.paths[t]
        if (gap[b][cells[:, 0], cells[:, 1]] < 1e-3).any():
            continue
        compared += 1
        np.testing.assert_array_equal(generic.paths[t], cells)
        assert generic.termination[t] == engine.termination[t]
    assert compared >= 0.9 * len(engine)


def _planners(size):
    torch.manual_seed(0)
    gppn = GPPN(GPPNConfig(k=6, l_h=8))
    # the averaged one sees the whole map (a 5x5 kernel, 10 steps): a mirror-symmetric patch inside a smaller view
    # would tie two actions up to the rounding of each forward, which differs with the batch
    wide = GPPN(GPPNConfig(k=10, l_h=8, f=5))
    with torch.no_grad():  # a wider logit spread than the default initialisation: longer, varied paths
        gppn.policy.weight.mul_(30)
        wide.policy.weight.mul_(30)
    return [
        VINPlanner(planning_vin(size, seed=2), size=size),
        OptimalPlanner(size),
        TorchPlanner(gppn, "gppn", size),
        load_custom("examples/my_planner.py:make", size),
        TorchPlanner(DihedralAverage(wide), "gppn+d4", size),
    ]


@pytest.mark.parametrize("index", range(5), ids=["vin", "optimal", "gppn", "byo-example", "gppn+d4"])
def test_every_planner_batched_equals_one_by_one(index):
    maps = generate_maps(12, 16, seed=9, n_starts=3)
    planner = _planners(16)[index]
    batched = planner.plan(maps.obstacles, maps.starts, maps.goals, chunk_size=5)
    for b in range(len(maps)):
        for s in range(3):
            one = planner.plan(maps.obstacles[b : b + 1], maps.starts[b : b + 1, s], maps.goals[b : b + 1])
            np.testing.assert_array_equal(one.paths[0], batched.paths[b * 3 + s])
            assert one.termination[0] == batched.termination[b * 3 + s]
    spec = planner.spec()
    assert spec["name"] == planner.name and spec["size"] == 16
    assert (spec["weights_sha256"] is None) == (planner.name == "optimal")


class Broken(nn.Module):
    def __init__(self, mode):
        super().__init__()
        self.mode = mode
        self.w = nn.Parameter(torch.ones(1))

    def forward(self, obstacles, goals):
        b, n = obstacles.shape[0], obstacles.shape[-1]
        if self.mode == "shape":
            return torch.zeros(b, 4, n, n)
        if self.mode == "nan":
            out = torch.zeros(b, 8, n, n)
            out[0, 3, 2, 2] = float("nan")
            return out
        if self.mode == "int":
            return torch.zeros(b, 8, n, n, dtype=torch.int64)
        if self.mode == "-inf everywhere":  # every move of every cell of the first map
            out = torch.zeros(b, 8, n, n)
            out[0] = float("-inf")
            return out
        if self.mode == "-inf on illegal moves":  # masking as a planner may: every move that is not legal
            legal = valid_moves(obstacles.numpy().astype(bool))
            return torch.from_numpy(np.where(legal, 0.0, -np.inf).transpose(0, 3, 1, 2).astype(np.float32))
        if self.mode in ("+inf", "-inf"):  # at one cell of the last map
            out = torch.zeros(b, 8, n, n)
            out[-1, 3, 2, 2] = float(self.mode)
            return out
        if self.mode == "meta":
            return torch.zeros(b, 8, n, n, device="meta")
        raise RuntimeError("boom")


@pytest.mark.parametrize(
    "mode,message",
    [
        ("shape", r"logits of shape \(3, 4, 8, 8\); expected \(B, 8, N, N\)"),
        ("nan", "NaN logits"),
        ("int", "torch.int64 logits"),
        ("meta", "logits on the 'meta' device, which holds no values"),
        ("+inf", r"returned \+inf logits \(on 1 of 3 maps\)"),
        ("-inf everywhere", r"-inf logits for every legal move of cell \(\d+, \d+\) of map 0, which can reach"),
        ("raise", "forward failed: RuntimeError: boom"),
    ],
)
def test_a_planner_that_breaks_the_contract_is_refused_by_name(mode, message):
    maps = generate_maps(3, 8, seed=1, n_starts=1)
    planner = TorchPlanner(Broken(mode), "my-broken", 8)
    with pytest.raises(PlannerError, match="planner 'my-broken'.*" + message):
        planner.plan(maps.obstacles, maps.starts, maps.goals)
    assert issubclass(PlannerError, InputError)


class BatchRecorder(nn.Module):
    """Logits that say which map they came from, and the size of every batch it was called with."""

    def __init__(self):
        super().__init__()
        self.sizes = []

    def forward(self, obstacles, goals):
        self.sizes.append(len(obstacles))  # list.append is atomic: the planner's threads may call at once
        return (obstacles.sum(dim=(1, 2)) + 100 * goals[:, 0])[:, None, None, None].expand(-1, 8, *obstacles.shape[1:])


@pytest.mark.parametrize("b", [5, 16, 47, 300])
def test_cpu_forwards_take_16_to_31_maps_and_each_map_its_own_logits(b):
    maps = generate_maps(b, 8, seed=2, n_starts=1)
    module = BatchRecorder()
    logits = TorchPlanner(module, "recorder", 8).policy_logits(maps.obstacles, maps.goals)
    expected = maps.obstacles.sum(axis=(1, 2)) + 100 * maps.goals[:, 0]
    np.testing.assert_array_equal(logits[:, 3, 2, 1], expected)
    assert sum(module.sizes) == b
    assert all(16 <= size < 32 for size in module.sizes) if b >= 16 else module.sizes == [b]


@pytest.mark.parametrize("mode", ["-inf", "-inf on illegal moves"])
def test_minus_infinity_masks_a_move(mode):
    maps = generate_maps(3, 8, seed=1, n_starts=1)
    result = TorchPlanner(Broken(mode), "masking", 8).plan(maps.obstacles, maps.starts, maps.goals)
    assert len(result) == 3
    if mode == "-inf on illegal moves":
        assert not (result.termination == COLLISION).any()  # only legal moves were left to take


def test_check_logits_numpy_and_sizes():
    with pytest.raises(PlannerError, match="returned list"):
        check_logits("p", [[0.0]], 1, 4)
    assert check_logits("p", np.zeros((1, 8, 4, 4), np.float16), 1, 4).dtype == np.float32
    maps = generate_maps(2, 8, seed=1, n_starts=1)
    with pytest.raises(PlannerError, match="planner 'optimal' is for 16x16 maps, the maps are 8x8"):
        OptimalPlanner(16).plan(maps.obstacles, maps.starts, maps.goals)


def test_cli_refuses_a_broken_planner_with_exit_2(tmp_path, capsys):
    (tmp_path / "bad.py").write_text("import torch\n\ndef make(size):\n    return torch.nn.Conv2d(1, 4, 1)\n")
    generate = [
        "maps",
        "generate",
        "--n",
        "3",
        "--size",
        "8",
        "--seed",
        "1",
        "--out",
        str(tmp_path / "m.npz"),
        "--quiet",
    ]
    assert main(generate) == 0
    code = main(
        [
            "plan",
            "--maps",
            str(tmp_path / "m.npz"),
            "--out",
            str(tmp_path / "p.npz"),
            "--quiet",
            "--planner",
            f"{tmp_path / 'bad.py'}:make",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and "bad.py:make" in err and "Traceback" not in err


def test_bad_starts_are_refused():
    maps = generate_maps(2, 8, seed=1, n_starts=2)
    planner = OptimalPlanner(8)
    with pytest.raises(InputError, match=r"starts has shape \(2, 2\), expected \(2, S, 2\)"):
        planner.plan_maps(maps.obstacles, maps.goals, maps.starts[:, 0])
    with pytest.raises(InputError, match="starts has a cell outside the 8x8 grid"):
        planner.plan_maps(maps.obstacles, maps.goals, maps.starts + 8)
    with pytest.raises(InputError, match="goals has shape"):
        planner.plan_maps(maps.obstacles, maps.goals[:1], maps.starts)
    with pytest.raises(InputError, match=r"starts has shape \(2, 2, 2, 1\), expected \(2, S, 2\)"):
        planner.plan(maps.obstacles, maps.starts[..., None], maps.goals)


@pytest.mark.parametrize("index", range(2), ids=["vin", "optimal"])
def test_the_deprecated_calls_are_plan_in_the_old_argument_orders(index):
    maps = generate_maps(4, 16, seed=2, n_starts=2)
    planner = _planners(16)[index]
    many = planner.plan(maps.obstacles, maps.starts, maps.goals, maps.corner_cutting, maps.moves)
    assert_same(planner.plan_maps(maps.obstacles, maps.goals, maps.starts, maps.corner_cutting), many)
    one = planner.plan(maps.obstacles, maps.starts[:, 1], maps.goals)
    assert_same(planner.plan_batch(maps.obstacles, maps.starts[:, 1], maps.goals), one)
    assert_same(one, many.take(np.arange(1, 8, 2)))


def test_plan_refuses_maps_of_another_movement_model_in_one_line():
    maps = generate_maps(2, 8, seed=1, n_starts=1)
    with pytest.raises(PlannerError, match=r"planner 'optimal' plans octile moves .*; the maps use 'news' moves"):
        OptimalPlanner(8).plan(maps.obstacles, maps.starts, maps.goals, True, "news")
