"""A point-cloud obstacle's own keys: ``[[obstacles]]`` with ``shape = "cloud"``.

docs/method.md, "Obstacles from point clouds". Beside the keys every obstacle has
(``name``, ``position`` and ``rpy`` of the cloud's frame, ``threshold``), a cloud takes:

- ``file``: an ``(N, 3)`` ``.npy``, a ``.ply`` or a ``.pcd`` file (read when the run is
  built, :func:`~clik.clouds.read.read_cloud`), relative to the scenario's folder;
- ``voxel`` [m] >= 0: the voxel spheres' edge (default
  :data:`~clik.clouds.cloud_obstacle.DEFAULT_VOXEL`);
- ``self_filter`` (default true): leave out the points on the robot at the start
  configuration (:meth:`~clik.clouds.cloud_obstacle.CloudObstacle.without_robot`), within
  ``self_padding`` [m] (default :data:`SELF_PADDING`) of its links.

A cloud is at rest (new points replace it between ticks): a ``velocity`` is refused.
"""

from __future__ import annotations

from typing import Any

from clik.clouds.cloud_obstacle import DEFAULT_VOXEL
from clik.schema import MAX_LENGTH, Table

CLOUD_SUFFIXES = (".npy", ".ply", ".pcd")
"""The cloud files a scenario names (:func:`~clik.clouds.read.read_cloud` reads them)."""

SELF_PADDING = 0.01
"""Default ``self_padding`` [m]: a depth camera's noise about a link at 1 m."""


def cloud_keys(ob: Table) -> dict[str, Any]:
    """``file`` (as written), ``voxel``, ``self_filter`` and ``self_padding`` of a cloud.

    Raises:
        ScenarioError: A ``velocity``, a ``file`` not ending ``.npy``, ``.ply`` or
            ``.pcd``, a ``voxel`` or ``self_padding`` not a length >= 0 [m], a
            ``self_padding`` with ``self_filter = false``; naming the key.
    """
    if ob.has("velocity"):
        raise ob.error(
            "velocity",
            "no velocity for a cloud (its points are at rest; a controller replaces them "
            "between ticks: Controller.step(obstacles={name: points}))",
            ob.raw("velocity"),
        )
    file = ob.string("file")
    if "://" in file or not file.lower().endswith(CLOUD_SUFFIXES):
        expected = "a point cloud file ending " + ", ".join(CLOUD_SUFFIXES)
        raise ob.error("file", expected + " (URLs are not fetched)", file)
    self_filter = ob.boolean("self_filter", True)
    if not self_filter and ob.has("self_padding"):
        raise ob.error("self_padding", "no self_padding: self_filter is false (nothing removed)")
    voxel = ob.number("voxel", DEFAULT_VOXEL, minimum=0.0, unit="[m]", bound=MAX_LENGTH)
    padding = ob.number("self_padding", SELF_PADDING, minimum=0.0, unit="[m]", bound=MAX_LENGTH)
    return {
        "file": file,
        "voxel": float(voxel),
        "self_filter": self_filter,
        "self_padding": float(padding),
    }
