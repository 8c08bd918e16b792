"""A controller's clouds replaced between ticks: docs/method.md, "Obstacles from point clouds".

``ctl.step(targets, obstacles={"scan": points})`` or ``ctl.update_cloud("scan", points)``
gives a cloud new points (in its own frame, as it was given); the spheres and their grid
are built again (one pass over the points, :func:`~clik.clouds.voxels.voxel_spheres` and
:func:`~clik.clouds.grid.sphere_grid`), and the rows see the new cloud from the next
tick, its pairs measured again.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from clik.clouds.cloud_obstacle import CloudObstacle
from clik.constraints.cloud_avoidance import CloudAvoidance
from clik.errors import InputError

if TYPE_CHECKING:
    from clik.constraints.constraint_set import ConstraintSet


def cloud_kind(cset: ConstraintSet | None) -> CloudAvoidance | None:
    """The set's cloud kind, or None."""
    kinds = () if cset is None else cset.kinds
    return next((k for k in kinds if isinstance(k, CloudAvoidance)), None)


def cloud_names(cset: ConstraintSet | None) -> list[str]:
    """The names of the set's clouds."""
    kind = cloud_kind(cset)
    return [] if kind is None else [c.name for c in kind.clouds]


def new_cloud(
    cset: ConstraintSet | None,
    current: dict[str, Any],
    name: str,
    points: Any,
    q: np.ndarray,
    robot_padding: float | None,
) -> tuple[CloudObstacle, float]:
    """Cloud ``name`` with ``points`` (its frame) [m], and its threshold [m].

    Args:
        cset: The controller's constraint set.
        current: The clouds replaced so far in the session, by name (updated).
        name: The cloud's name.
        points: ``(N, 3)`` points [m] in the cloud's frame.
        q: The joints now (the robot's own points are removed at them).
        robot_padding: Remove the points within this margin [m] of the robot at ``q``;
            None: keep every point.

    Raises:
        InputError: No cloud so named, points not ``(N, 3)`` numbers.
    """
    kind = cloud_kind(cset)
    names = cloud_names(cset)
    if kind is None or name not in names:
        raise InputError("obstacles", f"a cloud's name, one of {names}", name)
    old = current.get(name, kind.clouds[names.index(name)])
    cloud = old.with_points(points)  # converted and checked by CloudObstacle
    if robot_padding is not None:
        assert cset is not None
        cloud = cloud.without_robot(cset.robot, q, robot_padding)
    current[name] = cloud
    threshold = cloud.threshold if cloud.threshold is not None else kind.threshold
    return cloud, float(threshold)
