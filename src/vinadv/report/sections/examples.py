"""Example map pairs (figs. 1, 2, 5)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vinadv.classify.batch import PathPairBatch
from vinadv.classify.rule import label_batch
from vinadv.plot.palette import PALETTE
from vinadv.report.data import CATEGORY_ORDER, Context, Figure, Table


@dataclass(frozen=True)
class ExamplePair:
    """One pair shown in a figure: its label and the rule's distances (`dh`, `dv`, threshold `t`); `deciding`:
    which distance makes an FP pair a fork (`dh`, `dv` or `dh and dv`), None for the other labels."""

    pair_index: int
    label: str
    dh: int
    dv: int
    t: int

    @property
    def deciding(self) -> str | None:
        if self.label != "FP":
            return None
        over = [name for name, d in (("dh", self.dh), ("dv", self.dv)) if d > self.t]
        return " and ".join(over) or None


@dataclass
class ExamplesData:
    fig1: Figure
    fig2: Figure
    fig5: Figure
    pairs: list[ExamplePair]
    t: int

    def tables(self) -> list[Table]:
        return []

    def figures(self) -> list[Figure]:
        return [self.fig1, self.fig2, self.fig5]


def chosen_examples(ctx: Context):
    """Up to two stored pairs per category of the main run (the first by pair index), read with their rule
    distances: `(records, chosen {label: pair indices}, ExamplePairs in records order)`."""
    chosen = {
        label: np.array(
            [r["pair_index"] for r in ctx.store.page_pairs(ctx.run_id, label=label, limit=2)], dtype=np.int64
        )
        for label in CATEGORY_ORDER
    }
    indices = np.concatenate([chosen[label] for label in CATEGORY_ORDER])
    if len(indices) == 0:  # only invalid pairs
        indices = np.array(
            [r["pair_index"] for r in ctx.store.page_pairs(ctx.run_id, label="invalid", limit=4)], dtype=np.int64
        )
    records = ctx.store.read_pairs(ctx.run_id, pair_indices=indices)
    rule = label_batch(PathPairBatch.from_pairs(records))  # the exact distances, whatever labelled the run
    pairs = [
        ExamplePair(pair_index=int(p), label=str(lab), dh=int(dh), dv=int(dv), t=int(rule.t))
        for p, lab, dh, dv in zip(records.pair_index, records.label, rule.dh, rule.dv)
    ]
    return records, chosen, pairs


def gather(ctx: Context) -> ExamplesData:
    from vinadv.report import figures  # noqa: PLC0415 (Matplotlib: drawn when gathered)

    records, chosen, pairs = chosen_examples(ctx)
    position = {p.pair_index: i for i, p in enumerate(pairs)}
    # figs. 1 and 2: a successful attack when there is one (FP, then UrP), else any pair
    lead = next((int(chosen[lab][0]) for lab in ("FP", "UrP", "DP", "UcP") if len(chosen[lab])), pairs[0].pair_index)
    i = position[lead]
    fig1 = Figure(
        tuple(figures.map_pair(records, i, ctx.out / "fig1_map_pair", with_paths=False)),
        "Fig. 1: a pair of maps, the normal map and the adversarial map ("
        + ("one added obstacle" if records.n_added == 1 else f"{records.n_added} added obstacles")
        + f", {PALETTE.added.name}).",
        "original and adversarial map",
        760,
    )
    fig2 = Figure(
        tuple(figures.map_pair(records, i, ctx.out / "fig2_path_pair", with_paths=True, distances=pairs[i])),
        f"Fig. 2: the pair of paths the planner plans on them (original {PALETTE.original.name}, adversarial "
        f"{PALETTE.adversarial.name} dashed).",
        "original and adversarial path",
        760,
    )
    fig5 = Figure(
        tuple(figures.example_pairs(records, ctx.out / "fig5_map_pairs", distances=pairs)),
        f"Fig. 5: examples of map pairs ({len(pairs)}: up to two per category), original map and path "
        "above, adversarial map with both paths below.",
        "example map pairs",
    )
    return ExamplesData(fig1=fig1, fig2=fig2, fig5=fig5, pairs=pairs, t=pairs[0].t)
