"""The hypothesis profiles of tests/conftest.py: CI draws the same examples every run (issue 45)."""

import os

from hypothesis import settings


def test_the_ci_profile_is_reproducible_and_loaded_in_ci():
    ci = settings.get_profile("ci")
    assert ci.derandomize and ci.database is None and ci.print_blob
    assert settings.get_profile("dev").print_blob
    if os.environ.get("HYPOTHESIS_PROFILE") == "ci" or (
        "HYPOTHESIS_PROFILE" not in os.environ and os.environ.get("CI") == "true"
    ):
        assert settings.default.derandomize
