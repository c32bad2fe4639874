"""The planner's quality: as the evaluation stage measured it on the run's own maps and stored it
(`vinadv.evaluation.planner_quality`), beside how the run's original paths ended.

The rows follow what the planner declares (`Capabilities`, stored with the measurement): every planner gets the
rollout figures (success, % optimal, mean extra cost); action accuracy only a planner with a policy at every cell;
the search figures (Opt, Exp, Hmean, expansions beside A*'s) only a planner that reports its expansions; the value-map
figure only a planner with value maps of its own. A run not evaluated (or whose planner is not on this machine)
declares nothing, so it gets the rows every planner has. The CSV is `planner_quality.csv`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vinadv.report.data import Context, Figure, Table
from vinadv.vocabulary import PLANNER_QUALITY

#: the stored quality figures every planner has, in the table's order
KEYS = ("success_rate", "optimal_rate", "optimal_rate_of_reached", "mean_extra_cost", "maps", "starts_per_map")
#: the figure of a planner with a policy at every cell (`Capabilities.policy`)
POLICY_KEYS = ("action_accuracy",)
#: the search figures of a planner that reports its expansions (`Capabilities.expansions`: `search_metrics`)
SEARCH_KEYS = ("opt", "exp", "hmean", "expansions", "astar_expansions")


@dataclass
class PlannerData:
    """`evaluated`: the evaluation stage stored the planner's quality (else `source` is None and `metrics` empty);
    `source`: where the stored metrics come from, or why there are none; `capabilities`: what the planner declared
    (`{}` when unknown); `search`: its search figures where it reports expansions, else None; `figure`: its value map
    on the first map measured, where it has value maps."""

    run_id: int
    url: str
    evaluated: bool
    source: str | None
    metrics: dict
    capabilities: dict
    search: dict | None
    terminations: dict[str, int]
    reached: int
    total: int
    table: Table
    figure: Figure | None = None

    def tables(self) -> list[Table]:
        return [self.table]

    def figures(self) -> list[Figure]:
        return [] if self.figure is None else [self.figure]


def gather(ctx: Context) -> PlannerData:
    stored = ctx.store.read_measurement(ctx.run_id, PLANNER_QUALITY)
    metrics = (stored or {}).get("metrics") or {}
    capabilities = (stored or {}).get("capabilities") or {}
    search = (stored or {}).get("search") if capabilities.get("expansions") else None
    terms = ctx.store.termination_counts(ctx.run_id, "o")
    total, reached = sum(terms.values()), terms.get("goal", 0)
    keys = [*KEYS[:3], *(POLICY_KEYS if capabilities.get("policy") else ()), *KEYS[3:]]
    table = Table(
        "planner_quality.csv",
        ("figure", "value"),
        [[k, metrics.get(k)] for k in keys]
        + [[f"search_{k}", search.get(k)] for k in SEARCH_KEYS if search is not None]
        + [["run_original_paths", total], ["run_original_paths_reaching_goal", reached]]
        + [[f"run_original_paths_ended_by_{k}", v] for k, v in terms.items()],
    )
    figure = None
    value_map = (stored or {}).get("value_map") if capabilities.get("value_maps") else None
    if value_map:
        figure = _value_map_figure(ctx, value_map, (stored.get("planner") or {}).get("name"))
    return PlannerData(
        run_id=ctx.run_id,
        url=ctx.store.url,
        evaluated=stored is not None,
        source=None if stored is None else stored["source"],
        metrics=metrics,
        capabilities=capabilities,
        search=search,
        terminations=terms,
        reached=reached,
        total=total,
        table=table,
        figure=figure,
    )


def _value_map_figure(ctx: Context, value_map: dict, planner: str | None) -> Figure:
    """The stored value map drawn on its map (the original map of the pair it names, read from the store)."""
    from vinadv.plot.maps import value_map as draw_value_map  # noqa: PLC0415 (Matplotlib: drawn when gathered)
    from vinadv.report.figures import save  # noqa: PLC0415 (Matplotlib, as above)

    pair = ctx.store.read_pairs(ctx.run_id, pair_indices=np.array([value_map["pair_index"]]))
    values = np.array([[np.nan if v is None else v for v in row] for row in value_map["values"]], dtype=np.float64)
    fig = draw_value_map(values, pair.obstacles_o[0], pair.goals[0], pair.starts[0], title=f"pair {pair.pair_index[0]}")
    return Figure(
        tuple(save(fig, ctx.out / "fig_planner_value_map")),
        f"The value map of planner {planner or '?'} on the original map of pair {int(pair.pair_index[0])} (the first "
        "map its quality was measured on), as the planner computes it (Planner.value_maps); obstacles drawn on top.",
        "the planner's value map",
        420,
    )
