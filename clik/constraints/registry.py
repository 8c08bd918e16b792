"""The kinds of constraint rows clik knows, in one place.

:data:`KINDS` lists every kind (the generic tests run over it); :data:`TABLE_KINDS`
those a scenario gives as an array of tables, ``[[constraints.<table>]]``, read by
:func:`clik.scenarios.scenario.parse_scenario` and built by
:func:`clik.scenarios.build_constraints.build_constraints` without naming them. A new kind is a
module with its :class:`~clik.constraints.kind.ConstraintKind`, its C++ type in
``src/engine/constraints/`` (registered in ``kinds.hpp``), and a line here.
"""

from __future__ import annotations

from clik.constraints.cone import Cone
from clik.constraints.dexterity import Dexterity
from clik.constraints.joint_limits import JointLimits
from clik.constraints.kind import ConstraintKind
from clik.constraints.link_pairs import LinkPairs
from clik.constraints.obstacle_avoidance import ObstacleAvoidance
from clik.constraints.workspace import Workspace

TABLE_KINDS: tuple[type[ConstraintKind], ...] = (Workspace, Cone)
"""Kinds read from ``[[constraints.<table>]]`` arrays, in the order their rows follow."""

KINDS: tuple[type[ConstraintKind], ...] = (
    JointLimits,
    ObstacleAvoidance,
    LinkPairs,
    Dexterity,
    *TABLE_KINDS,
)
"""Every kind, in the order a :class:`~clik.constraints.ConstraintSet` evaluates them."""
