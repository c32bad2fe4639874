"""`maps import --format transpath`: the authors' XML tasks (their six examples: the `_f`, `_h` and `_k` files of a task
counted once, starts and goals as the files say), several files at once, malformed files refused in one line naming
the file, and byte mutations that load or give one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.byte_mutations import refused_mutations
from tests.needs import public_data
from tests.planners.transpath.literal import example_tasks
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid.mapset import MapSet
from vinadv.interop import export_maps, import_maps
from vinadv.interop.formats import read_maps


def example_files() -> list[str]:
    return [str(public_data(f"transpath/heatmap_{i}_{t}.xml")) for i in range(6) for t in "fhk"]


def task_xml(grid, start=(1, 0), goal=(2, 3), heat: str | None = None, extra: str = "") -> str:
    """A task file as the authors write it: `start` and `goal` as `(row, col)`, `grid` a list of rows of 0/1."""
    rows = "".join(f"<row>{' '.join(str(v) for v in row)}</row>" for row in grid)
    h, w = len(grid), len(grid[0]) if grid else 0
    heat = heat if heat is not None else "".join(f"<row>{' '.join('0.5' for _ in row)}</row>" for row in grid)
    return (
        '<?xml version="1.0" encoding="UTF-8" ?>\n<root><map>'
        f"<startx>{start[1]}</startx><starty>{start[0]}</starty><goalx>{goal[1]}</goalx><goaly>{goal[0]}</goaly>"
        f"<width>{w}</width><height>{h}</height><grid>{rows}</grid></map>{extra}"
        f"<heatmap><width>{w}</width><height>{h}</height><grid>{heat}</grid></heatmap></root>\n"
    )


GRID = [[0, 0, 0, 0], [0, 1, 1, 0], [0, 0, 1, 0], [0, 0, 0, 0]]


def test_the_six_examples_import_once_each_with_their_starts_and_goals():
    obstacles, starts, goals, _ = example_tasks("h")
    maps, info = read_maps(example_files(), "transpath")
    assert (len(maps), maps.size, maps.n_starts, maps.moves, maps.corner_cutting) == (6, 64, 1, "octile", True)
    assert info["files"] == 18 and info["tasks_counted_once"] == 12
    assert (maps.obstacles == obstacles).all()
    assert (maps.starts[:, 0] == starts).all() and (maps.goals == goals).all()
    # the `_h` files hold the exact cost-to-go: vinadv's expert costs (octile, corner cutting) are the same numbers
    _, _, _, cost_to_go = example_tasks("h")
    at_start = cost_to_go[np.arange(6), starts[:, 0], starts[:, 1]]
    assert np.allclose(maps.expert_costs[:, 0], at_start, atol=1e-3)


def test_the_cli_reads_several_files_and_refuses_several_for_other_formats(tmp_path, capsys):
    files = example_files()
    out = str(tmp_path / "tp.npz")
    assert main(["maps", "import", "--format", "transpath", *files[:4], "--out", out, "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["maps"] == 2 and info["tasks_counted_once"] == 2 and len(info["file"]) == 4
    assert (MapSet.load(out).goals == read_maps(files[3], "transpath")[0].goals[0]).all(axis=1).any()
    assert main(["maps", "import", "--format", "ascii", files[0], files[1], "--out", out]) == 2
    assert "format ascii reads one file, got 2" in capsys.readouterr().err
    assert main(["maps", "import", "--format", "transpath", files[0], "--out", out, "--no-corner-cutting"]) == 0
    assert MapSet.load(out).corner_cutting is False


def test_a_task_of_another_size_is_padded_and_export_is_refused(tmp_path):
    path = tmp_path / "t.xml"
    path.write_text(task_xml([row[:3] for row in GRID], goal=(3, 2)))  # 4 rows of 3: padded into 4x4
    maps, info = read_maps(path, "transpath", pad_to=6)
    assert maps.size == 6 and info["grids_padded_to_square"] == 1 and maps.obstacles[0, :, 3:].all()
    with pytest.raises(InputError, match="read only"):
        export_maps(maps, tmp_path / "x.xml", "transpath")


BAD = {
    "not xml": ("<root><map>", "not well-formed XML"),
    "entity": ('<!DOCTYPE r [<!ENTITY a "b">]><root/>', "document type or entity declaration"),
    "root": ("<other/>", "expected <root>"),
    "no map": ("<root/>", "no <map> in <root>"),
    "start missing": (task_xml(GRID).replace("<startx>0</startx>", ""), "no <startx> in <map>"),
    "start text": (task_xml(GRID).replace("<startx>0</startx>", "<startx>a</startx>"), "<map><startx> 'a'"),
    "start negative": (task_xml(GRID).replace("<startx>0</startx>", "<startx>-1</startx>"), "not a whole number"),
    "short row": (task_xml(GRID).replace("<row>0 1 1 0</row>", "<row>0 1 1</row>"), "row 1 has 3 values"),
    "rows missing": (task_xml(GRID).replace("<row>0 0 0 0</row>", "", 1), "expected 4 <row>"),
    "cell 2": (task_xml(GRID).replace("<row>0 1 1 0</row>", "<row>0 2 1 0</row>"), "cell (1, 1) is 2.0"),
    "cell word": (task_xml(GRID).replace("<row>0 1 1 0</row>", "<row>0 x 1 0</row>"), "'x' is not a number"),
    "heat nan": (task_xml(GRID, heat="<row>nan 0 0 0</row>" * 4), "expected a finite number"),
    "heat shape": (task_xml(GRID, heat="<row>0 0 0 0</row>" * 3), "<heatmap><grid> holds 3"),
    "two maps": (task_xml(GRID, extra="<map/>"), "more than one <map>"),
    "start on obstacle": (task_xml(GRID, start=(1, 1)), "start (1, 1) is on an obstacle"),
    "goal off grid": (task_xml(GRID, goal=(9, 0)), "goal (9, 0) is outside"),
    "walled in": (task_xml([[0, 1, 0], [1, 1, 0], [0, 0, 0]], start=(0, 0), goal=(2, 2)), "cannot reach the goal"),
    "too wide": (task_xml(GRID).replace("<width>4</width>", "<width>9999</width>", 1), "expected 1..4096"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_malformed_files_are_refused_in_one_line_naming_the_file(tmp_path, case, capsys):
    text, expected = BAD[case]
    path = tmp_path / "task.xml"
    path.write_text(text)
    with pytest.raises(InputError) as err:
        import_maps(path, "transpath")
    message = str(err.value)
    assert message.startswith(str(path)) and expected in message and "\n" not in message, message
    assert main(["maps", "import", "--format", "transpath", str(path), "--out", str(tmp_path / "m.npz")]) == 2
    assert capsys.readouterr().err.strip().count("\n") == 0


def test_starts_and_missing_files_are_refused(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_maps([str(tmp_path / "none.xml")], "transpath")
    (tmp_path / "t.xml").write_text(task_xml(GRID))
    with pytest.raises(InputError, match="brings its own start"):
        read_maps(tmp_path / "t.xml", "transpath", starts=3)


def test_byte_mutations_load_or_give_one_line(tmp_path):
    target = tmp_path / "task.xml"
    target.write_bytes(public_data("transpath/heatmap_2_k.xml").read_bytes())
    refused = refused_mutations(target, lambda: import_maps(target, "transpath"))
    assert any(cut < 0.5 for cut in refused)  # a file cut short is refused
