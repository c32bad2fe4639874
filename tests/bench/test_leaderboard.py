"""The leaderboard: sorted by the worst-case harmful rate, each row linking to its entry, flags shown; Markdown and
HTML written by `vinadv bench leaderboard`; a file that is not an entry refused in one line."""

from __future__ import annotations

import html
import json
import math
from html.parser import HTMLParser

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

from vinadv.bench.leaderboard import (  # noqa: E402
    COLUMNS,
    COMPACT,
    LEGEND,
    compute_time,
    curve_series,
    k_curve_figure,
    k_curve_name,
    planner_label,
    read_entries,
    render_html,
    render_legend,
    render_markdown,
    rows,
    stylesheet,
)
from vinadv.bench.suites import ENTRY_FORMAT, FROZEN  # noqa: E402
from vinadv.cli import main  # noqa: E402
from vinadv.intervals import rate_interval  # noqa: E402


def _entry(planner: str, harmful: float, flags=(), removal: float = 0.0) -> dict:
    figures = {"k": 1, "harmful_rate": harmful, "paper_success_rate": harmful / 2}
    return {
        "format": ENTRY_FORMAT,
        "suite": {"name": "vin28-quick-v1", "checksum": FROZEN["vin28-quick-v1"]},
        "planner": {"name": planner},
        "weights_sha256": None,
        "clean": {"success_rate": 0.9},
        "attacks": {"remove:random": {"edit": "remove", "by_obstacles": [{**figures, "harmful_rate": removal}]}},
        "worst_case": [figures, {**figures, "k": 3}],
        "flags": {name: {"raised": name in flags, "why": ""} for name in ("gradient_masking", "too_weak")},
    }


def test_sorted_by_worst_case_harmful_rate_with_links_and_flags(tmp_path, capsys):
    entries = tmp_path / "entries"
    entries.mkdir()
    for name, harmful, flags in (("b", 0.30, ()), ("a", 0.05, ("too_weak",)), ("c", 0.10, ())):
        (entries / f"{name}.json").write_text(json.dumps(_entry(name, harmful, flags)))
    table = rows(read_entries(entries))
    assert [r["planner"] for r in table["vin28-quick-v1"]] == ["a", "c", "b"]
    md = render_markdown(table, "e/")
    assert md.index("[a](e/a.json)") < md.index("[c](e/c.json)") < md.index("[b](e/b.json)")
    assert "too_weak" in md and "5.0%" in md
    assert {r["time"] for r in table["vin28-quick-v1"]} == {"—"}  # no time recorded
    timed = {**_entry("t", 0.1), "time": {"wall_s": 5.0, "chunks_s": [60.0, 30.0]}, "machine": {"device": "cpu"}}
    assert compute_time(timed) == "1.5 min (cpu)"
    out = tmp_path / "board"
    assert main(["bench", "leaderboard", str(entries), "--out", str(out), "--quiet"]) == 0
    html = (out / "leaderboard.html").read_text()
    assert '<a href="../entries/a.json">a</a>' in html and html.index(">a</a>") < html.index(">b</a>")
    assert "[a](../entries/a.json)" in (out / "leaderboard.md").read_text()


def test_clean_optimal_for_every_planner_and_exp_for_search_planners_only(tmp_path):
    policy = _entry("vin", 0.1)
    policy["clean"]["percent_optimal"] = 0.862
    search = _entry("astar", 0.0)
    search["clean"].update(percent_optimal=0.71, search={"opt": 0.71, "exp": 0.3427})
    for name, e in (("vin", policy), ("astar", search)):
        (tmp_path / f"{name}.json").write_text(json.dumps(e))
    by_planner = {r["planner"]: r for r in rows(read_entries(tmp_path))["vin28-quick-v1"]}
    assert (by_planner["vin"]["optimal"], by_planner["vin"]["exp"]) == (0.862, None)
    assert (by_planner["astar"]["optimal"], by_planner["astar"]["exp"]) == (0.71, 0.3427)
    md = render_markdown(rows(read_entries(tmp_path)))
    astar_line = next(line for line in md.splitlines() if "[astar]" in line)
    vin_line = next(line for line in md.splitlines() if "[vin]" in line)
    assert "| 71.0% | 34.3% |" in astar_line and "| 86.2% | — |" in vin_line


def test_a_file_that_is_not_an_entry_is_one_line(tmp_path, capsys):
    (tmp_path / "x.json").write_text(json.dumps({"format": "something/1"}))
    assert main(["bench", "leaderboard", str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "not a benchmark entry" in err
    assert main(["bench", "leaderboard", str(tmp_path / "missing"), "--out", str(tmp_path / "o")]) == 2


def test_a_planner_with_parameters_is_named_with_their_values():
    assert planner_label({"name": "wastar", "config": {"moves": "moore", "w": 2.0}}) == "wastar:w=2"
    assert planner_label({"name": "wastar", "config": {"moves": "moore", "w": 2.5}}) == "wastar:w=2.5"
    assert planner_label({"name": "astar", "config": {"moves": "moore"}}) == "astar"
    assert planner_label({"name": "mine.py:make", "config": {"w": 1}}) == "mine.py:make"  # not registered


def test_every_rate_has_its_wilson_interval_from_the_entrys_counts(tmp_path, capsys):
    """A v1 entry holds counts, not intervals: the leaderboard computes each rate's from them, shows it as
    `57.7% [47.9, 67.0]` and gives it in `--json` as `{rate}_low`, `{rate}_high`."""
    e = _entry("vin", 0.0)
    worst = {"k": 1, "valid": 90, "harmful": 52, "broken": 30, "harmful_rate": 52 / 90, "paper_success_rate": 30 / 90}
    e["clean"].update(maps=100, reached=90, percent_optimal=0.62)
    e["worst_case"] = [worst, {**worst, "k": 3, "harmful": 60, "harmful_rate": 60 / 90}]
    e["attacks"]["remove:random"]["by_obstacles"] = [{**worst, "harmful": 9, "harmful_rate": 0.1}]
    (tmp_path / "e").mkdir()
    (tmp_path / "e" / "vin.json").write_text(json.dumps(e))
    (row,) = rows(read_entries(tmp_path / "e"))["vin28-quick-v1"]
    expected = {
        "clean": (90, 100),
        "optimal": (62, 100),
        "harmful": (52, 90),
        "paper": (30, 90),
        "harmful_k": (60, 90),
        "removal": (9, 90),
    }
    for name, (count, n) in expected.items():
        assert (row[f"{name}_low"], row[f"{name}_high"]) == rate_interval(count, n), name
        assert row[f"{name}_low"] <= row[name] <= row[f"{name}_high"]
    assert row["format"] == "v1"
    low, high = rate_interval(52, 90)
    assert f"| 57.8% \\[{100 * low:.1f}, {100 * high:.1f}\\] |" in render_markdown({"s": [row]})
    assert main(["bench", "leaderboard", str(tmp_path / "e"), "--out", str(tmp_path / "b"), "--json"]) == 0
    (printed,) = json.loads(capsys.readouterr().out)["suites"]["vin28-quick-v1"]
    assert (printed["harmful_low"], printed["harmful_high"]) == (low, high)
    page = (tmp_path / "b" / "leaderboard.html").read_text()
    assert f'57.8% <span class="ci">[{100 * low:.1f}, {100 * high:.1f}]</span>' in page
    # no valid map: no rate, no interval
    e["worst_case"] = [
        {**worst, "valid": 0, "harmful": 0, "broken": 0, "harmful_rate": None, "paper_success_rate": None}
    ]
    (tmp_path / "e" / "vin.json").write_text(json.dumps(e))
    (row,) = rows(read_entries(tmp_path / "e"))["vin28-quick-v1"]
    assert (row["harmful"], row["harmful_low"], row["harmful_high"]) == (None, None, None)


def _counted_entry(planner: str = "vin") -> dict:
    """An entry with counts: 52 of 90 valid maps harmed at k = 1, 60 at k = 3."""
    e = _entry(planner, 0.0)
    worst = {"k": 1, "valid": 90, "harmful": 52, "broken": 30, "harmful_rate": 52 / 90, "paper_success_rate": 30 / 90}
    e["clean"].update(maps=100, reached=90, percent_optimal=0.62)
    e["worst_case"] = [worst, {**worst, "k": 3, "harmful": 60, "harmful_rate": 60 / 90}]
    return e


def _wilson(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """The Wilson score interval by its textbook formula (DESIGN.md), plain Python."""
    p = k / n
    centre = (k + z * z / 2) / (n + z * z)
    half = z * math.sqrt(n) / (n + z * z) * math.sqrt(p * (1 - p) + z * z / (4 * n))
    return max(0.0, centre - half), min(1.0, centre + half)


def test_the_compact_table_puts_each_interval_on_a_second_line(tmp_path):
    (tmp_path / "vin.json").write_text(json.dumps(_counted_entry()))
    (tmp_path / "x.json").write_text(json.dumps(_counted_entry("<b>x|y</b>")))
    md = render_markdown(rows(read_entries(tmp_path)), "e/", compact=True)
    header = md.splitlines()[2]
    assert header == "| " + " | ".join(t for t, _ in COMPACT).replace("largest k", "k = 3") + " |"
    low, high = _wilson(52, 90)
    line = next(line for line in md.splitlines() if "[vin](e/vin.json)" in line)
    assert f"| 57.8%<br><small>\\[{100 * low:.1f}, {100 * high:.1f}\\]</small> |" in line
    assert "<b>" not in md and "\\<b\\>x\\|y\\</b\\>" in md  # the entry's strings stay text
    assert len(line.split(" | ")) == len(COMPACT)


def test_every_column_has_a_legend_with_its_denominator():
    assert set(LEGEND) == {"#", *COLUMNS} and {key for _, key in COMPACT} <= set(LEGEND)
    rates = [c for c in COLUMNS if "success" in c or "harmful" in c or c == "clean optimal"]
    assert rates and all("Denominator" in LEGEND[c] for c in rates)
    legend = render_legend(compact=True)
    assert all(f"**{title}**" in legend for title, _ in COMPACT) and "Wilson 95%" in legend


class _Balanced(HTMLParser):
    """Every element closed in order (void elements excepted): a check that the page parses as HTML."""

    VOID = {"meta", "br", "img", "link", "hr", "input"}

    def __init__(self):
        super().__init__()
        self.open: list[str] = []
        self.tags: list[tuple[str, dict]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        if tag not in self.VOID:
            self.open.append(tag)

    def handle_endtag(self, tag):
        assert self.open and self.open[-1] == tag, (self.open, tag)
        self.open.pop()


def test_the_html_page_is_styled_like_the_report_and_parses(tmp_path):
    (tmp_path / "vin.json").write_text(json.dumps(_counted_entry()))
    (tmp_path / "x.json").write_text(json.dumps(_counted_entry("<script>x</script>")))
    table = rows(read_entries(tmp_path))
    page = render_html(table, "e/", figures=True)
    parser = _Balanced()
    parser.feed(page)
    parser.close()
    assert not parser.open
    assert stylesheet() in page and ".scroll" in stylesheet()  # the report's one stylesheet, inlined
    assert sum(tag == "script" for tag, _ in parser.tags) == 0  # the entry's name is text
    images = [a["src"] for tag, a in parser.tags if tag == "img"]
    assert images == [k_curve_name("vin28-quick-v1", "png")]
    assert all(f"<dt>{html.escape(c)}</dt>" in page for c in COLUMNS)


def test_the_k_curve_has_each_planners_worst_case_with_its_wilson_interval(tmp_path):
    (tmp_path / "vin.json").write_text(json.dumps(_counted_entry()))
    (tmp_path / "astar.json").write_text(json.dumps(_counted_entry("astar")))
    ((key, rs),) = rows(read_entries(tmp_path)).items()
    series = dict(curve_series(rs))
    assert list(series) == ["astar", "vin"]
    for points in series.values():
        assert [p["k"] for p in points] == [1, 3]
        for p, harmed in zip(points, (52, 60)):
            assert p["harmful_rate"] == harmed / 90
            assert (p["harmful_rate_low"], p["harmful_rate_high"]) == pytest.approx(_wilson(harmed, 90))
    fig = k_curve_figure(key, rs)
    drawn = [line for line in fig.axes[0].lines if line.get_label() == "vin"]
    assert [round(y, 6) for y in drawn[0].get_ydata()] == [round(100 * 52 / 90, 6), round(100 * 60 / 90, 6)]
    plt.close(fig)


@pytest.mark.slow  # draws and writes two figures: seconds
def test_the_command_writes_each_suites_k_curve_with_figures(tmp_path):
    (tmp_path / "e").mkdir()
    (tmp_path / "e" / "vin.json").write_text(json.dumps(_counted_entry()))
    out = str(tmp_path / "b")
    assert main(["bench", "leaderboard", str(tmp_path / "e"), "--out", out, "--figures", "--quiet"]) == 0
    written = sorted(p.name for p in (tmp_path / "b").iterdir())
    assert written == ["k-curve.vin28-quick-v1.png", "k-curve.vin28-quick-v1.svg", "leaderboard.html", "leaderboard.md"]
    assert (tmp_path / "b" / "k-curve.vin28-quick-v1.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
