"""The report's sections: gathered in any order they hold the same data, each renders from its gathered data
alone; the map figures carry a legend for the markers; the FP/DP examples give dh and dv (against a plain-Python
oracle of DESIGN.md's definition) and say which one makes a pair a fork."""

from __future__ import annotations

import html
import re

import pytest
import sqlalchemy as sa
from tests.store.oracle import parse_path

from vinadv.cli import main
from vinadv.report.build import report_context
from vinadv.report.render import PAGE_SECTIONS, render_page, render_report
from vinadv.report.sections import SECTIONS, gather_report
from vinadv.store import Store

pytestmark = pytest.mark.slow


def _gather(url, out, order, runs):
    out.mkdir(parents=True, exist_ok=True)
    with Store.open(url, create=False) as store:
        return gather_report(report_context(store, out, None, runs), order=order)


def test_sections_do_not_depend_on_the_order_they_are_gathered_in(evaluated, tmp_path, png_only):
    url, (saliency, near_path), _ = evaluated
    ids = [s.id for s in SECTIONS]
    forward = _gather(url, tmp_path / "a", ids, [saliency, near_path])
    backward = _gather(url, tmp_path / "b", ids[::-1], [saliency, near_path])
    assert list(forward.sections) == list(backward.sections) == ids
    for sid in ids:  # every section: the report measures nothing itself, it reads what the evaluation stored
        assert forward.sections[sid] == backward.sections[sid], sid
    assert forward.files() == backward.files()
    # the same figure bytes whichever order wrote them (PNG: the SVGs carry matplotlib's random ids, so the test
    # saves PNGs only)
    for name in forward.files():
        if name.endswith(".png"):
            assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


@pytest.mark.parametrize("sid", [s.id for s in SECTIONS])
def test_each_section_renders_from_its_gathered_data_alone(evaluated, tmp_path, sid, unrendered):
    url, (saliency, _), _ = evaluated
    data = _gather(url, tmp_path, [sid], [saliency])
    assert list(data.sections) == [sid]
    page = render_report(data, tmp_path).read_text()
    assert page == render_page(data)
    found = re.findall(r'<section id="([a-z]+)">', page)
    assert found == [sid, "files"]
    body = page.split(f'<section id="{sid}">', 1)[1].split("</section>", 1)[0]
    assert len(re.sub(r"<[^>]+>|\s", "", body)) > 40  # a heading and content, not an empty shell
    for name in data.files():  # every file the section wrote is linked from its part of the page
        assert f'="{name}"' in body and (tmp_path / name).is_file(), name
    assert f"<h2>{dict(PAGE_SECTIONS)[sid]}</h2>" in html.unescape(body)


@pytest.mark.parametrize("stem", ["fig1_map_pair", "fig2_path_pair", "fig3_categories", "fig5_map_pairs"])
def test_map_figures_have_a_legend_for_start_goal_and_obstacle(evaluated, stem):
    _, _, out = evaluated
    svg = (out / f"{stem}.svg").read_text()
    texts = set(re.findall(r"<text[^>]*>([^<]*)</text>", svg))
    assert {"start", "goal", "added obstacle"} <= texts, texts
    if stem != "fig1_map_pair":
        assert {"original", "adversarial"} & texts


def _oracle_distances(path_o: str, path_a: str) -> tuple[int, int]:
    """DESIGN.md: Do = original cells not on the adversarial path, Da the reverse; dh the largest column distance
    of a Do and a Da cell in one row, dv the largest row distance in one column (0 where none)."""
    o, a = parse_path(path_o), parse_path(path_a)
    do = [c for c in o if c not in set(a)]
    da = [c for c in a if c not in set(o)]
    dh = max([abs(p[1] - q[1]) for p in do for q in da if p[0] == q[0]], default=0)
    dv = max([abs(p[0] - q[0]) for p in do for q in da if p[1] == q[1]], default=0)
    return dh, dv


def test_fp_and_dp_examples_give_dh_dv_and_what_makes_a_fork(evaluated):
    url, (saliency, _), out = evaluated
    page = (out / "index.html").read_text()
    listed = re.findall(r"pair (\d+) \((FP|DP)\): dh (\d+), dv (\d+)(?:: FP by (dh and dv|dh|dv) \(|: DP)", page)
    assert {label for _, label, *_ in listed} == {"FP", "DP"}  # the run has both, and the page lists both
    with sa.create_engine(url).connect() as conn:
        for pair, label, dh, dv, by in listed:
            path_o, path_a, stored = conn.execute(
                sa.text("SELECT path_o, path_a, label FROM map_pairs WHERE run_id = :r AND pair_index = :p"),
                {"r": saliency, "p": int(pair)},
            ).one()
            assert stored == label
            assert (int(dh), int(dv)) == _oracle_distances(path_o, path_a)
            t = 2  # round(4 * 12 / 28)
            if label == "FP":
                assert by == " and ".join(n for n, d in (("dh", int(dh)), ("dv", int(dv))) if d > t)
            else:
                assert int(dh) <= t and int(dv) <= t
    assert "can look\nlike a detour and still be FP" in page or "look like a detour and still be FP" in page


def _section(page: str, sid: str) -> str:
    return page.split(f'<section id="{sid}">', 1)[1].split("</section>", 1)[0]


#: the sections that show what `vinadv evaluate` stores
EVALUATED = ["planner", "classifiers", "timing"]


def test_a_store_without_the_evaluation_says_so_until_vinadv_evaluate_stores_it(db_copy, tmp_path):
    url, (saliency, _) = db_copy
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        conn.execute(sa.text("DELETE FROM measurements"))
    engine.dispose()
    data = _gather(url, tmp_path / "bare", EVALUATED, [saliency])
    page = render_page(data)
    command = f"<code>vinadv evaluate --db {url} --run {saliency}</code>"
    for sid in EVALUATED:
        assert command in _section(page, sid), sid
    assert "Not evaluated" in _section(page, "planner") and "Source:" not in page
    assert _section(page, "timing").count("<td>not evaluated</td>") == 2
    rows = {row[0]: row for row in data.sections["timing"].table.rows}
    assert rows["rule"][1:4] == rows["database_read"][1:4] == [None, None, None]
    quiet = ["--quiet", "--db", url, "--run", str(saliency)]
    assert main(["evaluate", *quiet, "--classifiers", "rule"]) == 0
    data = _gather(url, tmp_path / "evaluated", EVALUATED, [saliency])
    page = render_page(data)
    assert "Not evaluated" not in page and "Source: " in _section(page, "planner")
    assert "stored pairs of run" in _section(page, "timing") and "<td>not evaluated</td>" not in page
    assert data.sections["timing"].pairs == sum(data.sections["timing"].counts.values()) > 0
