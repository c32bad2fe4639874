"""The documentation cannot go stale: the CLI reference is the parsers' help, the results are the committed metrics.

The site itself is built by `make docs` (`mkdocs build --strict`, in CI); these tests hold what the build cannot see.
"""

import importlib
import json
import re
from pathlib import Path

import matplotlib.pyplot as plt
import pytest

import vinadv.plot.files
from tests.docs_hooks import DOCS, ROOT, WEIGHTS, docs_module
from vinadv.attacks.pairs import PAIRS_FORMAT
from vinadv.classify.base import MODEL_FORMAT
from vinadv.cli import build_parser
from vinadv.commands.store import EXPORT_FORMAT
from vinadv.grid.mapset import MAPS_FORMAT
from vinadv.planners.gppn import GPPN_FORMAT
from vinadv.planners.pathset import PATHS_FORMAT
from vinadv.planners.vin.weights import WEIGHTS_FORMAT


def test_the_cli_reference_is_the_parsers_help():
    gen_cli = docs_module("gen_cli")
    assert (DOCS / "reference" / "cli.md").read_text() == gen_cli.render(), (
        "docs/reference/cli.md is stale: run .venv/bin/python docs/gen_cli.py"
    )


def test_the_cli_reference_has_every_command():
    gen_cli = docs_module("gen_cli")
    text = gen_cli.render()
    commands = [words for words, _ in gen_cli.walk(build_parser())]
    assert "vinadv maps generate" in commands and "vinadv run" in commands and "vinadv gppn train" in commands
    for words in commands:
        assert f"`{words}`\n\n```text\nusage: {words} " in text


def test_the_results_table_is_read_from_the_metrics_files(tmp_path):
    hooks = docs_module("hooks")
    table = hooks.weights_table()
    for metrics in sorted(WEIGHTS.glob("*.metrics.json")):
        data = json.loads(metrics.read_text())
        figures = data.get("vinadv", data)
        weights = metrics.name.replace(".metrics.json", ".pt")
        row = next(line for line in table.splitlines() if f"| `{weights}` |" in line)
        assert f"{100 * figures['success_rate']:.1f}%" in row or f"{100 * figures['success_rate']:.2f}%" in row
        assert f"{figures['rollouts']:,}" in row
        assert data["command"] in hooks.weights_commands()
    # a re-measured file changes the table: nothing is copied by hand
    (tmp_path / "vin28.metrics.json").write_text(
        json.dumps(
            {
                "weights_sha256": "ab" * 32,
                "command": "vinadv vin eval --n 10",
                "size": 28,
                "success_rate": 0.5,
                "rollouts": 10,
                "optimal_rate": 0.25,
                "action_accuracy": 0.999996,
            }
        )
    )
    assert hooks.weights_table(tmp_path).splitlines()[2] == (
        "| `vin` | `vin28.pt` | 50.0% of 10 | 25.0% | 100.00% |  |  |"
    )


def test_the_hook_fills_the_results_page(monkeypatch):
    hooks = docs_module("hooks")
    monkeypatch.setattr(hooks, "by_length_svg", lambda folder: "<svg/>")  # drawn for real in the slow test below
    page = (DOCS / "results" / "index.md").read_text()
    for name in ("weights-table", "weights-commands", "by-length", "by-length-figure"):
        assert f"<!-- vinadv:{name} -->" in page
    filled = hooks.on_page_markdown(page, page=None, config=None, files=None)
    assert "<!-- vinadv:" not in filled and hooks.weights_table() in filled
    assert "| 25-29 |" in hooks.by_length_table()
    assert "](data:image/svg+xml;base64,PHN2Zy8+)" in filled  # base64 of "<svg/>"


@pytest.mark.slow  # matplotlib's import and a figure: about two seconds
def test_the_length_curve_draws_every_metrics_file_with_rows_by_length():
    hooks = docs_module("hooks")
    svg = hooks.by_length_svg()
    drawn = [e for e in hooks.weights_metrics() if e["vinadv"].get("by_length")]
    assert drawn  # the shipped files record rows by length
    for entry in drawn:
        assert entry["weights"] in svg  # the legend names each file
        for row in entry["vinadv"]["by_length"]:
            assert f"{row['moves'][0]}-{row['moves'][1]}" in svg  # each bucket labelled
    assert svg == hooks.by_length_svg()  # same files, same bytes: the page changes only with the data


def test_user_facing_pages_name_public_sources_not_the_workspace():
    pages = [ROOT / "README.md", *DOCS.rglob("*.md")]
    for page in pages:
        assert not re.search(r"shared/data|/work/", page.read_text()), page


NOT_PYTHON = {"vinadv.db", "vinadv.by_length"}  # a database file name; a key of `vinadv eval --json`


def named_objects() -> set[str]:
    """Every `vinadv.x.y` the README and the pages name in code spans, file formats (`vinadv.maps/1`) left out."""
    pages = [ROOT / "README.md", *DOCS.rglob("*.md")]
    names = set()
    for page in pages:
        for name, after in re.findall(r"`(vinadv(?:\.\w+)+)(.?)", page.read_text()):
            if after not in "/-" or not after:
                names.add(name)
    return names - NOT_PYTHON


def test_every_python_name_the_docs_give_exists():
    missing = []
    for name in sorted(named_objects()):
        parts = name.split(".")
        for cut in range(len(parts), 0, -1):  # the longest importable module, then attributes
            try:
                obj = importlib.import_module(".".join(parts[:cut]))
            except ModuleNotFoundError:
                continue
            for attr in parts[cut:]:
                obj = getattr(obj, attr, None)
            if obj is None:
                missing.append(name)
            break
    assert not missing, f"the docs name what the code no longer has: {missing}"


def test_the_readme_is_a_front_page():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    for heading in ("## Install", "## A five-minute tour", "## Documentation", "## Citing", "## Licence"):
        assert f"\n{heading}\n" in text
    for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", text):  # every relative link leads to a file
        assert (ROOT / target).exists(), target


def test_the_readme_results_table_is_the_generated_one():
    hooks = docs_module("hooks")
    assert hooks.readme_table((ROOT / "README.md").read_text()) == hooks.weights_table(), (
        "README.md's results table is stale: run .venv/bin/python docs/hooks.py"
    )


def test_the_formats_page_names_every_file_format_version():
    page = (DOCS / "formats.md").read_text()
    for name in (MAPS_FORMAT, PATHS_FORMAT, PAIRS_FORMAT, WEIGHTS_FORMAT, GPPN_FORMAT, MODEL_FORMAT, EXPORT_FORMAT):
        assert f'"{name}"' in page or f"`{name}`" in page, f"docs/formats.md does not describe {name}"


@pytest.mark.slow  # matplotlib's import and a k curve per suite, drawn: seconds
def test_the_benchmark_page_carries_the_leaderboard_of_the_committed_entries(monkeypatch):
    hooks = docs_module("hooks")
    # the figures are drawn, not rendered to SVG (tests/plot/test_curves.py renders one): a second each
    monkeypatch.setattr(vinadv.plot.files, "svg_text", lambda fig: plt.close(fig) or "<svg/>")
    page = (DOCS / "results" / "bench.md").read_text()
    assert "<!-- vinadv:bench-leaderboard -->" in page
    board = hooks.on_page_markdown(page)
    entries = sorted((DOCS / "results" / "bench").glob("*.json"))
    assert entries, "no committed benchmark entry"
    for path in entries:  # every committed entry is a row, linked from the page
        assert f"(bench/{path.name})" in board
    # the compact table in its own box, its legend, and one k curve per suite drawn in place of the marker
    assert '<div class="leaderboard" markdown>' in board and "**harmful, k = 1**:" in board
    assert "<!-- vinadv:bench-k-curves -->" in page and "<!-- vinadv:" not in board
    suites = {json.loads(p.read_text())["suite"]["name"] for p in entries}
    assert board.count("](data:image/svg+xml;base64,") == len(suites)


def test_algorithm_stars_are_text_not_emphasis_outside_code():
    hooks = docs_module("hooks")
    text = "Beside A*, weighted A* and **bold** `A*, A*`\n```sh\nA*, A*\n```\nNeural A*'s"
    assert hooks.escape_algorithm_stars(text) == (
        "Beside A\\*, weighted A\\* and **bold** `A*, A*`\n```sh\nA*, A*\n```\nNeural A\\*'s"
    )


#: the README's word that the built site, not GitHub's rendering of docs/, is where the pages are read whole
SITE_IS_THE_PLACE = "the site is the place to read the documentation"


def test_pages_github_shows_incomplete_send_the_reader_to_the_site():
    # GitHub renders docs/*.md without the snippets extension and without the hooks: a `--8<--` line shows as itself
    # and a figure's marker as nothing; such pages are allowed only while the README says to read the built site
    incomplete = [
        str(page.relative_to(ROOT))
        for page in sorted(DOCS.rglob("*.md"))
        if re.search(r"^\s*--8<--|<!-- vinadv:", page.read_text(), re.M)
    ]
    assert "docs/own-planner.md" in incomplete and "docs/guide/neural-astar.md" in incomplete
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert SITE_IS_THE_PLACE in readme, (
        f"{incomplete} read incomplete on GitHub; the README must say: {SITE_IS_THE_PLACE}"
    )


def shell_blocks(text: str) -> list[str]:
    return re.findall(r"```(?:sh|bash|console)\n(.*?)```", text, re.S)


def unmade_folders(text: str) -> list[str]:
    """The commands of a page's shell blocks that write a file (`--out`, `--report`, `--db`, `--index`) into a
    relative folder that nothing before them on the page made (`mkdir`, or an output that is a folder)."""
    made, wrong = set(), []
    for block in shell_blocks(text):
        for line in block.splitlines():
            made.update(folder.rstrip("/") for folder in re.findall(r"mkdir (?:-p )?(\S+)", line))
            for value in re.findall(r"--(?:out|report|db|index)[ =](\S+)", line):
                path = Path(value)
                if value.endswith("/") or not path.suffix:  # a folder the command makes
                    made.add(value.rstrip("/"))
                elif (
                    str(path.parent) != "."
                    and not value.startswith(("/", "<", "$", "~"))
                    and str(path.parent) not in made
                ):
                    wrong.append(line.strip())
    return wrong


def test_the_docs_commands_write_only_into_folders_that_exist():
    assert unmade_folders("```sh\nvinadv bench run --out entries/vin.json\n```\n") == [
        "vinadv bench run --out entries/vin.json"
    ]
    assert not unmade_folders("```sh\nmkdir -p entries\nvinadv bench run --out entries/vin.json\n```\n")
    pages = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]
    wrong = {str(p.relative_to(ROOT)): unmade_folders(p.read_text()) for p in pages}
    assert not {page: lines for page, lines in wrong.items() if lines}


def test_a_diagonal_of_sqrt_2_is_said_of_octile_moves():
    # `moore` moves all cost 1 and `news` has no diagonal: a paragraph that gives a diagonal sqrt 2 says it is octile's
    wrong = []
    for page in [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]:
        for paragraph in page.read_text().split("\n\n"):
            if re.search(r"diagonal[^.|]*(sqrt ?\(?2|√2)", paragraph) and "octile" not in paragraph:
                wrong.append(f"{page.relative_to(ROOT)}: {paragraph[:100]}")
    assert not wrong


def test_make_demo_says_how_long_it_takes():
    makefile = (ROOT / "Makefile").read_text()
    recipe = makefile.split("\ndemo:", 1)[1].split("\n\n", 1)[0]
    (echo,) = [line for line in recipe.splitlines() if "@echo" in line and "minutes" in line]
    minutes = re.search(r"about (\d+) minutes", echo).group(1)
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert f"about {minutes} minutes" in readme.split("make demo", 1)[1].split("make test", 1)[0]
