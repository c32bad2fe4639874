"""The planner the attack tests attack: a noisy synthetic VIN (`planning_vin`, seed 1, noise 0.1), whose plans an
attack can break, for the maps of the test module that asks for it (its `SIZE`)."""

import pytest

from vinadv.testing.planners import planning_vin


@pytest.fixture(scope="module")
def model(request):
    return planning_vin(request.module.SIZE, seed=1, noise=0.1)
