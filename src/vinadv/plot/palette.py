"""The one palette and set of markers every drawing of vinadv uses: the report's figures, the viewer's images and
captions, `vinadv maps show`, `vinadv.plot` (and through it the notebook).

A `Style` is a colour (hex, as matplotlib and CSS take it), the colour's word (what a caption says: "the added obstacle
orange") and, for what is drawn as a point or a line, its matplotlib marker or line style. `PALETTE` is frozen:
change a colour here and every figure, caption and page follows (tests/plot/test_palette.py holds the drawing
modules to it). No matplotlib here: the viewer's templates and the report's captions read the words without it.
"""

from __future__ import annotations

from dataclasses import dataclass, fields


@dataclass(frozen=True)
class Style:
    """How one thing on a map is drawn.

    Attributes:
        colour: `#rrggbb`.
        name: the colour in words, as captions say it (`orange`).
        marker: matplotlib marker of a point (`o`, `*`, `s`), or None.
        line: matplotlib line style of a path (`-`, `--`), or None.
    """

    colour: str
    name: str
    marker: str | None = None
    line: str | None = None

    @property
    def rgb(self) -> tuple[int, int, int]:
        """`(r, g, b)`, each 0..255."""
        return tuple(int(self.colour[i : i + 2], 16) for i in (1, 3, 5))


@dataclass(frozen=True)
class Palette:
    """The styles of a map drawing (the report's and the viewer's colours since vinadv 0.1).

    Attributes:
        free, obstacle: the cells (white, black).
        start, goal: markers (green circle, red star).
        original, adversarial: the planner's path on the original map (red, solid) and on the adversarial map
            (blue, dashed); expert: an optimal path (green, solid).
        added: an added obstacle (orange square, filled); removed: a freed obstacle cell (orange square, outlined);
            several edited cells are each drawn so.
        expanded: the cells a search planner expanded (a pale tint under the paths).
        edge: marker edges and reference lines (black).
        harmful, harmless: harm verdicts in charts (red, grey).
        values: the matplotlib colour map of value maps.
        series: the lines of a chart with one line per planner (k curves), in order: each a colour and its own
            marker, so that lines stay apart in grey print too.
    """

    free: Style = Style("#ffffff", "white")
    obstacle: Style = Style("#000000", "black")
    start: Style = Style("#2ca02c", "green", marker="o")
    goal: Style = Style("#d62728", "red", marker="*")
    original: Style = Style("#d62728", "red", line="-")
    adversarial: Style = Style("#1f77b4", "blue", line="--")
    expert: Style = Style("#2ca02c", "green", line="-")
    added: Style = Style("#ff7f0e", "orange", marker="s")
    removed: Style = Style("#ff7f0e", "orange", marker="s")
    expanded: Style = Style("#ffeda0", "pale yellow")
    edge: Style = Style("#000000", "black")
    harmful: Style = Style("#d62728", "red")
    harmless: Style = Style("#7f7f7f", "grey")
    values: str = "viridis"
    series: tuple[Style, ...] = (
        Style("#1f77b4", "blue", marker="o", line="-"),
        Style("#ff7f0e", "orange", marker="s", line="-"),
        Style("#2ca02c", "green", marker="^", line="-"),
        Style("#d62728", "red", marker="D", line="-"),
        Style("#9467bd", "purple", marker="v", line="-"),
        Style("#8c564b", "brown", marker="P", line="-"),
        Style("#e377c2", "pink", marker="X", line="-"),
        Style("#7f7f7f", "grey", marker="*", line="-"),
        Style("#bcbd22", "olive", marker="h", line="--"),
        Style("#17becf", "cyan", marker="p", line="--"),
    )

    def styles(self) -> dict[str, Style]:
        """{role: Style} of every role that has one."""
        return {f.name: getattr(self, f.name) for f in fields(self) if isinstance(getattr(self, f.name), Style)}

    def line(self, i: int) -> Style:
        """The style of a chart's `i`-th line (`series`, round again after the last)."""
        return self.series[i % len(self.series)]

    def path(self, label: str) -> Style | None:
        """The style of a path labelled `label` (`original`, `adversarial`, `expert`; `planned`, a planner's path on
        a map of no pair, as `original`), None for any other."""
        label = {"planned": "original"}.get(label, label)
        return getattr(self, label) if label in ("original", "adversarial", "expert") else None


#: the palette (one definition: every drawing reads it)
PALETTE = Palette()
