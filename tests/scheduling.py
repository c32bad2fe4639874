"""How `pytest -n 2` (pytest-xdist; `make test`, `make test-fast`) shares the tests between its workers.

A worker takes a whole test module at a time, so a module's fixtures (`scope="module"`: the maps, weights and runs
its tests share) are made once, not once per worker; the packages in `ONE_WORKER` go to one worker whole, for the
session fixtures their modules share (the report tests' stored runs and their classifier comparison), all but the
modules in `OWN_FIXTURES`, which use none of them: each of those is a unit of its own, so that the other worker can
take it while one runs the package.
"""

from __future__ import annotations

#: test packages whose modules share session fixtures: one worker runs all of them
ONE_WORKER = {"report"}
#: modules of a `ONE_WORKER` package that use none of its session fixtures (tests/test_scheduling.py checks)
OWN_FIXTURES = {"tests/report/test_report_baseline.py", "tests/report/test_report_planners.py"}


def scope(node_id: str) -> str:
    """The unit of work of the test `node_id`: its module, or its package where that is in `ONE_WORKER` (and the
    module not in `OWN_FIXTURES`)."""
    module = node_id.split("::", 1)[0]
    parts = module.split("/")
    if len(parts) > 2 and parts[1] in ONE_WORKER and module not in OWN_FIXTURES:
        return "/".join(parts[:2])
    return module


def make_scheduler(config, log):
    """xdist's `--dist loadscope` scheduler, with the units of `scope` (loadscope's own splits classes apart)."""
    from xdist.scheduler import LoadScopeScheduling  # noqa: PLC0415 (pytest-xdist: only where `pytest -n` runs)

    class ModuleScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return scope(nodeid)

    return ModuleScheduling(config, log)
