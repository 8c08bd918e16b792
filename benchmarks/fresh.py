"""A measurement in a fresh interpreter: one function of this suite, its report as JSON.

The memory figures are each measured in a new process of this interpreter
(``sys.executable``), so that neither the suite's other lines nor another measurement
leave memory behind. The suite is not installed with clik: the child finds it by the
checkout's root, put last on its path (as ``clik bench`` does), and imports clik as any
process started here would.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

CHECKOUT = Path(__file__).resolve().parents[1]
"""The clik checkout this suite is in (the folder holding ``benchmarks/``)."""


def child_code(function: Callable[..., dict[str, Any]]) -> str:
    """What the child runs: ``function`` on its integer arguments, the report as last line.

    Args:
        function: A module-level function of this suite returning a JSON-able dict.
    """
    return (
        "import json, sys\n"
        f"sys.path.append({str(CHECKOUT)!r})\n"
        f"from {function.__module__} import {function.__name__}\n"
        f"print(json.dumps({function.__name__}(*map(int, sys.argv[1:]))))\n"
    )


def run_fresh(function: Callable[..., dict[str, Any]], *args: int, what: str) -> dict[str, Any]:
    """``function(*args)`` in a subprocess of this interpreter; its report.

    Args:
        function: A module-level function of this suite returning a JSON-able dict.
        *args: Its integer arguments.
        what: The measurement, as an error names it (``"memory"``).

    Raises:
        RuntimeError: The subprocess failed (its stderr's end in the message).
    """
    proc = subprocess.run(
        [sys.executable, "-c", child_code(function), *map(str, args)],
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{what} subprocess failed:\n{proc.stderr[-2000:]}")
    result: dict[str, Any] = json.loads(proc.stdout.strip().splitlines()[-1])
    return result
