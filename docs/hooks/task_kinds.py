"""MkDocs hook: the pages' lists of task kinds, made from the kinds themselves.

``docs/guides/scenarios.md`` holds the marker ``<!-- clik-task-kinds -->``; at build
time it is replaced by one row per registered kind (:data:`clik.tasks.registry.TASK_KINDS`):
its ``kind`` names, its keys (``table_keys``), its ``[tasks.trajectory]``
(``table_trajectory``) and the shipped scenario that uses it (``example``).
``docs/reference/api.md``'s marker ``<!-- clik-task-kind-api -->`` becomes each kind's
API entry (``::: clik.<Kind>``, read by mkdocstrings after this hook). A kind owns its
words: a new kind shows up at the next build, and no page is a hand copy.
"""

from __future__ import annotations

from typing import Any

MARKER = "<!-- clik-task-kinds -->"
"""Where the table goes in ``guides/scenarios.md``."""

PAGE = "guides/scenarios.md"
"""The page (relative to ``docs/``) that holds the marker."""

API_MARKER = "<!-- clik-task-kind-api -->"
"""Where the kinds' API entries go in ``reference/api.md``."""

API_PAGE = "reference/api.md"
"""The API page (relative to ``docs/``)."""


def table() -> str:
    """The Markdown table of every kind with a table of its own, in the registry's order."""
    from clik.tasks.registry import TASK_KINDS

    rows = [
        "| `kind` | keys | `[tasks.trajectory]` | example |",
        "|---|---|---|---|",
    ]
    for kind in TASK_KINDS:
        if not kind.table_keys:
            continue  # read from another kind's table (a relative task: a frame's)
        names = ", ".join(f'`"{name}"`' for name in kind.names)
        example = f"`{kind.example}`" if kind.example else ""
        rows.append(f"| {names} | {kind.table_keys} | {kind.table_trajectory} | {example} |")
    return "\n".join(rows)


def api_entries() -> str:
    """``::: clik.<Kind>`` for every registered kind (each exported from ``clik``)."""
    from clik.tasks.registry import TASK_KINDS

    return "\n\n".join(f"::: clik.{kind.__name__}" for kind in TASK_KINDS)


def on_page_markdown(markdown: str, page: Any, **_: Any) -> str:
    """Replace the markers of the scenario guide and the API page (MkDocs event)."""
    made = {PAGE: (MARKER, table), API_PAGE: (API_MARKER, api_entries)}
    if page.file.src_uri not in made:
        return markdown
    marker, make = made[page.file.src_uri]
    if marker not in markdown:
        raise RuntimeError(f"{page.file.src_uri}: the marker {marker} is missing")
    return markdown.replace(marker, make())
