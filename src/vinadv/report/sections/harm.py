"""Harm: worse paths, or only different ones?"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from vinadv.classify.harm import DEFAULT_TOL, harm_summary
from vinadv.grid.shortest_paths import expert_paths
from vinadv.plot.palette import PALETTE
from vinadv.records import run_config_kind
from vinadv.report.data import ALL_LABELS, Context, Figure, Table
from vinadv.vocabulary import HARMS, SUCCESS_LABELS

#: the example kinds of the harm section, `(label, harm)`: a fork the planner was right to take, a detour that hurt
HARM_EXAMPLES = (("FP", "harmless"), ("DP", "harmful"))
#: pairs shown per example kind
HARM_EXAMPLES_SHOWN = 4
#: the labels of the regret histogram (both paths reach the goal, so both regrets exist)
REGRET_LABELS = ("FP", "DP")
#: at most this many histogram bins: the bin width is the smallest of `_BIN_WIDTHS` that keeps to it
_MAX_BINS = 40
_BIN_WIDTHS = (0.05, 0.1, 0.125, 0.25, 0.5, 1.0, 2.0, 2.5, 5.0, 10.0, 20.0, 25.0, 50.0, 100.0)
NOT_COMPUTED = "not computed"


@dataclass(frozen=True)
class HarmExample:
    """One pair of the harm examples: its stored label, harm and costs (cost units) and the expert (optimal,
    DESIGN.md tie-break) paths recomputed for the figure, `((row, col), ...)` on each map, with their costs."""

    pair_index: int
    label: str
    harm: str
    expert_label: str | None
    cost_o: float
    opt_cost_o: float
    regret_o: float
    cost_a: float
    opt_cost_a: float
    regret_a: float
    expert_path_o: tuple[tuple[int, int], ...]
    expert_path_a: tuple[tuple[int, int], ...]
    expert_cost_o: float
    expert_cost_a: float

    @property
    def change(self) -> float:
        """`regret_a - regret_o`: the regret the attack added."""
        return self.regret_a - self.regret_o


@dataclass(frozen=True)
class RegretChanges:
    """The regret change `regret_a - regret_o` of one label's pairs (those with both regrets): how many pairs are
    harmful / harmless, how many lost (`improved`, change < -tol), kept (`same`, |change| <= tol) or added
    regret (`added`, change > tol), the mean and the largest change."""

    label: str
    pairs: int
    harmful: int
    harmless: int
    improved: int
    same: int
    added: int
    mean: float | None
    largest: float | None


@dataclass
class HarmData:
    """The harm section of the main run. `available`: some pair of the run has harm stored (a run whose pairs hold
    no harm: then every other field is empty). `counts`: {label: {harm: pairs}}, every label
    and harm value (and `NOT_COMPUTED` where some pairs lack harm); `rates`: the paper's success rate and the
    harmful rate, both over the valid pairs with harm; `tol`, `rtol`: the run's harm tolerances."""

    run_id: int
    available: bool
    total: int
    not_computed: int
    harms: tuple[str, ...]
    counts: dict[str, dict[str, int]]
    rates: dict[str, float | None]
    tol: float
    rtol: float
    table: Table | None = None
    changes: list[RegretChanges] = field(default_factory=list)
    changes_table: Table | None = None
    histogram: Figure | None = None
    histogram_table: Table | None = None
    examples: dict[str, list[HarmExample]] = field(default_factory=dict)  # {"harmless FP": [...], ...}
    example_figures: dict[str, Figure] = field(default_factory=dict)  # the same keys, kinds with pairs only

    def tables(self) -> list[Table]:
        return [t for t in (self.table, self.changes_table, self.histogram_table) if t is not None]

    def figures(self) -> list[Figure]:
        return [*([self.histogram] if self.histogram else []), *self.example_figures.values()]

    def row_total(self, label: str) -> int:
        return sum(self.counts[label].values())


def change_bins(values: np.ndarray, tol: float) -> np.ndarray:
    """Histogram bin edges for regret changes `values` (at least one): an edge at `tol`, so the bins
    `(edges[k], edges[k + 1]]` never mix changes above and below it, a round width keeping to `_MAX_BINS`, the
    first edge below the smallest value and the last at or above the largest (0 always inside)."""
    lo, hi = min(float(values.min()), 0.0), max(float(values.max()), 0.0)
    width = next((w for w in _BIN_WIDTHS if (hi - lo) / w <= _MAX_BINS - 2), None)
    if width is None:
        width = _BIN_WIDTHS[-1] * 10 ** np.ceil(np.log10((hi - lo) / (_MAX_BINS - 2) / _BIN_WIDTHS[-1]))
    first = int(np.ceil((lo - tol) / width)) - 1
    last = max(int(np.ceil((hi - tol) / width)), first + 1)
    return tol + np.round(width * np.arange(first, last + 1), 9)  # round: 0.3, not 0.30000000000000004


def gather(ctx: Context) -> HarmData:
    info = ctx.store.run_info(ctx.run_id)
    # the run's tolerances as its config records them (`vinadv.records`), the defaults for a run without such a config
    config = info["config"] if run_config_kind(info["config"]) is not None else {}
    tol, rtol = float(config.get("harm_tolerance", DEFAULT_TOL)), float(config.get("harm_rtol", 0.0))
    stored = ctx.store.harm_counts(ctx.run_id)
    not_computed = sum(row.get(None, 0) for row in stored.values())
    total = sum(sum(row.values()) for row in stored.values())
    harms = HARMS + ((NOT_COMPUTED,) if not_computed else ())
    counts = {
        label: {h: int(stored.get(label, {}).get(None if h == NOT_COMPUTED else h, 0)) for h in harms}
        for label in ALL_LABELS
    }
    available = not_computed < total
    summary = harm_summary(counts)
    valid = summary["harm_counts"]["harmful"] + summary["harm_counts"]["harmless"]
    success = sum(counts[label]["harmful"] + counts[label]["harmless"] for label in SUCCESS_LABELS)
    data = HarmData(
        run_id=ctx.run_id,
        available=available,
        total=total,
        not_computed=not_computed,
        harms=harms,
        counts=counts,
        rates={"success": success / valid if valid else None, "harmful": summary["harmful_rate"]},
        tol=tol,
        rtol=rtol,
    )
    if not available:
        return data
    data.table = Table(
        "harm_label_x_harm.csv",
        ("label", *harms, "pairs", "harmful_share"),
        [
            [
                label,
                *(counts[label][h] for h in harms),
                data.row_total(label),
                counts[label]["harmful"] / data.row_total(label) if data.row_total(label) else None,
            ]
            for label in ALL_LABELS
        ],
    )
    _harm_regrets(ctx, data)
    _harm_examples(ctx, data, bool(config.get("corner_cutting", True)), info["moves"])
    return data


def _harm_regrets(ctx: Context, data: HarmData) -> None:
    """The regret change summary and histogram of the FP and DP pairs, from one GROUP BY (`Store.regret_changes`)."""
    from vinadv.report import figures  # noqa: PLC0415 (Matplotlib: drawn when gathered)

    groups = ctx.store.regret_changes(ctx.run_id, REGRET_LABELS)
    for label in REGRET_LABELS:
        parts = {harm: groups[(label, harm)] for harm in ("harmful", "harmless") if (label, harm) in groups}
        values = np.concatenate([v for v, _ in parts.values()]) if parts else np.zeros(0)
        weights = np.concatenate([k for _, k in parts.values()]) if parts else np.zeros(0, np.int64)
        n = int(weights.sum())
        data.changes.append(
            RegretChanges(
                label=label,
                pairs=n,
                harmful=int(parts["harmful"][1].sum()) if "harmful" in parts else 0,
                harmless=int(parts["harmless"][1].sum()) if "harmless" in parts else 0,
                improved=int(weights[values < -data.tol].sum()),
                same=int(weights[np.abs(values) <= data.tol].sum()),
                added=int(weights[values > data.tol].sum()),
                mean=float(np.dot(values, weights) / n) if n else None,
                largest=float(values.max()) if n else None,
            )
        )
    data.changes_table = Table(
        "harm_regret_changes.csv",
        ("label", "pairs", "harmful", "harmless", "improved", "same", "added", "mean_change", "largest_change"),
        [
            [c.label, c.pairs, c.harmful, c.harmless, c.improved, c.same, c.added, c.mean, c.largest]
            for c in data.changes
        ],
    )
    if not groups:
        return
    edges = change_bins(np.concatenate([v for v, _ in groups.values()]), data.tol)
    binned = {
        label: {
            harm: np.bincount(
                np.searchsorted(edges, values, side="left") - 1, weights=k, minlength=len(edges) - 1
            ).astype(np.int64)
            for (lab, harm), (values, k) in groups.items()
            if lab == label
        }
        for label in REGRET_LABELS
    }
    data.histogram_table = Table(
        "harm_regret_histogram.csv",
        ("label", "change_above", "change_at_most", "harmful", "harmless"),
        [
            [
                label,
                float(edges[b]),
                float(edges[b + 1]),
                *(int(binned[label][h][b]) if h in binned[label] else 0 for h in ("harmful", "harmless")),
            ]
            for label in REGRET_LABELS
            for b in range(len(edges) - 1)
        ],
    )
    rel = f" + {data.rtol:g} x opt_cost_a" if data.rtol else ""
    data.histogram = Figure(
        tuple(figures.regret_histogram(edges, binned, data.tol, ctx.out / "fig_harm_regret")),
        "The regret the attack added, regret_a - regret_o (cost units; 1 = one orthogonal move), of the FP and DP "
        "pairs: how much further from the optimal cost the adversarial path is than the original path was. A pair "
        f"is harmful when it is over the tolerance{rel} (dashed line), harmless at 0 (the planner moved onto "
        "another route as close to optimal as before) or below (the attack even brought it closer to optimal). "
        "Bars stacked by the stored harm; counts on a log scale.",
        "regret change histogram",
        880,
    )


def _harm_examples(ctx: Context, data: HarmData, corner_cutting: bool, moves: str) -> None:
    """Up to `HARM_EXAMPLES_SHOWN` pairs of each `HARM_EXAMPLES` kind (the first by pair index), their expert
    paths recomputed on both maps under the run's movement model `moves` (`grid.shortest_paths.expert_paths`: the
    few pairs shown, nothing stored)."""
    from vinadv.report import figures  # noqa: PLC0415 (Matplotlib: drawn when gathered)

    for label, harm in HARM_EXAMPLES:
        kind = f"{harm} {label}"
        chosen = [
            r["pair_index"] for r in ctx.store.page_pairs(ctx.run_id, label=label, harm=harm, limit=HARM_EXAMPLES_SHOWN)
        ]
        data.examples[kind] = []
        if not chosen:
            continue
        records = ctx.store.read_pairs(ctx.run_id, pair_indices=np.array(chosen, dtype=np.int64))
        starts = records.starts[:, None, :]
        cost_o, paths_o = expert_paths(records.obstacles_o, records.goals, starts, corner_cutting, moves)
        cost_a, paths_a = expert_paths(records.obstacles_a, records.goals, starts, corner_cutting, moves)
        shown = [
            HarmExample(
                pair_index=int(records.pair_index[i]),
                label=str(records.label[i]),
                harm=str(records.harm[i]),
                expert_label=records.expert_label[i],
                **{
                    name: float(getattr(records, name)[i])
                    for name in ("cost_o", "opt_cost_o", "regret_o", "cost_a", "opt_cost_a", "regret_a")
                },
                expert_path_o=tuple(map(tuple, paths_o[i].tolist())),
                expert_path_a=tuple(map(tuple, paths_a[i].tolist())),
                expert_cost_o=float(cost_o[i, 0]),
                expert_cost_a=float(cost_a[i, 0]),
            )
            for i in range(len(records))
        ]
        data.examples[kind] = shown
        what = (
            "forks the paper counts as successful attacks, yet the adversarial path is no further from optimal "
            "than the original"
            if harm == "harmless"
            else "detours the paper counts as failed attacks, yet the adversarial path is further from optimal than "
            "the original"
        )
        figure = Figure(
            tuple(figures.harm_pairs(records, shown, ctx.out / f"fig_harm_{harm}_{label}")),
            f"{harm.capitalize()} {label} pairs ({len(shown)}, the first by pair index): {what}. "
            f"Each pair: the original map with the planner's path ({PALETTE.original.name}) and the expert, optimal "
            f"path ({PALETTE.expert.name}, seen where the two differ), next to the adversarial map with the planner's "
            f"path ({PALETTE.adversarial.name}, dashed), the expert path on that map and the added obstacle "
            f"({PALETTE.added.name}).",
            kind,
            900,
        )
        data.example_figures[kind] = figure
