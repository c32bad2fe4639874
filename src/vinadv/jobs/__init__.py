"""Jobs of one shape that have no engine module of their own: a frozen config that checks itself (the planner given
by its spec inside it), one `run(config, executor)` and a result with `to_dict()`.

`attack` is `vinadv attack` (and the one attack call every job makes: `attack_maps`). The other jobs keep that shape
beside their engines: `vinadv.pipeline` (`RunConfig`, `run`), `vinadv.robustness` (`RobustnessConfig`, `run`),
`vinadv.bench.job` (`BenchConfig`, `run`). Where the work runs is the executor's (`vinadv.executor`).
"""
