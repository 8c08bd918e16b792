"""pink, the library clik is compared with: whether it is installed, and with which QP solver."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

PINK_DAMPING = 1e-8
"""Tikhonov damping of pink's QP (its default 1e-12 makes daqp fail on some solves)."""


@dataclass(frozen=True)
class Pink:
    """An installed pink and the QP solver it is run with.

    Attributes:
        module: The imported ``pink`` module.
        solver: Name of the QP solver given to ``pink.solve_ik`` (``daqp`` or ``quadprog``).
    """

    module: Any
    solver: str


def find_pink() -> tuple[Pink | None, str | None]:
    """``(Pink, None)``, or ``(None, why not)`` when pink or a QP solver is missing."""
    try:
        import pink
        import qpsolvers
    except ImportError as exc:
        return None, f"pink not installed ({exc}); pip install 'clik[bench]'"
    for solver in ("daqp", "quadprog"):
        if solver in qpsolvers.available_solvers:
            return Pink(pink, solver), None
    return None, "no daqp or quadprog for pink; pip install daqp"
