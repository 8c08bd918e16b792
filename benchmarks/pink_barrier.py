"""The three spheres as pink's collision barrier, the closest pink has to clik's obstacle rows.

pink's barriers (``pink.barriers``) hold no "sphere obstacle" kind:
``BodySphericalBarrier`` keeps two frames' origins apart and ``PositionBarrier``
bounds a frame's position. ``SelfCollisionBarrier`` takes the pairs of the
configuration's collision model, whatever they hold, and keeps their coal
distances above ``d_min`` through each pair's witness points. So the spheres
enter pink's collision model as ``coal.Sphere`` geometries on the world joint,
paired with each of the Panda's link geometries (the convex hulls clik collides,
:func:`~benchmarks.sphere_scene.sphere_geometry`): like against like, 3 x 17 pairs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import pinocchio as pin

import clik
from benchmarks.sphere_scene import sphere_geometry

OBSTACLE_THRESHOLD = 0.03
"""The distance every tool keeps from a sphere [m]: clik's default obstacle threshold
``d_o``, pink's ``d_min`` and mink's ``minimum_distance_from_collisions``."""
BARRIER_PAIRS = 3
"""Pairs pink's barrier puts in the QP each step: its ``n_collision_pairs``, the closest
pairs of all 51 (one per sphere, or the nearest links of one); pink computes every
pair's distance each step all the same."""
BARRIER_GAIN = 100.0
"""pink's barrier gain [1/s] (``J qdot >= -gain (d - d_min)``), its barrier example's
(``examples/barriers/arm_ur5.py``). The Panda starts 0.028 m from a sphere, inside
``d_min``: 850 1/s (mink's default, 85 % of the margin per 1 ms tick) pushes it out
at 3.9 times the URDF joint speed on the first tick; 20 and 100 track alike."""


@dataclass(frozen=True)
class PinkObstacles:
    """pink's collision barrier on the spheres and the collision model it reads.

    Attributes:
        collision_model: Link geometries, spheres and their pairs.
        barriers: ``[SelfCollisionBarrier]``, as ``solve_ik(barriers=...)`` takes it.
        description: The setting in words, for ``bench.md``.
    """

    collision_model: pin.GeometryModel
    barriers: list[Any]
    description: str

    def configuration_arguments(self) -> dict[str, Any]:
        """``pink.Configuration``'s collision arguments: the model and a fresh data."""
        return {
            "collision_model": self.collision_model,
            "collision_data": pin.GeometryData(self.collision_model),
        }


def pink_obstacles(
    robot: clik.Robot, centres: Sequence[Sequence[float]], radius: float
) -> PinkObstacles:
    """The spheres as pink's ``SelfCollisionBarrier`` over (sphere, link geometry) pairs.

    ``safe_displacement_gain = 0``: ``SelfCollisionBarrier``'s safe displacement is
    zero, so its cost term would only pull every step toward standing still (its
    default 1 costs millimetres of tracking).

    Args:
        robot: The Panda.
        centres: Sphere centres [m].
        radius: Sphere radius [m].
    """
    from pink.barriers import SelfCollisionBarrier

    gmodel = sphere_geometry(robot, centres, radius)
    barrier = SelfCollisionBarrier(
        n_collision_pairs=BARRIER_PAIRS,
        gain=BARRIER_GAIN,
        safe_displacement_gain=0.0,
        d_min=OBSTACLE_THRESHOLD,
    )
    pairs = len(gmodel.collisionPairs)
    description = (
        f"SelfCollisionBarrier over {pairs} pairs ({len(centres)} coal spheres of radius "
        f"{radius:g} m on the world joint x {pairs // max(len(centres), 1)} link convex "
        f"geometries), the {BARRIER_PAIRS} closest in the QP, d_min {OBSTACLE_THRESHOLD:g} m, "
        f"gain {BARRIER_GAIN:g} 1/s, safe_displacement_gain 0"
    )
    return PinkObstacles(gmodel, [barrier], description)
