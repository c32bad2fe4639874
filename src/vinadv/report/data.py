"""The report's data: what every section reads (`Context`), what it returns (its dataclass, holding `Table`s and
`Figure`s) and the whole page's (`ReportData`). Numbers stay numbers (formatting is the templates' job); `Table`s
are what the CSV files hold."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from vinadv.report.paper import papers_setting
from vinadv.vocabulary import STRENGTH_ORDER

ALL_LABELS = STRENGTH_ORDER
#: the four valid categories, in the paper's fig. 3 and table 4 order
CATEGORY_ORDER = STRENGTH_ORDER[:-1]
#: the label source of the exact rule labeller; any other source is a trained classifier
RULE_SOURCE = "rule"


@dataclass(frozen=True)
class Figure:
    """A figure written as PNG and SVG: file names (relative to the report folder), caption, alt text."""

    files: tuple[str, ...]
    caption: str
    alt: str
    width: int | None = None

    @property
    def png(self) -> str:
        return next(n for n in self.files if n.endswith(".png"))

    @property
    def svg(self) -> str | None:
        return next((n for n in self.files if n.endswith(".svg")), None)


@dataclass(frozen=True)
class Table:
    """A CSV file of the report: its name, header and rows of raw values (None: empty cell)."""

    name: str
    header: tuple[str, ...]
    rows: list[list]

    @property
    def records(self) -> list[dict]:
        """The rows as {column: value} dicts."""
        return [dict(zip(self.header, row)) for row in self.rows]


@dataclass
class Context:
    """What every section reads: `store` (open), `out` (the report folder), `run_id` (the main run), `compare`
    (the runs of table 4 and of the classifier section, main run first), `runs` ({id: `Store.list_runs` row})."""

    store: object
    out: Path
    run_id: int
    compare: list[int]
    runs: dict[int, dict]

    def not_papers(self, run_id: int | None = None) -> str | None:
        """Why the run (default the main run) is not in the paper's setting, or None when it is: the paper's numbers
        are shown beside a run's only then (`vinadv.report.paper.papers_setting`)."""
        return papers_setting(self.runs[self.run_id if run_id is None else run_id])

    def prefix(self, run_id: int) -> str:
        """File-name prefix of a run's own tables and figures: none for the main run, `runK_` for the others."""
        return "" if run_id == self.run_id else f"run{run_id}_"


class SectionData(Protocol):
    """What every section's dataclass has: its CSV tables and its figures (the files it wrote), listed by itself."""

    def tables(self) -> list[Table]: ...

    def figures(self) -> list[Figure]: ...


@dataclass
class ReportData:
    """Every section's data ({section id: its dataclass}, in the page's order), and the page's header facts:
    `header` (what the run was: planner spec, maps, seed), `not_papers` (why the main run is not in the paper's
    setting, None when it is: the paper's numbers are shown only then)."""

    run_id: int
    run_name: str | None
    compare: list[int]
    url: str
    version: str
    generated: str
    header: list[tuple[str, object]] = field(default_factory=list)
    not_papers: str | None = None
    sections: dict[str, SectionData] = field(default_factory=dict)

    def tables(self) -> list[Table]:
        return [t for data in self.sections.values() for t in data.tables()]

    def figures(self) -> list[Figure]:
        return [f for data in self.sections.values() for f in data.figures()]

    def files(self) -> list[str]:
        return sorted({*(t.name for t in self.tables()), *(n for f in self.figures() for n in f.files)})
