"""One palette: every module that draws maps, pairs or curves takes its colours from `vinadv.plot.palette.PALETTE`
(none writes a colour of its own), the drawn artists carry the palette's colours, and the captions of the report and
the viewer name them with the palette's words."""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.colors import to_hex

import vinadv
from vinadv.plot import maps
from vinadv.plot.palette import PALETTE

SOURCE = Path(vinadv.__file__).parent
ROOT = SOURCE.parents[1]
#: the modules that draw (the report's sections write the captions of its figures)
DRAWING = sorted(
    [
        *(SOURCE / "plot").glob("*.py"),
        SOURCE / "report" / "figures.py",
        *(SOURCE / "report" / "sections").glob("*.py"),
        SOURCE / "viewer" / "render.py",
        SOURCE / "commands" / "maps.py",
        SOURCE / "evaluation" / "length_curve.py",
    ]
)
#: the keyword arguments by which matplotlib takes a colour
COLOUR_KEYWORDS = {"color", "colour", "c", "ec", "edgecolor", "fc", "facecolor", "mec", "mfc", "cmap", "colors"}
HEX = re.compile(r"#[0-9a-fA-F]{6}\b|#[0-9a-fA-F]{3}\b")
#: the colour words a caption could say (the palette's own and the other common ones)
COLOUR_WORDS = re.compile(r"\b(red|orange|blue|green|black|white|grey|gray|yellow|purple)\b")


def own_colours(tree: ast.AST) -> list[str]:
    """The colours a module writes itself: hex strings anywhere, and string constants given to a colour keyword."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and HEX.search(node.value):
            found.append(node.value)
        if isinstance(node, ast.keyword) and node.arg in COLOUR_KEYWORDS and isinstance(node.value, ast.Constant):
            found.append(f"{node.arg}={node.value.value!r}")
    return found


def test_the_check_sees_a_colour_of_its_own():
    tree = ast.parse('ax.plot(x, color="tab:red"); ax.bar(x, edgecolor="white"); s = "#ff7f0e"; ax.plot(x, c=f"C{k}")')
    assert sorted(own_colours(tree)) == sorted(["color='tab:red'", "edgecolor='white'", "#ff7f0e"])


@pytest.mark.parametrize("path", [p for p in DRAWING if p.name != "palette.py"], ids=lambda p: p.stem)
def test_every_drawing_module_takes_its_colours_from_the_palette(path):
    assert not own_colours(ast.parse(path.read_text(encoding="utf-8"))), path


def test_the_notebook_draws_with_vinadv_plot():
    notebook = json.loads((ROOT / "examples" / "quickstart.ipynb").read_text(encoding="utf-8"))
    code = "\n".join("".join(c["source"]) for c in notebook["cells"] if c["cell_type"] == "code")
    assert "vinadv.plot.pair(" in code
    assert not own_colours(ast.parse(code))


def test_captions_name_the_palettes_colours():
    # the report's sections and the viewer's page say a map colour only through the palette's words
    for path in [*(SOURCE / "report" / "sections").glob("*.py"), SOURCE / "report" / "figures.py"]:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                words = set(COLOUR_WORDS.findall(node.value))
                # the path image's colours are the paper's encoding (classify.images), not the palette's
                assert not words or "path image" in node.value or "= " in node.value, (path.name, node.value)
    page = (SOURCE / "viewer" / "templates" / "pair.html").read_text(encoding="utf-8")
    captions = re.findall(r"<figcaption>(.*?)</figcaption>", page)
    assert captions and all("PALETTE." in c or "path image" in c for c in captions)
    assert not any(COLOUR_WORDS.search(c) for c in captions if "path image" not in c)


def test_the_palette_is_frozen_and_its_colours_are_hex():
    with pytest.raises(AttributeError):
        PALETTE.added = PALETTE.goal  # type: ignore[misc]
    for role, style in PALETTE.styles().items():
        assert re.fullmatch(r"#[0-9a-f]{6}", style.colour), role
    # the report's and the viewer's colours since vinadv 0.1: added obstacle orange, goal a red star
    assert (PALETTE.added.name, PALETTE.goal.name, PALETTE.goal.marker) == ("orange", "red", "*")


def test_a_drawn_pair_carries_the_palettes_colours():
    n = 8
    obstacles = np.zeros((n, n), bool)
    obstacles[0, :] = True
    added = np.array([[3, 3], [4, 4]])
    pair = maps.Pair(
        obstacles_o=obstacles,
        obstacles_a=obstacles | np.isin(np.arange(n * n), added @ [n, 1]).reshape(n, n),
        start=np.array([6, 1]),
        goal=np.array([1, 6]),
        added=added,
        removed=False,
        path_o=np.array([[6, 1], [5, 2], [4, 3], [3, 4], [2, 5], [1, 6]]),
        path_a=np.array([[6, 1], [6, 2], [5, 3], [4, 5], [3, 6], [2, 6], [1, 6]]),
        expanded_o=np.ones((n, n), bool),
    )
    fig, axes = plt.subplots(1, 2)
    maps.draw_pair(axes, pair)
    colours = {}
    for ax in axes:
        for line in ax.get_lines():
            colours.setdefault(line.get_label(), set()).add(to_hex(line.get_color()))
            if line.get_label() in ("start", "goal"):
                assert to_hex(line.get_markeredgecolor()) == PALETTE.edge.colour
                assert line.get_marker() == getattr(PALETTE, line.get_label()).marker
    assert colours == {
        "original": {PALETTE.original.colour},
        "adversarial": {PALETTE.adversarial.colour},
        "start": {PALETTE.start.colour},
        "goal": {PALETTE.goal.colour},
    }
    squares = [p for p in axes[1].patches if p.get_label() != "expanded cells" and p.get_width() > 0]
    assert {to_hex(p.get_facecolor()) for p in squares} == {PALETTE.added.colour} and len(squares) == 2
    # the cells: free and obstacle pixels, the expanded tint on the original map's free cells
    fig.canvas.draw()
    base, tint = axes[0].get_images()
    rgba = base.to_rgba(base.get_array())
    assert to_hex(rgba[0, 0]) == PALETTE.obstacle.colour and to_hex(rgba[5, 5]) == PALETTE.free.colour
    assert to_hex(tint.get_array()[5, 5]) == PALETTE.expanded.colour and tint.get_array()[0, 0, 3] == 0
    plt.close(fig)


def test_a_removed_cell_is_an_outline_in_the_palettes_colour():
    fig, ax = plt.subplots()
    maps.draw_map(ax, np.zeros((5, 5), bool), added=np.array([2, 2]), removed=True)
    (square,) = ax.patches
    assert not square.get_fill() and to_hex(square.get_edgecolor()) == PALETTE.removed.colour
    assert square.get_label() == "removed obstacle"
    plt.close(fig)
