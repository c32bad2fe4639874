"""The report's sections, one module each, listed in the page's order in `SECTIONS`.

Each module's `gather(ctx)` takes the report's `Context` (an open `Store`, the output folder, the main run and the
runs to compare) and returns its section's dataclass, which lists its own tables and figures. A section reads the
database only through `Store` methods (results the evaluation stage stored included: it computes nothing that
`vinadv evaluate` measures) and draws through `vinadv.report.figures` (which writes the PNG/SVG files into the
output folder). No section reads another's result, so they can be gathered in any order.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from vinadv import __version__
from vinadv.report.data import Context, ReportData, SectionData
from vinadv.report.sections import (
    categories,
    classifiers,
    distribution,
    examples,
    harm,
    planner,
    robustness,
    run,
    timing,
)


@dataclass(frozen=True)
class Section:
    """One section of the page: its id (the HTML anchor and the template `sections/<id>.html`), its heading and the
    function that gathers its data."""

    id: str
    heading: str
    gather: Callable[[Context], SectionData]


#: the page's sections in order
SECTIONS = (
    Section("run", "Run and configuration", run.gather),
    Section("planner", "The planner's quality", planner.gather),
    Section("examples", "Example map pairs (figs. 1, 2, 5)", examples.gather),
    Section("categories", "The four categories (fig. 3)", categories.gather),
    Section("distribution", "Category distribution (table 4)", distribution.gather),
    Section("harm", "Harm: worse paths, or only different ones?", harm.gather),
    Section("classifiers", "Classifier comparison (tables 5, 6; figs. 8, 9)", classifiers.gather),
    Section("robustness", "Robustness benchmarks", robustness.gather),
    Section("timing", "Processing time for 100 pairs (table 7)", timing.gather),
)


def gather_report(ctx: Context, order: list[str] | None = None) -> ReportData:
    """Gather every section (in `order` of section ids, default the page's: any order gives the same data)."""
    by_id = {s.id: s for s in SECTIONS}
    info = ctx.runs[ctx.run_id]
    data = ReportData(
        run_id=ctx.run_id,
        run_name=info.get("name"),
        compare=list(ctx.compare),
        url=ctx.store.url,
        version=__version__,
        generated=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
        header=run.header_rows(ctx.store.run_info(ctx.run_id)),
        not_papers=ctx.not_papers(),
    )
    for sid in order or list(by_id):
        data.sections[sid] = by_id[sid].gather(ctx)
    data.sections = {sid: data.sections[sid] for sid in by_id if sid in data.sections}
    return data
