"""Null-space objectives, the ``z`` of eq. (5): ``qdot = J^+ xdot + (I - J^+ J) z``."""

from clik.objectives.objective import OBJECTIVE_KINDS, Objective

__all__ = ["OBJECTIVE_KINDS", "Objective"]
