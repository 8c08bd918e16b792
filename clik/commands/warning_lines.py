"""Warnings on the command line: one clean line each, each distinct message once.

Python's own format shows the source file, line number and the source line
(``runner.py:109: MimicJointWarning: ... robot = Robot.load(``), and prints a
warning again from every place that raises it. On the command line
:func:`cli_warnings` prints instead::

    clik: warning: <message> [MimicJointWarning]

once per distinct message and category for the whole command. Python API
users keep Python's normal warnings: the previous ``warnings.showwarning`` and
filters come back when the command ends.
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TextIO


def warning_line(message: Warning | str, category: type[Warning]) -> str:
    """The line printed for one warning: ``clik: warning: <message> [<category>]``.

    Args:
        message: The warning (or its text).
        category: Its class; Python's generic ``UserWarning`` is not named.

    Returns:
        One line, without the newline (a multi-line message is joined with ``; ``).
    """
    text = "; ".join(part.strip() for part in str(message).splitlines() if part.strip())
    if category is UserWarning:
        return f"clik: warning: {text}"
    return f"clik: warning: {text} [{category.__name__}]"


@contextmanager
def cli_warnings(stream: TextIO | None = None) -> Iterator[set[str]]:
    """Print warnings raised inside the block as :func:`warning_line`, each once.

    Args:
        stream: Where the lines go (default: ``sys.stderr`` at the time of printing).

    Yields:
        The set of lines printed so far (for tests).
    """
    seen: set[str] = set()

    def show(
        message: Warning | str,
        category: type[Warning],
        filename: str,
        lineno: int,
        file: TextIO | None = None,
        line: str | None = None,
    ) -> None:
        text = warning_line(message, category)
        if text in seen:
            return
        seen.add(text)
        out = stream if stream is not None else sys.stderr
        try:
            print(text, file=out)
        except (OSError, ValueError):  # stderr closed: a warning is not worth a crash
            pass

    with warnings.catch_warnings():
        # Last in the list: filters set before (``-W error``, a test's ``ignore``) still win;
        # a warning no filter names reaches ``show`` from every place, which keeps one per text.
        warnings.filterwarnings("always", append=True)
        warnings.showwarning = show
        yield seen
