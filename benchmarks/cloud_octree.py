"""coal's octree beside clik's voxel spheres: the same cloud, asked link by link.

The comparison line of issue 45: the cloud's points as a ``coal.OcTree`` (resolution
the cloud's voxel), and at a tick's joints coal's distance from it to every link geometry
of the Panda, one query per link, as one would ask coal without clik. The link
geometries are clik's own (:class:`~clik.constraints.collision_scene.CollisionScene`:
the convex hulls clik's rows use), placed by Pinocchio.

The same probe also checks the distances: an octree cell holds its points, so coal's
distance is at most the true one and at least it less the cell's diagonal; clik's
nearest-sphere distance is a lower bound too (docs/method.md, "Obstacles from point
clouds"). Where both are known they agree within a voxel's diagonal.
"""

from __future__ import annotations

import gc
import math
import time
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from benchmarks.stats import stats
from clik.clouds import CloudObstacle
from clik.clouds.nearest import local_box, nearest_sphere
from clik.constraints.collision_scene import CollisionScene


def _placement(M: pin.SE3) -> coal.Transform3s:
    """A Pinocchio placement as coal's."""
    return coal.Transform3s(M.rotation, M.translation)


class OctreeProbe:
    """The cloud as a ``coal.OcTree`` and the robot's link geometries, built once.

    Args:
        robot: The robot (its collision model gives the links).
        cloud: The cloud (its points in the world and its voxel, the octree's resolution).

    Attributes:
        tree: The octree.
        build_ms: Time to build it from the points [ms].
        labels: Each link geometry's label (clik's, ``panda_link3``, ...).
    """

    def __init__(self, robot: Any, cloud: CloudObstacle) -> None:
        self.cloud = cloud
        points = np.array(cloud.world, dtype=float)
        start = time.perf_counter()
        self.tree = coal.makeOctree(points, cloud.voxel)
        self.build_ms = 1e3 * (time.perf_counter() - start)
        self.scene = CollisionScene(robot)
        self.labels = list(self.scene.link_labels)
        self.model = robot.model
        self.data = self.model.createData()
        self.gdata = pin.GeometryData(self.scene.gmodel)
        self.shapes = [
            self.scene.gmodel.geometryObjects[i].geometry for i in range(self.scene.n_links)
        ]
        self._identity = coal.Transform3s()
        self._request = coal.DistanceRequest()
        self._result = coal.DistanceResult()

    def distances(self, q: np.ndarray) -> np.ndarray:
        """The octree's distance to every link geometry at ``q`` [m], coal's (per link).

        Args:
            q: Configuration.
        """
        pin.updateGeometryPlacements(self.model, self.data, self.scene.gmodel, self.gdata, q)
        out = np.empty(len(self.shapes))
        for i, shape in enumerate(self.shapes):
            self._result.clear()
            out[i] = coal.distance(
                self.tree,
                self._identity,
                shape,
                _placement(self.gdata.oMg[i]),
                self._request,
                self._result,
            )
        return out

    def nearest_spheres(self, q: np.ndarray, threshold: float, reach: float) -> np.ndarray:
        """The nearest voxel sphere's distance of every link geometry at ``q`` [m], clik's.

        The voxel spheres of the cloud's grid for ``threshold`` (the rows' own), searched
        up to ``reach`` as :class:`~clik.constraints.cloud_avoidance.CloudAvoidance` does.

        Args:
            q: Configuration.
            threshold: The rows' threshold [m] (the grid's cell is chosen for it).
            reach: How far to look [m].

        Returns:
            One distance per link geometry [m]; NaN where no sphere is within ``reach``.
        """
        grid = self.cloud.spheres(threshold)
        pin.updateGeometryPlacements(self.model, self.data, self.scene.gmodel, self.gdata, q)
        out = np.full(len(self.shapes), np.nan)
        for i, shape in enumerate(self.shapes):
            found = nearest_sphere(
                grid, shape, local_box(shape), _placement(self.gdata.oMg[i]), reach
            )
            if found is not None:
                out[i] = found.distance
        return out


def sampled_ticks(ticks: int, samples: int) -> np.ndarray:
    """At most ``samples`` tick indices spread evenly over ``0 .. ticks - 1``, in order."""
    return np.unique(np.linspace(0, ticks - 1, max(1, min(samples, ticks))).round().astype(int))


def octree_line(probe: OctreeProbe, joints: np.ndarray, samples: int) -> dict[str, Any]:
    """The octree line: per tick, coal's distance from the octree to every link [us].

    Each sampled tick is timed alone: the geometry placed at its joints, then one
    ``coal.distance`` per link geometry.

    Args:
        probe: The octree and the link geometries.
        joints: A line's joints, one row per tick (m, nq).
        samples: Ticks timed (spread evenly over the run).

    Returns:
        Median, p10, p90 and min per tick [us], the ticks timed, the octree's build time
        [ms] and resolution [m], the links, and the distances found (``distances``: one
        row per tick timed) with the ticks they belong to.
    """
    ticks = sampled_ticks(len(joints), samples)
    times, rows = [], []
    gc.collect()
    for k in ticks:
        start = time.perf_counter()
        rows.append(probe.distances(joints[k]))
        times.append(1e6 * (time.perf_counter() - start))
    s = stats(times)
    return {
        "median_us": s["median"],
        "p10_us": s["p10"],
        "p90_us": s["p90"],
        "min_us": s["min"],
        "ticks_timed": len(ticks),
        "ticks": ticks.tolist(),
        "build_ms": probe.build_ms,
        "resolution_m": probe.cloud.voxel,
        "links": len(probe.labels),
        "distances": np.array(rows),
    }


def agreement(
    probe: OctreeProbe, joints: np.ndarray, ticks: np.ndarray, octree: np.ndarray, threshold: float
) -> dict[str, Any]:
    """The octree's distances (coal) against the nearest spheres' (clik) at the same ticks.

    Args:
        probe: The octree and the link geometries.
        joints: The line's joints, one row per tick.
        ticks: The ticks of ``octree``'s rows.
        octree: coal's distances, one row per tick, one column per link [m].
        threshold: The rows' threshold [m].

    Returns:
        ``pairs`` compared (link-tick pairs within clik's reach, ``2 threshold``), the
        largest ``|octree - spheres|`` [m] (None: no pair), the voxel's diagonal [m] and
        whether every pair agrees within it.
    """
    reach = 2.0 * threshold
    spheres = np.array([probe.nearest_spheres(joints[k], threshold, reach) for k in ticks])
    known = ~np.isnan(spheres)
    gap = np.abs(octree[known] - spheres[known]) if known.any() else np.zeros(0)
    diagonal = math.sqrt(3.0) * probe.cloud.voxel
    largest = float(gap.max()) if gap.size else None
    return {
        "pairs": int(gap.size),
        "max_abs_difference_m": largest,
        "voxel_diagonal_m": diagonal,
        "agree": bool(gap.size) and bool((gap <= diagonal).all()),
    }
