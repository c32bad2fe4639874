"""Drawing maps, pairs and value maps with matplotlib, in the colours and markers of `vinadv.plot.palette`.

`draw_map` and `draw_pair` draw on axes they are given (the report and the viewer bring their own figures);
`map`, `pair` and `value_map` make a figure (pyplot: a notebook shows it) or draw on `ax` / `axes` when given, and
return the figure. A pair is a row of `vinadv.open(...).pairs()`, or index `index` of a pairs file, a `PairSet`,
the store's `PairRecords` or a pairs DataFrame (`as_pair`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.layout_engine import ConstrainedLayoutEngine
from matplotlib.patches import Rectangle

from vinadv.errors import InputError
from vinadv.plot.palette import PALETTE

#: the labels of the edited cells in a legend, by edit and count
_EDITED = {False: ("added obstacle", "added obstacles"), True: ("removed obstacle", "removed obstacles")}


def draw_map(
    ax,
    obstacles: np.ndarray,
    goal: np.ndarray | None = None,
    start: np.ndarray | None = None,
    paths: Sequence[tuple[str, np.ndarray]] = (),
    added: np.ndarray | None = None,
    title: str | None = None,
    removed: bool = False,
    expanded: np.ndarray | None = None,
) -> None:
    """Draw one N x N map on `ax` in `PALETTE`'s styles: free cells white, obstacles black, the start a green circle,
    the goal a red star, paths as lines.

    `start` is one cell `(2,)` or several `(k, 2)` (each gets a marker). `paths` is a sequence of
    `(label, cells (L, 2))`; a label `original`, `adversarial` or `expert` gets its style. `added`, one cell `(2,)`
    or several `(k, 2)`, marks the edited cells: added obstacles as filled orange squares, or, with `removed` (edit
    `remove`), freed cells as orange outlines. `expanded`: the cells a search planner expanded, `(N, N)` bool or
    cells `(k, 2)`, tinted under the paths. Every artist carries its label, for `map_legend`.
    """
    obstacles = np.asarray(obstacles, dtype=bool)
    n = obstacles.shape[0]
    cells_cmap = ListedColormap([PALETTE.obstacle.colour, PALETTE.free.colour])
    ax.imshow(~obstacles, cmap=cells_cmap, vmin=0, vmax=1, interpolation="nearest")
    if expanded is not None:
        mask = _mask(expanded, obstacles.shape) & ~obstacles
        tint = np.zeros((*obstacles.shape, 4))
        tint[mask] = [*(c / 255 for c in PALETTE.expanded.rgb), 1.0]
        ax.imshow(tint, interpolation="nearest")
        # the tint is an image, which a legend does not list: an empty square stands for it
        ax.add_patch(Rectangle((0, 0), 0, 0, color=PALETTE.expanded.colour, label="expanded cells"))
    for label, cells in paths:
        style = PALETTE.path(label)
        cells = np.asarray(cells).reshape(-1, 2)
        colour, line = (style.colour, style.line) if style else (None, "-")
        ax.plot(cells[:, 1], cells[:, 0], line, color=colour, lw=2, label=label, alpha=0.9)
    if added is not None:
        cells = np.asarray(added).reshape(-1, 2)
        one, several = _EDITED[bool(removed)]
        edited = PALETTE.removed if removed else PALETTE.added
        for k, (r, c) in enumerate(cells):
            label = (one if len(cells) == 1 else several) if k == 0 else None
            if removed:
                square = Rectangle((c - 0.45, r - 0.45), 0.9, 0.9, fill=False, ec=edited.colour, lw=2, label=label)
            else:
                square = Rectangle((c - 0.5, r - 0.5), 1, 1, color=edited.colour, label=label)
            ax.add_patch(square)
    finish_map(ax, n, goal, start, title)


def finish_map(ax, n: int, goal, start, title: str | None) -> None:
    """The start and goal marked on `ax`, its limits those of an `n x n` map, no ticks, and its title."""
    draw_map_markers(ax, goal, start)
    ax.set_xlim(-0.5, n - 0.5)
    ax.set_ylim(n - 0.5, -0.5)
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=9)


def _mask(cells, shape: tuple[int, int]) -> np.ndarray:
    """`cells` as an `(N, N)` bool mask: a mask of that shape as it is, else `(k, 2)` cells."""
    cells = np.asarray(cells)
    if cells.shape == shape:
        return cells.astype(bool)
    cells = cells.reshape(-1, 2).astype(np.int64)
    if len(cells) and ((cells < 0).any() or (cells >= shape[0]).any()):
        raise InputError(f"expanded: cells outside the {shape[0]}x{shape[1]} map", "expanded")
    mask = np.zeros(shape, bool)
    mask[cells[:, 0], cells[:, 1]] = True
    return mask


def map_legend(fig, axes, **kwargs) -> None:
    """One legend for the maps of `fig` (the start and goal markers, the edited cells, the paths), below them:
    every labelled artist of `axes`, each label once."""
    handles: dict = {}
    for ax in np.asarray(axes).ravel():
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    if handles:
        # under constrained layout an "outside" legend gets its own room; else it hangs below the axes
        place = (
            {"loc": "outside lower center"}
            if isinstance(fig.get_layout_engine(), ConstrainedLayoutEngine)
            else {"loc": "lower center", "bbox_to_anchor": (0.5, -0.02)}
        )
        options = {**place, "ncol": min(len(handles), 5), "fontsize": 8, "frameon": False, **kwargs}
        fig.legend(list(handles.values()), list(handles), **options)


@dataclass(frozen=True, eq=False)
class Pair:
    """One pair as drawn: both maps, start, goal, the edited cells and both paths, `(row, col)` cells.

    Attributes:
        obstacles_o, obstacles_a: `(N, N)` bool. start, goal: `(2,)`. added: `(K, 2)` the edited cells.
        removed: the pair frees obstacle cells (edit `remove`). path_o, path_a: `(L, 2)`.
        pair_index, label, harm: what the title says (None where unknown).
        expanded_o, expanded_a: the cells a search planner expanded on each map (`(N, N)` bool), or None.
    """

    obstacles_o: np.ndarray
    obstacles_a: np.ndarray
    start: np.ndarray
    goal: np.ndarray
    added: np.ndarray
    removed: bool
    path_o: np.ndarray
    path_a: np.ndarray
    pair_index: int | None = None
    label: str | None = None
    harm: str | None = None
    expanded_o: np.ndarray | None = None
    expanded_a: np.ndarray | None = None

    @property
    def title(self) -> str:
        """`pair 12: FP, harmful` (what is known of it)."""
        what = ", ".join(str(v) for v in (self.label, self.harm) if v is not None)
        name = "pair" if self.pair_index is None else f"pair {self.pair_index}"
        return f"{name}: {what}" if what else name


def _grid(value) -> np.ndarray:
    """A map of a pairs DataFrame (N rows of N cells) as `(N, N)` bool (as `vinadv.analysis.grid`)."""
    rows = list(value)
    return np.array([np.asarray(r, dtype=bool) for r in rows], dtype=bool).reshape(len(rows), -1)


def _cells(value) -> np.ndarray:
    """A cell list of a pairs DataFrame as `(L, 2)` int (as `vinadv.analysis.cells`)."""
    return np.array([np.asarray(c) for c in value], dtype=np.int64).reshape(-1, 2)


def _optional(row, name: str):
    value = row.get(name) if hasattr(row, "get") else None
    # a DataFrame holds a missing value as None, NaN or pandas' NA (whose truth value raises: compare by identity)
    if value is None or (isinstance(value, float) and np.isnan(value)) or type(value).__name__ == "NAType":
        return None
    return value


def as_pair(pair, index: int | None = None) -> Pair:
    """The pair to draw, from any of:

    - a row of `vinadv.open(...).pairs()` (a pandas Series) or any mapping with its columns (`map_o`, `map_a`,
      `start`, `goal`, `added`, `edit`, `path_o`, `path_a`; `pair_index`, `label`, `harm` if present);
    - a pairs DataFrame and `index`, its row number (`iloc`);
    - a `PathPairs` (a `PairSet` of a pairs file, the store's `PairRecords`) and `index`;
    - a pairs file name and `index`.

    InputError for an index out of range or a pairs object without `index`."""
    if isinstance(pair, (str, os.PathLike)):
        from vinadv.attacks.pairs import PairSet  # noqa: PLC0415 (the attacks only for a pairs file)

        pair = PairSet.load(pair)
    if hasattr(pair, "iloc") and hasattr(pair, "columns"):  # a DataFrame
        if index is None:
            raise InputError("pair: a pairs DataFrame needs index= (a row number), or pass one row", "index")
        if not 0 <= index < len(pair):
            raise InputError(f"pair: index {index} is out of range: the DataFrame has {len(pair)} rows", "index")
        pair, index = pair.iloc[index], None
    if hasattr(pair, "obstacles_o"):  # PathPairs
        if index is None:
            raise InputError("pair: give index= (which pair of the set to draw)", "index")
        if not 0 <= index < len(pair):
            raise InputError(f"pair: index {index} is out of range: there are {len(pair)} pairs", "index")
        labels = getattr(pair, "label", None)
        harms = getattr(pair, "harm", None)
        numbers = getattr(pair, "pair_index", None)
        return Pair(
            obstacles_o=pair.obstacles_o[index],
            obstacles_a=pair.obstacles_a[index],
            start=pair.starts[index],
            goal=pair.goals[index],
            added=pair.added[index],
            removed=bool(pair.removes[index]),
            path_o=np.asarray(pair.path_o[index]),
            path_a=np.asarray(pair.path_a[index]),
            pair_index=int(numbers[index]) if numbers is not None else index,
            label=None if labels is None else str(labels[index]),
            harm=None if harms is None else str(harms[index]),
        )
    if isinstance(pair, Mapping) or hasattr(pair, "index"):  # a Series or a dict
        missing = [k for k in ("map_o", "map_a", "start", "goal", "added", "path_o", "path_a") if k not in pair]
        if missing:
            raise InputError(f"pair: the row has no {', '.join(missing)} (a row of vinadv.open(...).pairs())", "pair")
        number = _optional(pair, "pair_index")
        shape = _grid(pair["map_o"]).shape
        expanded = {
            side: None if _optional(pair, f"expanded_{side}") is None else _mask(pair[f"expanded_{side}"], shape)
            for side in ("o", "a")
        }
        return Pair(
            obstacles_o=_grid(pair["map_o"]),
            obstacles_a=_grid(pair["map_a"]),
            start=np.asarray(pair["start"], dtype=np.int64).reshape(2),
            goal=np.asarray(pair["goal"], dtype=np.int64).reshape(2),
            added=_cells(pair["added"]),
            removed=_optional(pair, "edit") == "remove",
            path_o=_cells(pair["path_o"]),
            path_a=_cells(pair["path_a"]),
            pair_index=None if number is None else int(number),
            label=_optional(pair, "label"),
            harm=_optional(pair, "harm"),
            expanded_o=expanded["o"],
            expanded_a=expanded["a"],
        )
    raise InputError(f"pair: cannot draw a {type(pair).__name__} (a DataFrame row, pairs and an index, or a file)")


def draw_pair(
    axes,
    pair: Pair,
    paths_o: Sequence[str] = ("original",),
    paths_a: Sequence[str] = ("original", "adversarial"),
    titles: tuple[str | None, str | None] = ("original map", "adversarial map"),
    expanded: bool = True,
) -> None:
    """`pair` on two axes: the original map with the paths named in `paths_o` on `axes[0]`, the adversarial map (its
    edited cells marked) with those of `paths_a` on `axes[1]` (names `original`, `adversarial`; an empty path is
    left out), each search's expanded cells tinted where `pair` has them and `expanded`."""
    cells = {"original": pair.path_o, "adversarial": pair.path_a}
    draw_map(
        axes[0],
        pair.obstacles_o,
        pair.goal,
        pair.start,
        paths=[(name, cells[name]) for name in paths_o if len(cells[name])],
        title=titles[0],
        expanded=pair.expanded_o if expanded else None,
    )
    draw_map(
        axes[1],
        pair.obstacles_a,
        pair.goal,
        pair.start,
        paths=[(name, cells[name]) for name in paths_a if len(cells[name])],
        added=pair.added,
        title=titles[1],
        removed=pair.removed,
        expanded=pair.expanded_a if expanded else None,
    )


def pair(
    pair,
    index: int | None = None,
    *,
    expanded_o: np.ndarray | None = None,
    expanded_a: np.ndarray | None = None,
    axes=None,
    title: str | None = None,
    legend: bool = True,
):
    """Draw one pair (see `as_pair` for what `pair` and `index` may be): the original map with the original path,
    next to the adversarial map with both paths and the edited cells (an added obstacle a filled orange square, a
    removed one an orange outline); a search planner's expanded cells (`expanded_o`, `expanded_a`: `(N, N)` bool
    or `(k, 2)` cells, e.g. `SearchResult.expanded`) tinted under the paths. `axes`: two axes to draw on (else a new
    figure). Returns the figure.

        with vinadv.open("results.db") as results:
            pairs = results.pairs()
        vinadv.plot.pair(pairs.iloc[0])
    """
    drawn = as_pair(pair, index)
    shape = drawn.obstacles_o.shape
    if expanded_o is not None or expanded_a is not None:
        drawn = Pair(
            **{
                **drawn.__dict__,
                "expanded_o": drawn.expanded_o if expanded_o is None else _mask(expanded_o, shape),
                "expanded_a": drawn.expanded_a if expanded_a is None else _mask(expanded_a, shape),
            }
        )
    if axes is None:
        fig, axes = plt.subplots(1, 2, figsize=(7, 4), layout="constrained")
    else:
        fig = np.asarray(axes).ravel()[0].figure
    draw_pair(np.asarray(axes).ravel(), drawn)
    fig.suptitle(drawn.title if title is None else title, fontsize=10)
    if legend:
        map_legend(fig, axes)
    return fig


def figure_for(ax, figsize: tuple[float, float]):
    """`(figure, axes)`: `ax` and its figure, or a new figure of `figsize` inches with one axes."""
    if ax is None:
        return plt.subplots(figsize=figsize, layout="constrained")
    return ax.figure, ax


def map(
    obstacles: np.ndarray,
    goal: np.ndarray | None = None,
    start: np.ndarray | None = None,
    paths: Sequence[tuple[str, np.ndarray]] = (),
    *,
    added: np.ndarray | None = None,
    removed: bool = False,
    expanded: np.ndarray | None = None,
    ax=None,
    title: str | None = None,
    legend: bool = True,
):
    """Draw one map (`draw_map`: obstacles, start or starts, goal, labelled paths, edited and expanded cells) on `ax`
    or a new figure, with its legend below; returns the figure."""
    fig, ax = figure_for(ax, (4, 4.4))
    draw_map(ax, obstacles, goal, start, paths, added=added, title=title, removed=removed, expanded=expanded)
    if legend:
        map_legend(fig, ax)
    return fig


def value_map(
    values: np.ndarray,
    obstacles: np.ndarray | None = None,
    goal: np.ndarray | None = None,
    start: np.ndarray | None = None,
    *,
    ax=None,
    title: str | None = None,
    colorbar: bool = True,
):
    """Draw a value map `(N, N)` (a VIN's values, a search planner's cost or heuristic map: `Planner.value_maps`)
    in `PALETTE.values`' colour map, obstacles (where given) in the obstacle colour on top, the start and goal
    marked; on `ax` or a new figure, with a colour bar. Returns the figure."""
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 2 or values.shape[0] != values.shape[1]:
        raise InputError(f"value_map: expected an (N, N) map, got shape {values.shape}", "values")
    fig, ax = figure_for(ax, (4.4, 4))
    shown = np.ma.masked_invalid(values)
    if obstacles is not None:
        shown = np.ma.masked_where(np.asarray(obstacles, dtype=bool), shown)
    cmap = plt.get_cmap(PALETTE.values).with_extremes(bad=PALETTE.obstacle.colour)
    image = ax.imshow(shown, cmap=cmap, interpolation="nearest")
    finish_map(ax, values.shape[0], goal, start, title)
    if colorbar:
        fig.colorbar(image, ax=ax, shrink=0.8)
    return fig


def draw_map_markers(ax, goal: np.ndarray | None, start: np.ndarray | None) -> None:
    """The start and goal markers alone (over a value map)."""
    if start is not None:
        starts = np.asarray(start).reshape(-1, 2)
        ax.plot(
            starts[:, 1],
            starts[:, 0],
            PALETTE.start.marker,
            color=PALETTE.start.colour,
            ms=8,
            mec=PALETTE.edge.colour,
            ls="none",
            label="start" if len(starts) == 1 else "starts",
        )
    if goal is not None:
        goal = np.asarray(goal).reshape(2)
        style = PALETTE.goal
        ax.plot(goal[1], goal[0], style.marker, color=style.colour, ms=13, mec=PALETTE.edge.colour, label="goal")
