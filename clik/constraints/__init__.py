"""Constraints as extra task rows (docs/method.md, "Constraints enlarge the task").

Each constraint contributes, while active, one row to the extended task of
eqs. (20)-(25): an error ``e_c`` (positive when its threshold is violated), a
Jacobian row ``j_c`` and a feed-forward term ``f_c`` such that
``edot_c = f_c - j_c qdot``. The law then runs on ``J_e = (J; j_c ...)`` and
``e_e = (e; e_c ...)``.

A kind of row is one class (:class:`ConstraintKind`, :mod:`clik.constraints.kind`)
and one C++ type; the core (:class:`ConstraintRun`) never names a kind:

- :class:`JointLimits`: joint-range rows, eqs. (16)-(19).
- :class:`ObstacleAvoidance`: link-obstacle rows, eqs. (13)-(15), on
  :class:`Obstacle` (sphere, box, capsule, cylinder, mesh hull).
- :class:`LinkPairs`: link-link rows (self-collision).
- :class:`Dexterity`: the dexterity row, ``w(q) >= w_min`` on the task's
  manipulability (D1)-(D3) (clik's addition; the paper's future work).
- :class:`Workspace`: a frame's origin kept inside a box, (W1)-(W2).
- :class:`Cone`: a frame axis kept within an angle of a direction, (C1)-(C3).
- :func:`obstacle_row`: obstacle rows, eqs. (13)-(15), in the paper's squared form
  or the normalised one.
- :class:`CollisionScene`: link geometry (convex) and obstacles, with pruning; each
  run places it in its own :class:`~clik.constraints.collision_scene.SceneRun`.
- :class:`ConstraintSet`: activation, release, the ``n - m`` bound (22), events.
- :mod:`~clik.constraints.pose_check`: is one configuration clear of its constraints
  (solve mode; :mod:`~clik.constraints.recovery`: a run that started inside a threshold).
- :class:`~clik.constraints.read_only.ReadOnlyList`: the read-only sequences a set and
  its kinds show (``cset.obstacles``): a set changes only through its methods.
"""

from clik.constraints.cloud_avoidance import CloudAvoidance
from clik.constraints.collision_scene import (
    CollisionScene,
    NoCollisionGeometryWarning,
    SkippedGeometryWarning,
)
from clik.constraints.cone import Cone
from clik.constraints.constraint_run import ConstraintRun
from clik.constraints.constraint_set import RELEASE_RULES, ConstraintSet
from clik.constraints.dexterity import Dexterity
from clik.constraints.joint_limits import JointLimits
from clik.constraints.kind import Candidate, ConstraintKind, KindRun
from clik.constraints.link_pairs import LinkPairs
from clik.constraints.obstacle import SHAPES, Obstacle
from clik.constraints.obstacle_avoidance import ObstacleAvoidance
from clik.constraints.obstacle_rows import FORMS, obstacle_row, point_jacobian
from clik.constraints.workspace import Workspace

__all__ = [
    "FORMS",
    "RELEASE_RULES",
    "SHAPES",
    "Candidate",
    "CloudAvoidance",
    "CollisionScene",
    "Cone",
    "ConstraintKind",
    "ConstraintRun",
    "ConstraintSet",
    "Dexterity",
    "JointLimits",
    "KindRun",
    "LinkPairs",
    "NoCollisionGeometryWarning",
    "Obstacle",
    "ObstacleAvoidance",
    "SkippedGeometryWarning",
    "Workspace",
    "obstacle_row",
    "point_jacobian",
]
