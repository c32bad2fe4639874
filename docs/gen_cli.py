"""Write the CLI reference, docs/reference/cli.md, from the `vinadv` argparse parsers.

Run it after changing a command: `.venv/bin/python docs/gen_cli.py` (`--check` exits 1 when the committed file
is stale, as `tests/test_docs.py` does). Every command and subcommand gets its own section holding its `--help`,
formatted at a fixed width so the file does not depend on the terminal it was made in.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CLI_MD = ROOT / "docs" / "reference" / "cli.md"
WIDTH = 100  # argparse wraps help at the terminal's width less 2: COLUMNS is set to WIDTH + 2 while formatting

HEADER = """# Command line reference

Generated from the parsers by `docs/gen_cli.py`; do not edit by hand (a test fails when this page is stale).
Every command exits with status 2 and one line naming the flag, file or field at fault on bad input.
"""


def subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """The parser's subcommands by name, in the order they were added (aliases left out)."""
    found: dict[str, argparse.ArgumentParser] = {}
    for action in parser._actions:  # argparse keeps subparsers only here
        if isinstance(action, argparse._SubParsersAction):
            seen = set()
            for name, sub in action.choices.items():
                if id(sub) not in seen:
                    seen.add(id(sub))
                    found[name] = sub
    return found


def walk(parser: argparse.ArgumentParser, words: tuple[str, ...] = ("vinadv",)) -> Iterator[tuple[str, str]]:
    """(command line, help text) of `parser` and every subcommand below it, depth first."""
    yield " ".join(words), parser.format_help()
    for name, sub in subcommands(parser).items():
        yield from walk(sub, (*words, name))


def render() -> str:
    """The whole reference page."""
    saved = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(WIDTH + 2)
    try:
        sys.path.insert(0, str(ROOT / "src"))
        from vinadv.cli import build_parser  # noqa: PLC0415 (the checkout's src/, put on the path just above)

        parser = build_parser()
        sections = [HEADER]
        for words, text in walk(parser):
            level = "#" * min(2 + words.count(" ") - 1, 4) if " " in words else "##"
            sections.append(f"{level} `{words}`\n\n```text\n{text.rstrip()}\n```\n")
        return "\n".join(sections)
    finally:
        sys.path.remove(str(ROOT / "src"))
        if saved is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = saved


def main(argv: list[str] | None = None) -> int:
    check = "--check" in (argv if argv is not None else sys.argv[1:])
    text = render()
    if check:
        if not CLI_MD.exists() or CLI_MD.read_text() != text:
            print(f"{CLI_MD.relative_to(ROOT)} is stale: run python docs/gen_cli.py", file=sys.stderr)
            return 1
        return 0
    CLI_MD.write_text(text)
    print(f"wrote {CLI_MD.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
