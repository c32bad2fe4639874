"""Plain-Python reference encoders of the paper's text formats (one cell at a time, obviously right)."""

from __future__ import annotations


def map_text(obstacles) -> str:
    return ";".join("".join("1" if cell else "0" for cell in row) for row in obstacles)


def path_text(cells) -> str:
    return ";".join(f"{int(r)},{int(c)}" for r, c in cells)


def parse_path(text: str) -> list[tuple[int, int]]:
    if text == "":
        return []
    return [tuple(int(v) for v in cell.split(",")) for cell in text.split(";")]


def parse_map(text: str) -> list[list[bool]]:
    return [[ch == "1" for ch in row] for row in text.split(";")] if text else []
