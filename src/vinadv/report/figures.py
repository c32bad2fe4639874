"""The report's figures (matplotlib, Agg backend), each saved as PNG and SVG.

Every function takes plain data (arrays, dicts read from the database) and a path stem; it writes `stem.png`
and `stem.svg` and returns their file names. Curves use scikit-learn's display helpers from stored points.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from vinadv.classify import render_path_images  # noqa: E402
from vinadv.grid.draw import draw_map  # noqa: E402

CATEGORY_ORDER = ("UrP", "FP", "DP", "UcP")  # the paper's fig. 3 and table 4 order
CATEGORY_NAMES = {"UrP": "Unreached Path", "FP": "Fork Path", "DP": "Detour Path", "UcP": "Unchanged Path",
                  "invalid": "invalid (original path fails)"}
FORMATS = ("png", "svg")


def save(fig, stem: Path) -> list[str]:
    """Write `stem.png` and `stem.svg`; close the figure; return the file names."""
    names = []
    for fmt in FORMATS:
        path = stem.with_suffix(f".{fmt}")
        fig.savefig(path, dpi=120, bbox_inches="tight")
        names.append(path.name)
    plt.close(fig)
    return names


def _paths(records, i: int) -> tuple[np.ndarray, np.ndarray]:
    o = records.path_o_cells[records.path_o_offsets[i] : records.path_o_offsets[i + 1]]
    a = records.path_a_cells[records.path_a_offsets[i] : records.path_a_offsets[i + 1]]
    return o, a


def map_pair(records, i: int, stem: Path, with_paths: bool) -> list[str]:
    """Figs. 1 and 2: pair `i` of `records`, original map next to adversarial map (with the planned paths)."""
    fig, axes = plt.subplots(1, 2, figsize=(7, 3.6))
    o, a = _paths(records, i)
    label = records.label[i]
    draw_map(axes[0], records.obstacles_o[i], records.goals[i], records.starts[i],
             paths=[("original", o)] if with_paths else (),
             title="(a) original path" if with_paths else "(a) the normal map")
    draw_map(axes[1], records.obstacles_a[i], records.goals[i], records.starts[i],
             paths=[("adversarial", a)] if with_paths else (), added=records.added[i],
             title="(b) adversarial path" if with_paths else "(b) the adversarial map (+1 obstacle, orange)")
    fig.suptitle(f"pair {records.pair_index[i]} ({label})", fontsize=9)
    return save(fig, stem)


def example_pairs(records, stem: Path, columns: int = 4) -> list[str]:
    """Fig. 5: example map pairs, original (top) and adversarial (bottom) with both paths."""
    n = len(records)
    columns = max(1, min(columns, n))
    rows = -(-n // columns)
    fig, axes = plt.subplots(2 * rows, columns, figsize=(2.3 * columns, 4.6 * rows), squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for i in range(n):
        r, c = 2 * (i // columns), i % columns
        o, a = _paths(records, i)
        axes[r, c].axis("on")
        axes[r + 1, c].axis("on")
        draw_map(axes[r, c], records.obstacles_o[i], records.goals[i], records.starts[i], paths=[("original", o)],
                 title=f"pair {records.pair_index[i]}: original")
        draw_map(axes[r + 1, c], records.obstacles_a[i], records.goals[i], records.starts[i],
                 paths=[("original", o), ("adversarial", a)], added=records.added[i],
                 title=f"adversarial ({records.label[i]})")
    return save(fig, stem)


def categories(examples: dict, stem: Path) -> list[str]:
    """Fig. 3: one pair per category (columns UrP, FP, DP, UcP): original map, adversarial map, path image.

    `examples`: {label: (records, i)} for the categories the run has."""
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
        o, a = _paths(records, i)
        draw_map(column[0], records.obstacles_o[i], records.goals[i], records.starts[i], paths=[("original", o)],
                 title=f"({'abcd'[c]}) the {label}")
        draw_map(column[1], records.obstacles_a[i], records.goals[i], records.starts[i],
                 paths=[("adversarial", a)], added=records.added[i])
        image = render_path_images(records.path_o.take([i]), records.path_a.take([i]), records.size)[0]
        column[2].imshow(image, interpolation="nearest")
        column[2].set_xticks([])
        column[2].set_yticks([])
    for r, name in enumerate(("original map", "adversarial map", "path image")):
        axes[r, 0].set_ylabel(name, fontsize=9)
        axes[r, 0].axis("on")
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

    `points`: {classifier: [(fraction, train_size, accuracy), ...]}."""
    fig, ax = plt.subplots(figsize=(5.2, 3.6))
    for name, values in sorted(points.items()):
        values = sorted(values)
        ax.plot([100 * v[0] for v in values], [v[2] for v in values], "o-", label=name)
    ax.set_xlabel("training set used (% of the 70% split, balanced)")
    ax.set_ylabel("test accuracy")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("accuracy vs training set size (fig. 8)", fontsize=9)
    return save(fig, stem)


def roc_pr_curves(curves: dict, stem: Path) -> list[str]:
    """Fig. 9: PR and ROC curves for imbalanced and balanced training, one curve per classifier, AP/AUC in the
    legend. `curves`: {training: {classifier: (curve points dict, roc_auc, ap)}}."""
    from sklearn.metrics import PrecisionRecallDisplay, RocCurveDisplay

    fig, axes = plt.subplots(2, 2, figsize=(10, 9))
    axes = axes.ravel()
    panels = [("pr", "imbalanced", "(a) PR curve, imbalanced training"),
              ("pr", "balanced", "(b) PR curve, balanced training"),
              ("roc", "imbalanced", "(c) ROC curve, imbalanced training"),
              ("roc", "balanced", "(d) ROC curve, balanced training")]
    for ax, (kind, training, title) in zip(axes, panels):
        drawn = 0
        for name, (points, auc, ap) in sorted(curves.get(training, {}).items()):
            if not points:
                continue
            if kind == "roc":
                RocCurveDisplay(fpr=np.asarray(points["roc"]["fpr"]), tpr=np.asarray(points["roc"]["tpr"]),
                                roc_auc=auc, name=name).plot(ax=ax)
            else:
                PrecisionRecallDisplay(precision=np.asarray(points["pr"]["precision"]),
                                       recall=np.asarray(points["pr"]["recall"]), average_precision=ap,
                                       name=name).plot(ax=ax)
            drawn += 1
        if not drawn:
            ax.text(0.5, 0.5, "no curve stored", ha="center", va="center", transform=ax.transAxes)
        ax.set_title(title, fontsize=9)
        if drawn:
            ax.legend(fontsize=7, loc="lower left" if kind == "pr" else "lower right")
    return save(fig, stem)
