"""Griffe extension: a Google ``Example:`` section read as ``Examples:`` (doctest code).

clik's docstrings title their doctest section ``Example:``; Griffe's Google parser takes
the singular as an admonition whose ``>>>`` lines are Markdown (block quotes, and
``x["a"]["b"]`` as a reference link). Renaming it before parsing makes it a code section.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

SINGULAR = re.compile(r"^(\s*)Example:\s*$", re.MULTILINE)
"""A section title ``Example:`` alone on its line."""


class SingularExamples(griffe.Extension):
    """Rename each docstring's ``Example:`` section to ``Examples:``."""

    def on_instance(self, *, obj: griffe.Object, **_: Any) -> None:
        """Rewrite the docstring before it is parsed (Griffe event)."""
        if obj.docstring is not None and "Example:" in obj.docstring.value:
            obj.docstring.value = SINGULAR.sub(r"\1Examples:", obj.docstring.value)
