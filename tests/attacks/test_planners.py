"""Every attack strategy on every kind of planner: the VIN, a GPPN, the `optimal` control and a user's own."""

import numpy as np
import pytest
import torch

from tests.attacks.test_search_planners import context
from tests.attacks.test_strategies import assert_valid
from tests.grid.oracle import brute_distances
from vinadv.attacks.pairs import PairSet
from vinadv.attacks.strategies import STRATEGIES, AttackContext, KeyPointsAttack, SaliencyAttack, make_attack
from vinadv.attacks.validity import valid_cells
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.identify import identify, rule_strength
from vinadv.planners.classical.optimal import OptimalPlanner
from vinadv.planners.gppn import GPPN, GPPNConfig
from vinadv.planners.interface import Capabilities, PlannerError, TorchPlanner
from vinadv.planners.registry import load_custom
from vinadv.planners.spec import is_planner_spec
from vinadv.planners.vin import make_input
from vinadv.planners.vin.planner import VINPlanner, as_planner
from vinadv.testing.planners import planning_vin

SIZE = 10


def _gppn() -> TorchPlanner:
    torch.manual_seed(0)
    gppn = GPPN(GPPNConfig(k=6, l_h=8))
    with torch.no_grad():  # a wider logit spread than the default initialisation: varied paths
        gppn.policy.weight.mul_(30)
    return TorchPlanner(gppn, "gppn", SIZE)


PLANNERS = {
    "vin": lambda: VINPlanner(planning_vin(SIZE, seed=1, noise=0.1), SIZE),
    "gppn": _gppn,
    "optimal": lambda: OptimalPlanner(SIZE),
    "byo-example": lambda: load_custom("examples/my_planner.py:make", SIZE),
}


@pytest.fixture(scope="module")
def maps():
    return generate_maps(12, SIZE, seed=3, n_starts=1)


@pytest.mark.parametrize("strategy", list(STRATEGIES))
@pytest.mark.parametrize("planner_name", list(PLANNERS))
def test_every_strategy_runs_on_every_planner(strategy, planner_name, maps):
    planner = PLANNERS[planner_name]()
    result = make_attack(strategy, per_map=1, seed=5, budget=4).attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, planner, strength=rule_strength
    )
    pairs = result.pairs
    assert len(pairs) > 0
    assert_valid(pairs, maps)
    assert pairs.params["planner"] == planner.spec() and is_planner_spec(planner.spec())
    # the adversarial paths are the planner's own paths on the adversarial maps
    again = planner.plan(pairs.obstacles_a, pairs.starts, pairs.goals)
    assert again.paths == pairs.path_a


@pytest.mark.parametrize("strategy", list(STRATEGIES))
def test_no_attack_on_the_optimal_planner_is_harmful(strategy, maps):
    """A perfect planner re-routes optimally: every valid pair is harmless, whatever the paper's label says."""
    result = make_attack(strategy, per_map=2, seed=1, budget=6).attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, OptimalPlanner(SIZE)
    )
    ident = identify(result.pairs)
    valid = ident.labels != "invalid"
    assert valid.any()
    assert set(ident.harm.harm[valid]) == {"harmless"}
    assert "UrP" not in set(ident.labels)


def test_saliency_on_the_vin_planner_is_the_gradient_of_the_vin_itself(maps):
    """The generic autograd path (through `Planner.logits_module`) equals the VIN's own obstacle-channel gradient."""
    vin = planning_vin(SIZE, seed=1, noise=0.1)
    planner = VINPlanner(vin, SIZE)
    obstacles, starts, goals = maps.obstacles, maps.starts[:, 0], maps.goals
    originals = planner.plan(obstacles, starts, goals)
    ctx = AttackContext(
        obstacles,
        starts,
        goals,
        valid_cells(obstacles, starts, goals, True),
        originals,
        planner,
        np.random.default_rng(0),
    )
    scores = SaliencyAttack().candidate_scores(ctx)
    # oracle: the log-probability of the chosen action at every non-goal path cell, differentiated w.r.t. the
    # obstacle channel of the VIN's own input, one map at a time
    for b in range(4):
        x = make_input(obstacles[b : b + 1], goals[b : b + 1]).requires_grad_(True)
        logits = vin.action_logits(x)[0]  # (N, N, 8)
        total = 0.0
        for r, c in originals.paths.take([b]).cells.tolist():
            if (r, c) != tuple(goals[b]):
                logp = torch.log_softmax(logits[r, c], dim=-1)
                total = total + logp[logp.detach().argmax()]
        (grad,) = torch.autograd.grad(total, x)
        np.testing.assert_allclose(scores[b], -grad[0, 0].numpy(), rtol=1e-3, atol=1e-5)  # float32 sums


def test_value_maps_per_planner(maps):
    obstacles, goals = maps.obstacles[:5], maps.goals[:5]
    # optimal: minus the exact cost-to-go (brute force), NaN on obstacles
    value = OptimalPlanner(SIZE).value_maps(obstacles, goals)
    for b in range(5):
        dist = brute_distances(obstacles[b].tolist(), tuple(goals[b]))
        for r in range(SIZE):
            for c in range(SIZE):
                d = dist[(r, c)][0] if (r, c) in dist else np.inf
                if obstacles[b, r, c] or not np.isfinite(d):
                    assert np.isnan(value[b, r, c])
                else:
                    assert value[b, r, c] == pytest.approx(-d)
    # vin: max_a q
    vin = planning_vin(SIZE, seed=1, noise=0.1)
    with torch.no_grad():
        q = vin.q_values(make_input(obstacles, goals)).max(dim=1).values.numpy()
    np.testing.assert_allclose(VINPlanner(vin, SIZE).value_maps(obstacles, goals), q, rtol=1e-5, atol=1e-6)
    # others: the log-probability of the chosen action (<= 0; at least log(1/8))
    stand_in = _gppn().value_maps(obstacles, goals)
    assert stand_in.shape == obstacles.shape
    assert np.all(stand_in <= 1e-9) and np.all(stand_in >= np.log(1 / 8) - 1e-9)


def test_saliency_without_gradients_ranks_as_key_points(maps):
    ctx = context(OptimalPlanner(SIZE), maps)
    np.testing.assert_array_equal(SaliencyAttack().candidate_scores(ctx), KeyPointsAttack().candidate_scores(ctx))


def test_as_planner():
    vin = planning_vin(SIZE, seed=1)
    assert isinstance(as_planner(vin, SIZE), VINPlanner)
    optimal = OptimalPlanner(SIZE)
    assert as_planner(optimal, SIZE) is optimal
    with pytest.raises(PlannerError, match="planner"):
        as_planner("vin", SIZE)


def test_the_planner_spec_survives_the_pairs_file_and_a_mangled_one_is_refused(maps, tmp_path):
    planner = OptimalPlanner(SIZE)
    pairs = (
        make_attack("random", per_map=1, seed=5, budget=4)
        .attack(maps.obstacles, maps.starts[:, 0], maps.goals, planner)
        .pairs
    )
    pairs.save(tmp_path / "p.npz")
    assert PairSet.load(tmp_path / "p.npz").params["planner"] == planner.spec()
    spec = planner.spec()
    for bad in ("optimal", {**spec, "size": "10"}, {k: v for k, v in spec.items() if k != "weights_sha256"}):
        pairs.params = {**pairs.params, "planner": bad}
        pairs.save(tmp_path / "bad.npz")
        with pytest.raises(InputError, match="field 'params' has a 'planner' that is not a planner spec"):
            PairSet.load(tmp_path / "bad.npz")


class _StartValues(OptimalPlanner):
    """`optimal` whose value maps read the start, as an encoder with a start channel does: plus a bump at each start
    (minus the exact cost-to-go elsewhere), so that the key-points ranking differs where the start is read."""

    capabilities = Capabilities(policy=True, value_maps=True, start_values=True)

    def value_maps(self, obstacles, goals, starts=None):
        value = super().value_maps(obstacles, goals)
        if starts is not None:
            value[np.arange(len(value)), starts[:, 0], starts[:, 1]] += 100.0
        return value


def test_key_points_give_a_planner_whose_values_read_the_start_the_starts_it_attacks(maps):
    ctx = context(_StartValues(SIZE), maps)
    scores = KeyPointsAttack().candidate_scores(ctx)
    # the ranking of the value maps read with the searches' starts, not of the goal-only maps
    told = context(OptimalPlanner(SIZE), maps)
    told_value = _StartValues(SIZE).value_maps(ctx.obstacles, ctx.goals, ctx.starts)
    told.planner.value_maps = lambda obstacles, goals: told_value
    np.testing.assert_array_equal(scores, KeyPointsAttack().candidate_scores(told))
    assert not np.array_equal(scores, KeyPointsAttack().candidate_scores(context(OptimalPlanner(SIZE), maps)))
