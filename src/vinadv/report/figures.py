"""The report's figures (matplotlib, Agg backend), each saved as PNG and SVG.

Every function takes plain data (arrays, dicts read from the database) and a path stem; it writes `stem.png`
and `stem.svg` and returns their file names. Maps, pairs and k curves are drawn by `vinadv.plot`, in its palette
(`vinadv.plot.palette.PALETTE`); curves use scikit-learn's display helpers from stored points. Map figures carry
one legend for the start/goal markers, the added obstacle and the paths; SVG text stays text (searchable,
selectable).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from vinadv.classify.images import render_path_images  # noqa: E402
from vinadv.outfile import atomic_output  # noqa: E402
from vinadv.plot.curves import draw_k_curve  # noqa: E402
from vinadv.plot.maps import as_pair, draw_map, draw_pair, map_legend  # noqa: E402
from vinadv.plot.palette import PALETTE  # noqa: E402
from vinadv.vocabulary import STRENGTH_ORDER  # noqa: E402

CATEGORY_ORDER = STRENGTH_ORDER[:-1]  # UrP, FP, DP, UcP: the paper's fig. 3 and table 4 order (invalid last)
CATEGORY_NAMES = {
    "UrP": "Unreached Path",
    "FP": "Fork Path",
    "DP": "Detour Path",
    "UcP": "Unchanged Path",
    "invalid": "invalid (original path fails)",
}
FORMATS = ("png", "svg")


def save(fig, stem: Path) -> list[str]:
    """Write `stem.png` and `stem.svg`; close the figure; return the file names."""
    names = []
    for fmt in FORMATS:
        path = stem.with_suffix(f".{fmt}")
        with plt.rc_context({"svg.fonttype": "none"}), atomic_output(path, "wb") as fh:
            fig.savefig(fh, format=fmt, dpi=120, bbox_inches="tight")
        names.append(path.name)
    plt.close(fig)
    return names


def _paths(records, i: int) -> tuple[np.ndarray, np.ndarray]:
    o, a = records.path_o[i], records.path_a[i]
    return o, a


def _draw_pair(axes, records, i: int, paths_o, paths_a, title_o: str, title_a: str | None) -> None:
    """Pair `i` of `records` on two axes (`vinadv.plot.draw_pair`): the original map with the paths named in
    `paths_o` (`original`, `adversarial`) on `axes[0]`, the adversarial map (its edited cells marked) with those of
    `paths_a` on `axes[1]`."""
    draw_pair(axes, as_pair(records, i), paths_o, paths_a, (title_o, title_a))


def _distances(pair) -> str:
    """`dh 6, dv 2 (t 4)` of an `ExamplePair` (with 'FP by dh' when a distance over t makes it a fork)."""
    if pair is None or pair.label not in ("FP", "DP"):
        return ""
    text = f"dh {pair.dh}, dv {pair.dv}, t {pair.t}"
    return f"{text}: FP by {pair.deciding}" if pair.deciding else text


def map_pair(records, i: int, stem: Path, with_paths: bool, distances=None) -> list[str]:
    """Figs. 1 and 2: pair `i` of `records`, original map next to adversarial map (with the planned paths);
    `distances`: the pair's `ExamplePair` (its dh/dv in the title)."""
    fig, axes = plt.subplots(1, 2, figsize=(7, 3.6))
    label = records.label[i]
    _draw_pair(
        axes,
        records,
        i,
        ("original",) if with_paths else (),
        ("adversarial",) if with_paths else (),
        "(a) original path" if with_paths else "(a) the normal map",
        "(b) adversarial path" if with_paths else f"(b) the adversarial map (+1 obstacle, {PALETTE.added.name})",
    )
    extra = _distances(distances) if with_paths else ""
    fig.suptitle(f"pair {records.pair_index[i]} ({label}{'; ' + extra if extra else ''})", fontsize=9)
    map_legend(fig, axes)
    return save(fig, stem)


def example_pairs(records, stem: Path, columns: int = 4, distances=None) -> list[str]:
    """Fig. 5: example map pairs, original (top) and adversarial (bottom) with both paths; `distances`: one
    `ExamplePair` per record (FP/DP panels show dh/dv)."""
    n = len(records)
    columns = max(1, min(columns, n))
    rows = -(-n // columns)
    # constrained: the distances under an adversarial map stay clear of the title of the map below
    fig, axes = plt.subplots(
        2 * rows, columns, figsize=(2.3 * columns, 4.8 * rows), squeeze=False, layout="constrained"
    )
    for ax in axes.ravel():
        ax.axis("off")
    for i in range(n):
        r, c = 2 * (i // columns), i % columns
        axes[r, c].axis("on")
        axes[r + 1, c].axis("on")
        _draw_pair(
            axes[r : r + 2, c],
            records,
            i,
            ("original",),
            ("original", "adversarial"),
            f"pair {records.pair_index[i]}: original",
            f"adversarial ({records.label[i]})",
        )
        if distances is not None:  # below the map: a second title line would run into the map above
            axes[r + 1, c].set_xlabel(_distances(distances[i]), fontsize=8)
    map_legend(fig, axes)
    return save(fig, stem)


def categories(examples: dict, stem: Path, distances: dict | None = None) -> list[str]:
    """Fig. 3: one pair per category (columns UrP, FP, DP, UcP): original map, adversarial map, path image.

    `examples`: {label: (records, i)} for the categories the run has; `distances`: {label: ExamplePair}."""
    fig, axes = plt.subplots(3, len(CATEGORY_ORDER), figsize=(2.4 * len(CATEGORY_ORDER), 7.4), squeeze=False)
    for c, label in enumerate(CATEGORY_ORDER):
        column = axes[:, c]
        if label not in examples:
            for ax in column:
                ax.axis("off")
            column[1].text(0.5, 0.5, f"no {label} pair\nin this run", ha="center", va="center", fontsize=9)
            column[0].set_title(f"({'abcd'[c]}) the {label}", fontsize=9)
            continue
        records, i = examples[label]
        _draw_pair(
            column[:2],
            records,
            i,
            ("original",),
            ("adversarial",),
            f"({'abcd'[c]}) the {label}",
            _distances((distances or {}).get(label)) or None,
        )
        image = render_path_images(records.path_o.take([i]), records.path_a.take([i]), records.size)[0]
        column[2].imshow(image, interpolation="nearest")
        column[2].set_xticks([])
        column[2].set_yticks([])
    for r, name in enumerate(("original map", "adversarial map", "path image")):
        axes[r, 0].set_ylabel(name, fontsize=9)
        axes[r, 0].axis("on")
    map_legend(fig, axes[:2])
    return save(fig, stem)


def _cost(value: float) -> str:
    """`12.66` (two decimals; float noise around 0 shows as 0.00, not -0.00)."""
    return f"{round(float(value), 2) + 0.0:.2f}"


def harm_pairs(records, examples, stem: Path, per_row: int = 2) -> list[str]:
    """The harm examples: each pair of `records` as its original map (the planner's path and the expert path) next
    to its adversarial map (likewise, the added obstacle marked), `per_row` pairs to a row, their costs and
    regrets under the maps. `examples`: one `sections.harm.HarmExample` per record (the expert paths, the costs)."""
    n = len(records)
    per_row = max(1, min(per_row, n))
    rows = -(-n // per_row)
    # constrained layout, and room for a title above and the costs below every (square) map
    fig, axes = plt.subplots(
        rows, 2 * per_row, figsize=(2.6 * 2 * per_row, 3.4 * rows), squeeze=False, layout="constrained"
    )
    for ax in axes.ravel():
        ax.axis("off")
    for i, e in enumerate(examples):
        left, right = axes[i // per_row, 2 * (i % per_row)], axes[i // per_row, 2 * (i % per_row) + 1]
        o, a = _paths(records, i)
        for ax, obstacles, paths, added, title, costs in (
            (
                left,
                records.obstacles_o[i],
                [("expert", np.array(e.expert_path_o)), ("original", o)],
                None,
                f"pair {e.pair_index}: original",
                (e.cost_o, e.opt_cost_o, e.regret_o),
            ),
            (
                right,
                records.obstacles_a[i],
                [("expert", np.array(e.expert_path_a)), ("adversarial", a)],
                records.added[i],
                f"adversarial ({e.label}, {e.harm})",
                (e.cost_a, e.opt_cost_a, e.regret_a),
            ),
        ):
            ax.axis("on")
            draw_map(
                ax,
                obstacles,
                records.goals[i],
                records.starts[i],
                paths=paths,
                added=added,
                title=title,
                removed=bool(records.removes[i]),
            )
            cost, optimum, regret = (_cost(v) for v in costs)
            ax.set_xlabel(f"cost {cost}, optimal {optimum}: regret {regret}", fontsize=8)
    map_legend(fig, axes)
    return save(fig, stem)


def regret_histogram(edges: np.ndarray, counts: dict[str, dict[str, np.ndarray]], tol: float, stem: Path) -> list[str]:
    """The regret change `regret_a - regret_o` of the FP and DP pairs: one panel per label of `counts`
    ({label: {harm: pairs per bin (len(edges) - 1,)}}), the harm values stacked, bins `(edges[k], edges[k + 1]]`,
    a log count axis (most pairs sit in the bin of 0) and a dashed line at the harm tolerance `tol`."""
    labels = list(counts)
    fig, axes = plt.subplots(
        1, len(labels), figsize=(4.4 * len(labels), 3.2), sharex=True, sharey=True, squeeze=False, layout="constrained"
    )
    widths = np.diff(edges)
    colours = {"harmful": PALETTE.harmful.colour, "harmless": PALETTE.harmless.colour}
    for ax, label in zip(axes[0], labels):
        bottom = np.zeros(len(widths))
        for harm, colour in colours.items():
            part = counts[label].get(harm)
            if part is None or not part.any():
                continue
            ax.bar(
                edges[:-1],
                part,
                widths,
                bottom=bottom,
                align="edge",
                color=colour,
                edgecolor=PALETTE.free.colour,
                linewidth=0.5,
                label=harm,
                log=True,
            )
            bottom = bottom + part
        ax.axvline(tol, color=PALETTE.edge.colour, ls="--", lw=1, label=f"tolerance ({tol:g})")
        ax.set_title(f"{label} pairs ({int(bottom.sum()):,})", fontsize=9)
        ax.set_xlabel("regret_a - regret_o (cost units)", fontsize=8)
    axes[0, 0].set_ylabel("pairs (log scale)", fontsize=8)
    handles: dict = {}
    for ax in axes[0]:
        for handle, name in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(name, handle)
    fig.legend(
        list(handles.values()), list(handles), loc="outside lower center", ncol=len(handles), fontsize=8, frameon=False
    )
    return save(fig, stem)


def category_bars(table: Sequence[tuple[str, dict]], paper: dict | None, stem: Path) -> list[str]:
    """Table 4 as bars: share of each category per run (and the paper's 5,000 pairs)."""
    series = list(table) + ([("paper (5,000 pairs)", paper)] if paper else [])
    labels = [*CATEGORY_ORDER, "invalid"]
    fig, ax = plt.subplots(figsize=(1.4 + 1.3 * len(labels), 3.4))
    width = 0.8 / max(len(series), 1)
    for k, (name, counts) in enumerate(series):
        total = sum(counts.get(lab, 0) for lab in labels) or 1
        shares = [100.0 * counts.get(lab, 0) / total for lab in labels]
        ax.bar(np.arange(len(labels)) + (k - (len(series) - 1) / 2) * width, shares, width, label=name)
    ax.set_xticks(np.arange(len(labels)), labels)
    ax.set_ylabel("% of pairs")
    ax.legend(fontsize=8)
    ax.set_title("category distribution (table 4)", fontsize=9)
    return save(fig, stem)


def accuracy_vs_size(points: dict, stem: Path) -> list[str]:
    """Fig. 8: test accuracy against the training-set fraction, one line per classifier.

    `points`: {(classifier, setting): [(fraction, train_size, accuracy), ...]}; one colour per classifier, solid
    for the baseline setting, dashed for the tuned one."""
    fig, ax = plt.subplots(figsize=(5.8, 3.8))
    colours = {kind: f"C{k}" for k, kind in enumerate(sorted({kind for kind, _ in points}))}
    for (kind, setting), values in sorted(points.items()):
        values = sorted(values)
        ax.plot(
            [100 * v[0] for v in values],
            [v[2] for v in values],
            "o-" if setting == "baseline" else "s--",
            color=colours[kind],
            label=f"{kind} ({setting})",
        )
    ax.set_xlabel("training set used (% of the 70% split, balanced)")
    ax.set_ylabel("test accuracy")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    ax.set_title("accuracy vs training set size (fig. 8)", fontsize=9)
    return save(fig, stem)


def roc_pr_curves(curves: dict, stem: Path) -> list[str]:
    """Fig. 9: PR and ROC curves for imbalanced and balanced training, one curve per classifier, AP/AUC in the
    legend. `curves`: {training: {classifier: (curve points dict, roc_auc, ap)}}."""
    from sklearn.metrics import PrecisionRecallDisplay, RocCurveDisplay  # noqa: PLC0415 (scikit-learn: only Fig. 9 draws with it)

    fig, axes = plt.subplots(2, 2, figsize=(10, 9), layout="constrained")  # titles clear of the x labels above
    axes = axes.ravel()
    panels = [
        ("pr", "imbalanced", "(a) PR curve, imbalanced training"),
        ("pr", "balanced", "(b) PR curve, balanced training"),
        ("roc", "imbalanced", "(c) ROC curve, imbalanced training"),
        ("roc", "balanced", "(d) ROC curve, balanced training"),
    ]
    for ax, (kind, training, title) in zip(axes, panels):
        drawn = 0
        for name, (points, auc, ap) in sorted(curves.get(training, {}).items()):
            if not points:
                continue
            if kind == "roc":
                RocCurveDisplay(
                    fpr=np.asarray(points["roc"]["fpr"]), tpr=np.asarray(points["roc"]["tpr"]), roc_auc=auc, name=name
                ).plot(ax=ax)
            else:
                PrecisionRecallDisplay(
                    precision=np.asarray(points["pr"]["precision"]),
                    recall=np.asarray(points["pr"]["recall"]),
                    average_precision=ap,
                    name=name,
                ).plot(ax=ax)
            drawn += 1
        if not drawn:
            ax.text(0.5, 0.5, "no curve stored", ha="center", va="center", transform=ax.transAxes)
        ax.set_title(title, fontsize=9)
        if drawn:
            ax.legend(fontsize=7, loc="lower left" if kind == "pr" else "lower right")
    return save(fig, stem)


def robustness_curves(series: Sequence[tuple[str, list[dict]]], stem: Path) -> list[str]:
    """The robustness curves: harmful rate and the paper's success rate against the number of added obstacles k,
    one line per benchmark (`series`: `(name, figures by k)`, each figure a dict with `k`, `harmful_rate`,
    `paper_success_rate`, as `vinadv.robustness.Figures.to_dict`), in % of the valid maps."""
    fig, axes = plt.subplots(1, 2, figsize=(9.2, 3.6), sharey=True, layout="constrained")
    for ax, key, title in zip(
        axes,
        ("harmful_rate", "paper_success_rate"),
        ("harmful rate (worst case per map)", "paper success rate, UrP + FP (worst case)"),
    ):
        draw_k_curve(ax, list(series), key)
        ax.set_title(title, fontsize=9)
    axes[0].set_ylabel("% of valid maps")
    axes[0].set_ylim(0, 100)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 3), fontsize=8, frameon=False)
    return save(fig, stem)
