"""The report is byte-identical to a frozen baseline (issue 31), timestamps, measured durations and the machine
aside (`normalise_html`, `normalise_csv`).

The store is built so that every CPU gives the same rows: two runs of `greedy_planner.make` (integer logits, no
float ties) with exhaustive / key-points attacks (no gradients), and a classifier comparison read from
`baseline/evaluations.json` (rows of `vinadv evaluate` stored once, so no classifier is trained here). The planner's
quality and the processing times are the evaluation stage's (`vinadv.evaluation`), run on that store. The baseline
was frozen from the report as it was before the report stopped computing (issue 31), so the test holds that moving
the evaluation out of the report changed nothing on the page. The report's figures are drawn but not rendered
(`figures_not_rendered`, tests/report/formats.py: rendering them is most of a report's time): the page links them
by name, and their files are the other report tests'.

`baseline/` holds `index.html` and every CSV table, normalised, each as `<name>.txt` (data to compare, not a page
or a table of the project). To re-freeze after an intended change to the page:
`VINADV_WRITE_REPORT_BASELINE=1 pytest tests/report/test_report_baseline.py` (it rewrites the files and fails, so
a re-freeze is never silent), then review the diff.
"""

from __future__ import annotations

import csv
import io
import json
import os
import re
from pathlib import Path

import pytest
from tests.report.formats import figures_not_rendered

from vinadv.evaluation import evaluate_planner_quality, evaluate_timing
from vinadv.pipeline import RunConfig, run_pipeline
from vinadv.report import build_report
from vinadv.store import Store

pytestmark = pytest.mark.slow

BASELINE = Path(__file__).parent / "baseline"
PLANNER = "tests.report.greedy_planner:make"
#: (name, attack, obstacles): run 1 the main run (every category but UcP), run 2 (with UcP) in table 4 beside it
RUNS = (("exhaustive", "exhaustive", 2), ("key-points", "key-points", 2))
SIZE = 16

MASKS = (
    # the run's and the evaluations' times of creation, the page's time of writing
    (re.compile(r"\d{4}-\d{2}-\d{2}[ T]\d{2}:\d{2}:\d{2}(\.\d+)?"), "<TIME>"),
    # the machine the timings were measured on: `x86_64, 2 CPUs, Python 3.12.3`
    (re.compile(r"[\w.-]+, \d+ CPUs, Python [\d.]+\w*"), "<MACHINE>"),
    # durations as the page writes them (`render.seconds`): `12 s`, `0.25 s`, `3.1 ms`, `40 µs`
    (re.compile(r"(?<![\w.])\d[\d,]*(\.\d+)? (s|ms|µs)(?!\w)"), "<SECONDS>"),
)
#: CSV columns holding measured seconds
SECONDS_COLUMNS = {"training_s", "prediction_s_per_100", "seconds_measured", "seconds_per_100", "seconds"}
#: rows of `run_config.csv` (first column) whose value is measured: the run's stage durations
TIMING_KEYS = re.compile(r"^timings\.")


def normalise_text(text: str, tmp: Path) -> str:
    """`text` with the test's temporary folder as `<TMP>` and every `MASKS` match replaced."""
    text = text.replace(str(tmp), "<TMP>")
    for pattern, mask in MASKS:
        text = pattern.sub(mask, text)
    return text


def normalise_html(text: str, tmp: Path) -> str:
    return normalise_text(text, tmp)


def normalise_csv(text: str, tmp: Path) -> str:
    """The CSV, each cell as `normalise_text`, with the non-empty cells of `SECONDS_COLUMNS` and the values of the
    `TIMING_KEYS` rows as `<SECONDS>`."""
    rows = list(csv.reader(io.StringIO(text)))
    header = rows[0]
    masked = [i for i, name in enumerate(header) if name in SECONDS_COLUMNS]
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(header)
    for row in rows[1:]:
        row = [normalise_text(v, tmp) for v in row]
        row = ["<SECONDS>" if i in masked and row[i] != "" else v for i, v in enumerate(row)]
        if header == ["key", "value"] and TIMING_KEYS.match(row[0]):
            row[1] = "<SECONDS>"
        writer.writerow(row)
    return out.getvalue()


def build_store(folder: Path) -> tuple[str, list[int]]:
    """The baseline's database in `folder`: the two runs, the stored classifier comparison of run 1 and the
    evaluation stage's measurements of run 1."""
    url = f"sqlite:///{folder / 'baseline.db'}"
    ids = []
    for name, attack, obstacles in RUNS:
        config = RunConfig(n=120, size=SIZE, attack=attack, seed=3, shard_size=60, planner=PLANNER, obstacles=obstacles)
        ids.append(run_pipeline(config, db=url, name=name, progress=False).run_id)
    rows = json.loads((BASELINE / "evaluations.json").read_text(encoding="utf-8"))
    with Store.open(url) as store:
        store.add_evaluations(ids[0], rows)
        evaluate_planner_quality(store, ids[0])
        evaluate_timing(store, ids[0])
    return url, ids


def report_files(out: Path, tmp: Path) -> dict[str, str]:
    """{file name: normalised text} of the report's page and CSV tables."""
    files = {"index.html": normalise_html((out / "index.html").read_text(encoding="utf-8"), tmp)}
    for path in sorted(out.glob("*.csv")):
        files[path.name] = normalise_csv(path.read_text(encoding="utf-8"), tmp)
    return files


def test_report_matches_the_frozen_baseline(tmp_path):
    url, ids = build_store(tmp_path)
    out = tmp_path / "report"
    with figures_not_rendered():  # the baseline is the page and the tables: the figures' names, not their pixels
        build_report(url, out, run_id=ids[0], runs=ids)
    written = report_files(out, tmp_path)
    if os.environ.get("VINADV_WRITE_REPORT_BASELINE"):
        for old in BASELINE.glob("*.txt"):
            old.unlink()
        for name, text in written.items():
            (BASELINE / f"{name}.txt").write_text(text, encoding="utf-8")
        pytest.fail(f"baseline rewritten in {BASELINE} ({len(written)} files): review the diff, then run again")
    frozen = {p.stem: p.read_text(encoding="utf-8") for p in sorted(BASELINE.glob("*.txt"))}
    assert sorted(written) == sorted(frozen)
    for name in frozen:
        assert written[name] == frozen[name], name


def test_the_normaliser_masks_only_times_durations_and_machine(tmp_path):
    page = (
        f"written 2026-11-26 08:31:01 UTC in {tmp_path}/x.db; 12 s, 0.25 s, 3.1 ms, 40 µs, 1,234 s "
        "(x86_64, 2 CPUs, Python 3.12.3); 0.913, 5,000 pairs, 12x12 maps, run 3"
    )
    assert normalise_html(page, tmp_path) == (
        "written <TIME> UTC in <TMP>/x.db; <SECONDS>, <SECONDS>, <SECONDS>, <SECONDS>, <SECONDS> "
        "(<MACHINE>); 0.913, 5,000 pairs, 12x12 maps, run 3"
    )
    table = "key,value\nseed,3\ntimings.attack,1.5\ncreated (UTC),2026-11-26 08:31:01\n"
    assert normalise_csv(table, tmp_path) == "key,value\nseed,3\ntimings.attack,<SECONDS>\ncreated (UTC),<TIME>\n"
    table = "method,pairs,seconds_measured,paper_seconds\nrule,100,0.01,\nmanual,,,300.0\n"
    assert normalise_csv(table, tmp_path) == (
        "method,pairs,seconds_measured,paper_seconds\nrule,100,<SECONDS>,\nmanual,,,300.0\n"
    )
