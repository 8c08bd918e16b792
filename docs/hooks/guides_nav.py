"""MkDocs hook: the Guides section of the navigation, from the files in ``docs/guides/``.

``mkdocs.yml`` says ``- Guides: guides/``; this hook replaces that entry with every
``docs/guides/*.md``: first those named in :data:`GUIDES_ORDER` (the order a reader
takes them in), then any other guide by file name. A guide cannot be left out of the
site, and a name in the list without its file is simply not shown.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

FOLDER = "guides/"
"""The nav entry's placeholder value, and the folder under ``docs/``."""

GUIDES_ORDER = (
    "python",
    "scenarios",
    "trajectories",
    "constraints",
    "robots",
    "statuses",
    "views-and-plots",
    "sweeps",
    "export",
    "online-control",
    "ros",
    "simulate",
    "performance",
)
"""File stems of the guides in reading order."""


def guide_pages(docs_dir: Path) -> list[str]:
    """The guides' paths relative to ``docs_dir``, in reading order."""
    stems = sorted(p.stem for p in (docs_dir / FOLDER).glob("*.md"))
    ordered = [s for s in GUIDES_ORDER if s in stems] + [s for s in stems if s not in GUIDES_ORDER]
    return [f"{FOLDER}{stem}.md" for stem in ordered]


def on_config(config: Any, **_: Any) -> Any:
    """Fill the ``Guides: guides/`` nav entry (MkDocs event)."""
    for entry in config["nav"] or []:
        if isinstance(entry, dict) and entry.get("Guides") == FOLDER:
            entry["Guides"] = guide_pages(Path(config["docs_dir"]))
    return config
