"""Point clouds as obstacles (issue 45): reading clouds, their voxel spheres, the rows' obstacle.

docs/method.md, "Obstacles from point clouds": :func:`~clik.clouds.read.read_cloud`
reads an ``(N, 3)`` ``.npy``, a PLY or a PCD file within budgets;
:func:`~clik.clouds.voxels.voxel_spheres` turns the points into the spheres (C1) the
rows keep away from; :class:`~clik.clouds.cloud_obstacle.CloudObstacle` is the obstacle
the cloud rows keep the links away from
(:class:`~clik.constraints.cloud_avoidance.CloudAvoidance`, in a set's ``kinds=[...]``).
"""

from clik.clouds.cloud_obstacle import CloudObstacle, EmptyCloudWarning
from clik.clouds.read import MAX_CLOUD_BYTES, MAX_CLOUD_POINTS, CloudPoints, read_cloud
from clik.clouds.voxels import voxel_spheres

__all__ = [
    "MAX_CLOUD_BYTES",
    "MAX_CLOUD_POINTS",
    "CloudObstacle",
    "CloudPoints",
    "EmptyCloudWarning",
    "read_cloud",
    "voxel_spheres",
]
