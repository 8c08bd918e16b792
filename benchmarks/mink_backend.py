"""mink (differential IK on MuJoCo), the second library clik's tick lines are compared with."""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any

MINK_INSTALL = "pip install 'clik[bench]'"
"""How to get mink and MuJoCo (the ``bench`` extra)."""


@dataclass(frozen=True)
class Mink:
    """An installed mink, its MuJoCo and the QP solver it is run with.

    Attributes:
        module: The imported ``mink`` module.
        mujoco: The imported ``mujoco`` module.
        solver: Name of the QP solver given to ``mink.solve_ik`` (``daqp`` or ``quadprog``).
    """

    module: Any
    mujoco: Any
    solver: str


def find_mink() -> tuple[Mink | None, str | None]:
    """``(Mink, None)``, or ``(None, why not)`` when mink, MuJoCo or a QP solver is missing."""
    try:  # imported by name: neither is needed to type-check clik
        mink = importlib.import_module("mink")
        mujoco = importlib.import_module("mujoco")
        qpsolvers = importlib.import_module("qpsolvers")
    except ImportError as exc:
        return None, f"mink or mujoco not installed ({exc}); {MINK_INSTALL}"
    for solver in ("daqp", "quadprog"):
        if solver in qpsolvers.available_solvers:
            return Mink(mink, mujoco, solver), None
    return None, "no daqp or quadprog for mink; pip install daqp"
