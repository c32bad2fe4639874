"""Saving a report figure as PNG and SVG: `vinadv.report.figures.save` (`bbox_inches="tight"` per format: each save
lays the figure out and measures it, then draws it) against one layout and one tight box, measured at the PNG's dpi,
shared by both formats (a candidate, not what the report does).

    nice .venv/bin/python perf/report_save.py [--maps 8] [--rounds 3] [--json]

The figure: `--maps` generated 12x12 maps with paths, under constrained layout, with titles and the map legend, as
the report's map figures are. Prints each way's best time and the ratio, and whether each format's bytes are the
same both ways (SVG ids fixed by `svg.hashsalt`). The shared layout leaves the PNG as it is but changes the SVG: the
SVG renderer measures text apart from Agg, so its own layout and box differ by a few tenths of a point.
"""

from __future__ import annotations

import argparse
import io
import json
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
matplotlib.rcParams["svg.hashsalt"] = "perf"
import matplotlib.pyplot as plt  # noqa: E402

from common import add_output_arguments, timed_side_by_side  # noqa: E402 (perf/common.py)
from vinadv.grid.generator import generate_maps  # noqa: E402
from vinadv.plot.maps import draw_map, map_legend  # noqa: E402
from vinadv.report.figures import FORMATS  # noqa: E402

DPI = 120


def figure(maps):
    n = len(maps.obstacles)
    fig, axes = plt.subplots(2, (n + 1) // 2, figsize=(2.3 * ((n + 1) // 2), 5.2), squeeze=False, layout="constrained")
    for i, ax in enumerate(axes.ravel()[:n]):
        start, goal = maps.starts[i, 0], maps.goals[i]
        path = [(int(start[0]), c) for c in range(int(start[1]), int(goal[1]) + 1)]
        draw_map(ax, maps.obstacles[i], goal, start, [("original", path)], added=goal, title=f"map {i} (FP)")
    map_legend(fig, axes)
    return fig


def tight_per_format(fig) -> dict[str, bytes]:
    out = {}
    for fmt in FORMATS:
        with plt.rc_context({"svg.fonttype": "none"}):
            buf = io.BytesIO()
            fig.savefig(buf, format=fmt, dpi=DPI, bbox_inches="tight")
        out[fmt] = buf.getvalue()
    plt.close(fig)
    return out


def shared_layout(fig) -> dict[str, bytes]:
    out = {}
    with plt.rc_context({"svg.fonttype": "none"}):
        fig.set_dpi(DPI)
        renderer = fig.canvas.get_renderer()
        fig.draw_without_rendering()
        box = fig.get_tightbbox(renderer).padded(plt.rcParams["savefig.pad_inches"])
        fig.set_layout_engine("none")
        for fmt in FORMATS:
            buf = io.BytesIO()
            fig.savefig(buf, format=fmt, dpi=DPI, bbox_inches=box)
            out[fmt] = buf.getvalue()
    plt.close(fig)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--maps", type=int, default=8, help="maps in the figure (default 8)")
    add_output_arguments(parser, rounds=3)
    args = parser.parse_args()
    maps = generate_maps(args.maps, 12, seed=0, n_starts=1)
    (old, new), (old_bytes, new_bytes) = timed_side_by_side(
        [lambda: tight_per_format(figure(maps)), lambda: shared_layout(figure(maps))], args.rounds
    )
    figures = {
        "tight_per_format_s": round(old, 4),
        "shared_layout_s": round(new, 4),
        "shared_over_tight": round(new / old, 3),
        **{f"{fmt}_identical": old_bytes[fmt] == new_bytes[fmt] for fmt in FORMATS},
    }
    if args.json:
        print(json.dumps(figures))
    else:
        for key, value in figures.items():
            print(f"{key}: {value}")


if __name__ == "__main__":
    main()
