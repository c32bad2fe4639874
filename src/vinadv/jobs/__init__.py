"""Jobs of one shape: a frozen config that checks itself when made (InputError naming the field; the planner given by
its spec and weights inside it, where the job has a planner), `to_dict()` of the config, one `run(config, executor)`
and a result with `to_dict()` (what `--json` prints). A command parses its options, builds the config, runs it and
prints; where the work runs is the executor's (`vinadv.executor`: `LOCAL` by default, `vinadv.cluster.DaskExecutor`
on a cluster), which knows no job.

This package holds the jobs without an engine module of their own: `attack` (`vinadv attack`, and `attack_maps`, the
one attack call every job makes). The others keep the shape beside their engines; `JOBS` names all six.
"""

#: every job: its command, and the module holding its config, `run` and result (by name: the modules lie above this
#: package's layer, so they are named, not imported)
JOBS = {
    "run": ("vinadv.pipeline", "RunConfig", "RunSummary"),
    "attack": ("vinadv.jobs.attack", "AttackConfig", "AttackOutcome"),
    "identify": ("vinadv.identify", "IdentifyConfig", "StoredIdentification"),
    "robustness": ("vinadv.robustness", "RobustnessConfig", "RobustnessResult"),
    "bench run": ("vinadv.bench.job", "BenchConfig", "BenchResult"),
    "evaluate": ("vinadv.evaluation.job", "EvaluateConfig", "EvaluateResult"),
}

__all__ = ["JOBS"]
