"""MkDocs hook: the command-line reference generated from clik's own argparse parser.

``docs/reference/cli.md`` holds the marker ``<!-- clik-cli-reference -->``; at build time
it is replaced by ``clik --help`` and, for each subcommand, a section with its
``clik NAME --help``, read from :func:`clik.cli.parser`. The page is never a hand copy:
a new flag or subcommand shows up at the next build.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

MARKER = "<!-- clik-cli-reference -->"
"""Where the generated reference goes in ``reference/cli.md``."""

PAGE = "reference/cli.md"
"""The page (relative to ``docs/``) that holds the marker."""

WIDTH = "88"
"""Columns argparse wraps the help at (``COLUMNS``), so the page does not depend on the terminal."""


def subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """The parser's subcommands, by name, in the order they were added."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def reference() -> str:
    """The Markdown of the command-line reference: the top-level help, then each subcommand."""
    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = WIDTH
    try:
        from clik.cli import parser as clik_parser

        top = clik_parser()
        parts = ["## clik", "", "```text", top.format_help().rstrip(), "```", ""]
        for name, sub in subcommands(top).items():
            parts += [f"## clik {name}", "", "```text", sub.format_help().rstrip(), "```", ""]
    finally:
        if previous is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = previous
    return "\n".join(parts)


def on_page_markdown(markdown: str, page: Any, **_: Any) -> str:
    """Replace the marker of the CLI page with the generated reference (MkDocs event)."""
    if page.file.src_uri != PAGE:
        return markdown
    if MARKER not in markdown:
        raise RuntimeError(f"{PAGE}: the marker {MARKER} is missing; the CLI reference goes there")
    return markdown.replace(MARKER, reference())
