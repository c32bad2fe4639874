"""The command line's help says only what is there: every `--flag` a help text names is a flag of the command it
names (its own, or the command a code span in it spells out), and every planner it names is registered."""

import argparse
import re
from pathlib import Path

import pytest

from tests.docs_hooks import docs_module
from vinadv.cli import build_parser
from vinadv.planners.registry import ALIASES, REGISTRY, canonical_name

FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")


def commands(parser: argparse.ArgumentParser, words: tuple[str, ...] = ()) -> dict[tuple[str, ...], object]:
    """Every command's parser by its words after `vinadv` (`()` the top level; aliases left out)."""
    found = {words: parser}
    for name, sub in docs_module("gen_cli").subcommands(parser).items():
        found |= commands(sub, (*words, name))
    return found


PARSERS = commands(build_parser())


def flags(parser: argparse.ArgumentParser) -> set[str]:
    return {option for action in parser._actions for option in action.option_strings}


def help_texts(words: tuple[str, ...]) -> list[tuple[tuple[str, ...], str]]:
    """(the command a text speaks for, the text) of everything `vinadv WORDS --help` prints: the description, the
    epilog and the options' help (the command's own), and each subcommand's line (that subcommand's)."""
    parser = PARSERS[words]
    texts = [(words, parser.description or ""), (words, parser.epilog or "")]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            texts += [((*words, choice.dest), choice.help or "") for choice in action._choices_actions]
        else:
            texts.append((words, action.help or ""))
    return texts


def named_command(span: str) -> tuple[str, ...] | None:
    """The command a code span spells out (`vinadv maps import --format mpd`, `gppn train --init OUT`): the longest
    run of its first words, `vinadv` dropped, that is a command; None when it names none."""
    words = span.split()
    words = words[1:] if words[:1] == ["vinadv"] else words
    for n in range(len(words), 0, -1):
        if tuple(words[:n]) in PARSERS:
            return tuple(words[:n])
    return None


def misnamed_flags(words: tuple[str, ...], text: str) -> list[str]:
    """The flags `text` (help of the command `words`) names that its command lacks: a code span naming a command
    (`vinadv plan --planner gppn`) is checked against that command, the rest against `words`'s own flags."""
    wrong = []
    pieces = text.split("`")  # even pieces are prose, odd ones code spans
    for i, piece in enumerate(pieces):
        owner = words
        if i % 2 == 1:
            owner = named_command(piece) or words
        wrong += [f"{' '.join(owner)}: {f}" for f in FLAG.findall(piece) if f not in flags(PARSERS[owner])]
    return wrong


def test_the_walk_reaches_every_command():
    assert ("robustness",) in PARSERS and ("bench", "run") in PARSERS and ("neural-astar", "train") in PARSERS


@pytest.mark.parametrize("words", sorted(PARSERS), ids=lambda words: " ".join(("vinadv", *words)))
def test_every_flag_a_help_names_exists(words):
    wrong = [name for owner, text in help_texts(words) for name in misnamed_flags(owner, text)]
    assert not wrong, f"`{' '.join(('vinadv', *words))} --help` names flags that are not there: {wrong}"


def test_the_check_catches_a_flag_of_another_command():
    assert misnamed_flags(("robustness",), "--obstacles K frees K greedily") == ["robustness: --obstacles"]
    assert misnamed_flags(("robustness",), "as `vinadv attack --obstacles K` does") == []
    assert misnamed_flags(("robustness",), "as `vinadv attack --max-obstacles K`") == ["attack: --max-obstacles"]


def planner_help(words: tuple[str, ...]) -> str:
    (action,) = [a for a in PARSERS[words]._actions if "--planner" in a.option_strings]
    return action.help


PLANNER_COMMANDS = sorted(words for words, parser in PARSERS.items() if "--planner" in flags(parser))


@pytest.mark.parametrize("words", PLANNER_COMMANDS, ids=lambda words: " ".join(("vinadv", *words)))
def test_the_planner_help_lists_every_registered_planner(words):
    text = planner_help(words)
    missing = [name for name in REGISTRY if not re.search(rf"(?<![\w-]){re.escape(name)}(?![\w-])", text)]
    assert not missing, f"`{' '.join(('vinadv', *words))} --help` leaves out the registered planners {missing}"


def planner_names(text: str) -> list[str]:
    """The planner names `--planner NAME` gives in `text`: a spec's name without its parameters or `+d4`; a file or
    module spec (`FILE.py:FACTORY`, `pkg.mod:make`) and placeholders in capitals (`NAME`, `P`) left out."""
    names = []
    for value in re.findall(r"--planner[ =]+([A-Za-z][\w.:/=+-]*)", text):
        head = canonical_name(value.removesuffix("+d4")).split(":", 1)[0]
        if value.split(":", 1)[0].endswith(".py") or "." in head or "/" in head or head != head.lower():
            continue
        if head in {"or", "accepts", "loads"}:  # prose: "--planner or --weights", "--planner accepts ..."
            continue
        names.append(head)
    return names


def test_every_planner_the_help_and_the_docs_name_is_registered():
    root = Path(__file__).resolve().parents[1]
    pages = [root / "README.md", *sorted((root / "docs").rglob("*.md"))]
    texts = {str(page.relative_to(root)): page.read_text() for page in pages}
    for words in PARSERS:
        texts[f"{' '.join(('vinadv', *words))} --help"] = "\n".join(text for _, text in help_texts(words))
    named = {where: planner_names(text) for where, text in texts.items()}
    assert sum(len(names) for names in named.values()) > 50  # the search read the pages
    unknown = {
        where: sorted(set(n for n in names if n not in REGISTRY and n not in ALIASES)) for where, names in named.items()
    }
    assert not {where: names for where, names in unknown.items() if names}
