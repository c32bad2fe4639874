"""The four categories (fig. 3)."""

from __future__ import annotations

from dataclasses import dataclass

from vinadv.plot.palette import PALETTE
from vinadv.report.data import CATEGORY_ORDER, Context, Figure, Table
from vinadv.report.sections.examples import ExamplePair, chosen_examples


@dataclass
class CategoriesData:
    figure: Figure
    pairs: list[ExamplePair]
    missing: list[str]

    def tables(self) -> list[Table]:
        return []

    def figures(self) -> list[Figure]:
        return [self.figure]


def gather(ctx: Context) -> CategoriesData:
    from vinadv.report import figures  # noqa: PLC0415 (Matplotlib: drawn when gathered)

    records, chosen, pairs = chosen_examples(ctx)
    position = {p.pair_index: i for i, p in enumerate(pairs)}
    shown = {label: position[int(chosen[label][0])] for label in CATEGORY_ORDER if len(chosen[label])}
    figure = Figure(
        tuple(
            figures.categories(
                {label: (records, i) for label, i in shown.items()},
                ctx.out / "fig3_categories",
                distances={label: pairs[i] for label, i in shown.items()},
            )
        ),
        f"Fig. 3: the four categories. Rows: original map ({PALETTE.original.name} path), adversarial map "
        f"({PALETTE.adversarial.name} path), path image (blue = adversarial path, red = original path drawn on top).",
        "the four categories",
        900,
    )
    return CategoriesData(
        figure=figure,
        pairs=[pairs[i] for i in shown.values()],
        missing=[label for label in CATEGORY_ORDER if label not in shown],
    )
