"""`vinadv.planners.check_planner`: every registered planner that loads cheaply passes (and its declared capabilities
are what each family offers); hand-made broken planners, each wrong in one way, are refused in one line naming it."""

from pathlib import Path

import numpy as np
import pytest
import torch

from vinadv.planners import check_planner
from vinadv.planners.interface import Capabilities, Planner, PlannerError, TorchPlanner
from vinadv.planners.registry import load_planner
from vinadv.planners.search import SearchPlanner, SearchResult, UserSearchPlanner
from vinadv.planners.vin.model import VINPolicy
from vinadv.planners.vin.planner import VINPlanner
from vinadv.testing.planners import planning_vin

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "my_search_planner.py"
SIZE = 8

#: each family's declaration: (policy, value_maps, gradients, expansions)
DECLARED = {
    "vin": Capabilities(policy=True, value_maps=True, gradients=True),
    "optimal": Capabilities(policy=True, value_maps=True),
    "astar": Capabilities(expansions=True),
    "wastar": Capabilities(expansions=True),
}


@pytest.mark.parametrize("name", sorted(DECLARED))
def test_every_cheap_registered_planner_passes_and_declares_what_its_family_offers(name):
    planner = load_planner(name, 28)
    assert check_planner(planner) is planner
    assert planner.capabilities == DECLARED[name]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("spec", "size", "moves", "declared"),
    [
        ("gppn", 28, "octile", Capabilities(policy=True, gradients=True)),
        ("vin+d4", 28, "octile", Capabilities(policy=True, gradients=True)),
        (
            "neural-astar",
            32,
            "moore",
            Capabilities(value_maps=True, gradients=True, expansions=True, start_values=True),
        ),
    ],
)
def test_the_torch_planners_pass_too(spec, size, moves, declared):
    planner = check_planner(load_planner(spec, size, moves=moves))
    assert planner.capabilities == declared


def test_a_user_search_planner_passes_whether_loaded_wrapped_or_given_as_its_object():
    loaded = load_planner(f"{EXAMPLE}:make", SIZE)
    assert check_planner(loaded).capabilities == Capabilities(expansions=True)
    obj = loaded.impl
    wrapped = check_planner(obj, SIZE)
    assert isinstance(wrapped, UserSearchPlanner) and wrapped.size == SIZE
    with pytest.raises(PlannerError, match="give its map side"):
        check_planner(obj)


def test_a_small_vin_and_a_torch_module_pass():
    vin = planning_vin(SIZE, k=10)
    assert check_planner(VINPlanner(vin, SIZE)).capabilities.value_maps
    module = VINPolicy(vin).eval()  # the VIN with the bring-your-own forward(obstacles, goals)
    assert check_planner(module, SIZE).capabilities == Capabilities(policy=True, gradients=True)


class Straight:
    """A search planner's object: the start alone (no path found); what it declares and answers is set per test."""

    moves = "octile"

    def __init__(self, expanded=False, capabilities=None, paths=None):
        self.expanded, self.paths = expanded, paths
        if capabilities is not None:
            self.capabilities = capabilities

    def plan_paths(self, obstacles, starts, goals, corner_cutting=True):
        paths = self.paths(starts) if self.paths else [s[None] for s in starts]
        expanded = np.zeros(obstacles.shape, bool) if self.expanded else None
        return SearchResult.from_paths(paths, goals, expanded=expanded)


class Policy(Planner):
    """A policy planner: uniform logits, unless a test breaks it."""

    name, size = "policy", SIZE

    def __init__(self, logits=None, value=None, capabilities=None, module=None):
        self._logits, self._value, self._module = logits, value, module
        if capabilities is not None:
            self.capabilities = capabilities

    def policy_logits(self, obstacles, goals):
        return self._logits(obstacles) if self._logits else np.zeros((len(obstacles), 8, SIZE, SIZE), np.float32)

    def value_maps(self, obstacles, goals):
        return self._value(obstacles) if self._value else super().value_maps(obstacles, goals)

    @property
    def logits_module(self):
        return self._module


class Wide(torch.nn.Module):
    """A module that answers one logit map too few (7 actions)."""

    def forward(self, obstacles, goals):
        return obstacles[:, None].repeat(1, 7, 1, 1)


class Blocked(SearchPlanner):
    """A search planner that jumps from its start straight to its goal."""

    name, size = "blocked", SIZE

    def plan_paths(self, obstacles, starts, goals, corner_cutting=True):
        return SearchResult.from_paths([np.stack([s, g]) for s, g in zip(starts, goals)], goals)


def nan_logits(obstacles):
    return np.full((len(obstacles), 8, SIZE, SIZE), np.nan, np.float32)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: 42, r"planner 'int': a int is not a planner"),
        (lambda: UserSearchPlanner(Straight(expanded=True), "undeclared", SIZE), "'undeclared' reports expanded cells"),
        (
            lambda: UserSearchPlanner(Straight(capabilities={"expansions": True}), "claims", SIZE),
            "'claims' declares expansions, but plan reported no expanded cells",
        ),
        (lambda: Policy(logits=nan_logits), "planner 'policy' returned NaN logits"),
        (
            lambda: Policy(value=lambda obstacles: np.zeros(obstacles.shape[:2])),
            r"'policy': value_maps returned shape \(3, 8\)",
        ),
        (lambda: Policy(capabilities=Capabilities(policy=True, gradients=True)), "'policy' declares gradients, but"),
        (lambda: Policy(module=Wide()), r"'policy' offers a module \(differentiable\) but does not declare gradients"),
        (
            lambda: Policy(capabilities=Capabilities(policy=True, gradients=True), module=Wide()),
            r"its differentiable module gave \(3, 7, 8, 8\)",
        ),
        (lambda: TorchPlanner(Wide(), "wide", SIZE), r"'wide' returned logits of shape \(3, 7, 8, 8\)"),
        (lambda: Blocked(), "'blocked' returned a path for row 0 that moves from"),
        (lambda: UserSearchPlanner(Straight(capabilities={"speed": True}), "odd", SIZE), "'odd': capabilities"),
    ],
)
def test_a_broken_planner_is_refused_in_one_line_naming_it(make, message):
    with pytest.raises(PlannerError, match=message) as caught:
        check_planner(make())
    assert "\n" not in str(caught.value)


def test_a_bad_name_size_or_movement_model_is_refused():
    for attribute, value, message in [
        ("name", "", "its name must be a non-empty string"),
        ("size", 3, "its size 3 must be an int >= 8"),
        ("moves", "hex", "its moves 'hex'"),
        ("capabilities", {"policy": True}, "capabilities is dict, not a Capabilities"),
    ]:
        planner = Policy()
        setattr(planner, attribute, value)
        with pytest.raises(PlannerError, match=message):
            check_planner(planner)
