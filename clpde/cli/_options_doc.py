"""docs/command-line.md's "Every option" section, written from the parsers themselves, so
that the page says what `clpde COMMAND --help` says (tests/cli/test_first_use_cli.py checks
that the page holds this text). After changing an option, rewrite the section with

    python -m clpde.cli._options_doc
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from . import build_parser

PAGE = Path(__file__).resolve().parents[2] / "docs" / "command-line.md"
BEGIN = "<!-- options: written by `python -m clpde.cli._options_doc` from the parsers -->"
END = "<!-- options end -->"
SKIPPED = ("--help", "--device")  # --device is the same on every command: the prose says it


def _subcommands(parser: argparse.ArgumentParser) -> argparse._SubParsersAction:
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))


def _usage(name: str, parser: argparse.ArgumentParser) -> str:
    if parser.usage:
        return parser.usage.replace("%(prog)s", f"clpde {name}")
    words = [f"clpde {name}"]
    for action in parser._actions:
        if not action.option_strings:
            words.append(action.metavar or action.dest)
            if action.nargs in ("+", "*"):
                words[-1] += "..."
        elif action.required:
            words.append(f"{action.option_strings[0]} {action.metavar or action.dest.upper()}")
    return " ".join(words + ["[options]"])


def _entry(formatter: argparse.HelpFormatter, action: argparse.Action) -> str:
    if action.option_strings:
        names = formatter._format_action_invocation(action).split(", ")
    else:
        names = [action.metavar or action.dest]
    text = " ".join(formatter._expand_help(action).split())
    return "- " + ", ".join(f"`{n}`" for n in names) + f": {text}"


def options_markdown() -> str:
    """The section's text: per command, its summary, usage and one line per option."""
    subcommands = _subcommands(build_parser())
    summaries = {a.dest: a.help for a in subcommands._choices_actions}
    parts = []
    for name, parser in subcommands.choices.items():
        formatter = parser._get_formatter()
        lines = [f"### `clpde {name}`: {summaries[name]}", "", f"`{_usage(name, parser)}`", ""]
        lines += [
            _entry(formatter, action)
            for action in parser._actions
            if action.help != argparse.SUPPRESS and not set(action.option_strings) & set(SKIPPED)
        ]
        parts.append("\n".join(lines))
    return "\n\n".join(parts) + "\n"


def page_section(page: str) -> str:
    """The generated section as it stands in the page's text."""
    match = re.search(re.escape(BEGIN) + r"\n\n(.*?)\n" + re.escape(END), page, re.S)
    if match is None:
        raise ValueError(f"{PAGE} has no {BEGIN!r} ... {END!r} block")
    return match.group(1)


def main() -> None:
    page = PAGE.read_text()
    old = page_section(page)
    PAGE.write_text(page.replace(old, options_markdown(), 1))
    print(f"wrote the options of every command into {PAGE}")


if __name__ == "__main__":
    main()
