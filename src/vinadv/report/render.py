"""Render: the gathered `ReportData` as files. `index.html` from the Jinja2 templates in `templates/` (autoescaped),
the one stylesheet `style.css` copied beside it, and every `Table` as a CSV file. Formatting of numbers lives in
the filters below, so the gathered data stays numbers."""

from __future__ import annotations

import csv
import time
from importlib import resources
from pathlib import Path

import jinja2

from vinadv import __version__, display
from vinadv.outfile import atomic_output
from vinadv.report import paper
from vinadv.report.data import ALL_LABELS, CATEGORY_ORDER, ReportData, Table
from vinadv.report.sections import SECTIONS

STYLESHEET = "style.css"
#: the page's sections in order, `(id, heading)`: the gathered ones and the list of files
PAGE_SECTIONS = (*((s.id, s.heading) for s in SECTIONS), ("files", "Files"))


def num(value, digits: int = 3) -> str:
    """`1,234` for integers, `0.913` for floats (float noise and `-0.000` as `0.000`), an em dash for None/NaN
    (`vinadv.display.number`)."""
    return display.number(value, digits)


def pct(value) -> str:
    """A share in percent, `57.7%` (`vinadv.display.percent`)."""
    return display.percent(value)


def share(part, total) -> str:
    """`12.3%` of `total` (an em dash when it is 0)."""
    return pct(part / total) if total else "—"


def seconds(value) -> str:
    """A duration in the unit that reads best: `12 s`, `0.25 s`, `3.1 ms`, `40 µs`."""
    if value is None:
        return "—"
    value = float(value)
    if value >= 10:
        return f"{value:,.0f} s"
    if value >= 0.1:
        return f"{value:.2f} s"
    if value >= 1e-3:
        return f"{1e3 * value:.1f} ms"
    return f"{1e6 * value:.0f} µs"


def counts(values) -> str:
    """`DP 12, FP 3` of a {label: n} dict."""
    return ", ".join(f"{k} {v:,}" for k, v in sorted((values or {}).items())) or "—"


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("vinadv.report", "templates"),
        autoescape=jinja2.select_autoescape(default=True),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters.update(num=num, pct=pct, seconds=seconds, counts=counts)
    env.globals.update(
        share=share, fmt_seconds=seconds, paper=paper, CATEGORY_ORDER=CATEGORY_ORDER, ALL_LABELS=ALL_LABELS
    )
    return env


def render_page(data: ReportData) -> str:
    """The HTML of `index.html` for `data`."""
    sections = [(sid, title) for sid, title in PAGE_SECTIONS if sid in data.sections or sid == "files"]
    return (
        _environment()
        .get_template("report.html")
        .render(data=data, s=data.sections, sections=sections, files=data.files(), stylesheet=STYLESHEET)
    )


def _write_table(table: Table, out: Path) -> None:
    """`table` as the CSV file `out / table.name`: its header, then its rows (None as an empty field)."""
    with atomic_output(out / table.name, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(table.header)
        writer.writerows([["" if v is None else v for v in row] for row in table.rows])


def write_tables(data: ReportData, out: Path) -> None:
    for table in data.tables():
        _write_table(table, out)


def render_robustness_page(data, out: Path, url: str | None = None) -> Path:
    """The robustness page of `vinadv robustness --report`: `index.html` with only the robustness section
    (`data`: a `sections.robustness.RobustnessData`), its CSV table and the stylesheet, into `out`; return the
    page's path."""
    out = Path(out)
    files = sorted({*([data.table.name] if data.table else []), *(data.figure.files if data.figure else ())})
    if data.table is not None:
        _write_table(data.table, out)
    css = (resources.files("vinadv.report") / "templates" / STYLESHEET).read_text(encoding="utf-8")
    with atomic_output(out / STYLESHEET, "w", encoding="utf-8") as fh:
        fh.write(css)
    page = (
        _environment()
        .get_template("robustness.html")
        .render(
            d=data,
            url=url,
            version=__version__,
            generated=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
            files=files,
            stylesheet=STYLESHEET,
        )
    )
    index = out / "index.html"
    with atomic_output(index, "w", encoding="utf-8") as fh:
        fh.write(page)
    return index


def render_report(data: ReportData, out: Path) -> Path:
    """Write the CSV tables, the stylesheet and `index.html` of `data` into `out`; return the page's path."""
    out = Path(out)
    write_tables(data, out)
    css = (resources.files("vinadv.report") / "templates" / STYLESHEET).read_text(encoding="utf-8")
    with atomic_output(out / STYLESHEET, "w", encoding="utf-8") as fh:
        fh.write(css)
    index = out / "index.html"
    with atomic_output(index, "w", encoding="utf-8") as fh:
        fh.write(render_page(data))
    return index
