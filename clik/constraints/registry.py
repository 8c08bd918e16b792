"""The kinds of constraint rows clik knows, in one place.

:data:`KINDS` lists every kind (the generic tests run over it); :data:`TABLE_KINDS`
those a scenario gives as an array of tables, ``[[constraints.<table>]]``, read by
:func:`clik.scenarios.scenario.parse_scenario` and built by
:func:`clik.scenarios.build_constraints.build_constraints` without naming them. A new kind is a
module with its :class:`~clik.constraints.kind.ConstraintKind`, its C++ type in
``src/engine/constraints/`` (registered in ``kinds.hpp``), and a line here.

What is said about a constraint by its key (a recovery record's check name and depth,
a violation record's words, a region's drawing) is said by the kind that owns the key,
found here by the key's prefix (:func:`kind_of`), not by a list of kinds elsewhere.
"""

from __future__ import annotations

from clik.constraints.cloud_avoidance import CloudAvoidance
from clik.constraints.cone import Cone
from clik.constraints.dexterity import Dexterity
from clik.constraints.joint_limits import JointLimits
from clik.constraints.kind import ConstraintKind
from clik.constraints.link_pairs import LinkPairs
from clik.constraints.obstacle_avoidance import ObstacleAvoidance
from clik.constraints.words import CROSSED, LimitWords
from clik.constraints.workspace import Workspace

TABLE_KINDS: tuple[type[ConstraintKind], ...] = (Workspace, Cone)
"""Kinds read from ``[[constraints.<table>]]`` arrays, in the order their rows follow."""

KINDS: tuple[type[ConstraintKind], ...] = (
    JointLimits,
    ObstacleAvoidance,
    LinkPairs,
    Dexterity,
    *TABLE_KINDS,
    CloudAvoidance,
)
"""Every kind, in the order a :class:`~clik.constraints.ConstraintSet` evaluates them."""


def kind_of(key: str) -> type[ConstraintKind] | None:
    """The registered kind that owns ``key`` (a row's key, a region's name), or None."""
    return next((kind for kind in KINDS if kind.owns(key)), None)


def limit_words(key: str) -> LimitWords:
    """How a crossed limit of constraint ``key`` reads: its kind's words.

    :data:`~clik.constraints.words.CROSSED` (the amount as it is) for a key no
    registered kind owns, or whose kind guards no limit.
    """
    kind = kind_of(key)
    words = None if kind is None else kind.limit_words
    return CROSSED if words is None else words
