r"""Point-cloud obstacles: one row per link-cloud pair within the threshold, eqs. (C1)-(C2).

docs/method.md, "Obstacles from point clouds". A cloud is its voxel spheres (C1) in a
grid (:mod:`clik.clouds.grid`); a link's distance to it is its nearest sphere's
(:func:`~clik.clouds.nearest.nearest_sphere`), a lower bound of its distance to the
points (C2). The row is the obstacle row (13)-(15), normalised, from that sphere's
witness pair, with no feed-forward (a cloud is at rest between updates).

Each (link geometry, cloud) pair keeps a certificate, as the obstacle kind does: a lower
bound of its distance, lowered each sample by how far the link can have moved
(``rho |dq|``). The grid is searched only for pairs whose bound is below the threshold
(or active), and looks up to ``reach = d_o +`` :data:`SEARCH_MARGIN`: a link with no
sphere within reach gets the bound ``reach`` (nothing within it), so far from the cloud
a sample costs one subtraction per pair. Each cloud's nearest pair is then evaluated
until it is exact or beyond reach; the record keeps that distance, a lower bound where
it is not exact. A sphere entered is a crossed limit, as an obstacle's surface.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import coal
import numpy as np
import pinocchio as pin

from clik.clouds.cloud_obstacle import CloudObstacle
from clik.clouds.grid import SphereGrid
from clik.clouds.nearest import Nearest, local_box, nearest_sphere
from clik.constraints.kind import (
    CHECK_TOLERANCE,
    Candidate,
    ConstraintKind,
    KindRun,
    PoseCheck,
    RunSetup,
    Sample,
    Violation,
)
from clik.constraints.obstacle_rows import obstacle_row, point_jacobian
from clik.constraints.read_only import ReadOnlyList
from clik.constraints.words import MILLIMETRES, PENETRATED
from clik.errors import InputError

if TYPE_CHECKING:
    from clik.constraints.collision_scene import CollisionScene
    from clik.constraints.violations import ViolationMonitor
    from clik.outputs.result import TrackingResult

SEARCH_MARGIN = 0.02
"""How far beyond its threshold a cloud is searched [m]: a link that far from every
sphere is not searched again until it may have moved that far."""

_AT_REST = np.zeros(3)


class CloudAvoidance(ConstraintKind):
    """Link-cloud rows (C1)-(C2), (13)-(15); the clouds' distances are monitored.

    Args:
        clouds: The cloud obstacles.
        rows: Whether their rows may enter the task (False: monitor only).
        threshold: Default ``d_o`` [m] (a cloud's own threshold wins).
        gain: The rows' gain [1/s]; None: the law's default.
    """

    name = "cloud"
    per_sample = ("cloud_distance", "cloud_link")
    depth_measure = MILLIMETRES
    limit_words = PENETRATED
    """A link in a cloud's sphere: how deep [m], in mm."""

    def __init__(
        self,
        clouds: Sequence[CloudObstacle] = (),
        rows: bool = True,
        threshold: float = 0.03,
        gain: float | None = None,
    ) -> None:
        for i, c in enumerate(clouds):
            if not isinstance(c, CloudObstacle):
                raise InputError(f"clouds[{i}]", "a CloudObstacle(name, points, ...)", c)
        names = [c.name for c in clouds]
        if len(set(names)) != len(names):
            raise InputError("clouds", "distinct cloud names", names)
        self.clouds = ReadOnlyList(clouds, "clouds", "Controller.step(obstacles={name: points})")
        self.rows = bool(rows)
        self.threshold = float(threshold)
        self.gain = gain
        self.thresholds = np.array(
            [c.threshold if c.threshold is not None else self.threshold for c in self.clouds]
        )
        """``d_o`` per cloud [m]."""
        self.thresholds.flags.writeable = False

    @classmethod
    def check_name(cls, key: str) -> str:
        """``cloud:scan:link4`` -> ``cloud 'scan'`` (the check takes its nearest link)."""
        return f"cloud {key.partition(':')[2].rpartition(':')[0]!r}"

    @property
    def needs_scene(self) -> bool:  # type: ignore[override]
        """The links' geometry, when there is a cloud."""
        return bool(self.clouds)

    @property
    def wants_rows(self) -> bool:
        """Rows unless the set only monitors its clouds."""
        return self.rows and bool(self.clouds)

    def grids(self) -> list[SphereGrid]:
        """Each cloud's spheres in their grid."""
        return [c.spheres(float(t)) for c, t in zip(self.clouds, self.thresholds, strict=True)]

    def start(self, setup: RunSetup) -> CloudRun:
        """The pairs' certificates and records for one run."""
        return CloudRun(self, setup)

    def engine_config(self) -> Any:
        """``_engine.CloudRowsConfig``: each cloud's grid arrays, checked by the engine."""
        from clik.engine import load

        engine = load()
        return engine.CloudRowsConfig(
            clouds=[
                cloud_config(engine, c.name, g, float(t))
                for c, g, t in zip(self.clouds, self.grids(), self.thresholds, strict=True)
            ],
            rows=self.rows,
            search_margin=SEARCH_MARGIN,
            gain=self.gain,
        )

    def replaced_cloud(self, cloud: CloudObstacle) -> CloudAvoidance:
        """A new kind with the cloud of the same name replaced (this one is unchanged)."""
        clouds = [cloud if c.name == cloud.name else c for c in self.clouds]
        return CloudAvoidance(clouds, self.rows, self.threshold, self.gain)

    def finish(
        self, result: TrackingResult, records: dict[str, Any], n_rec: int, extra: dict[str, Any]
    ) -> None:
        """Distances per cloud: the record's columns, the summary's minima (with the obstacles').

        Also the points a view draws (:mod:`clik.clouds.drawn`): ``extra["cloud_points"]``
        and ``extra["cloud_points_index"]``.
        """
        from clik.clouds.drawn import drawn_clouds

        result.info["clouds"] = [
            {**c.info(), "threshold": float(t), "spheres": len(g.radii)}
            for c, g, t in zip(self.clouds, self.grids(), self.thresholds, strict=True)
        ]
        if not self.clouds:
            return
        result.extra["cloud_points"], result.extra["cloud_points_index"] = drawn_clouds(self.clouds)
        result.extra["cloud_distance"] = records["cloud_distance"][:n_rec]
        result.extra["cloud_link"] = records["cloud_link"][:n_rec]
        run_min, labels = np.asarray(records["run_min"]), result.info["links"]
        names = [c.name for c in self.clouds]
        by_cloud = {name: float(run_min[i]) for i, name in enumerate(names)}
        extra["min_cloud_distance_by_cloud"] = by_cloud
        extra["min_cloud_distance_link_by_cloud"] = {
            name: labels[link] if link >= 0 else ""
            for name, link in zip(names, records["run_min_link"], strict=True)
        }
        extra["min_cloud_distance_time_by_cloud"] = {
            name: float(records["run_min_t"][i]) for i, name in enumerate(names)
        }
        nearest = float(run_min.min())
        extra["min_cloud_distance"] = nearest
        extra.setdefault("min_obstacle_distance_by_obstacle", {}).update(by_cloud)
        known = extra.get("min_obstacle_distance")
        extra["min_obstacle_distance"] = nearest if known is None else min(known, nearest)

    def check(self, checker: PoseCheck, q: np.ndarray) -> list[Violation]:
        """Clouds nearer than their ``d_o`` to some link (C1), from coal."""
        scene = checker.scene
        if scene is None or not self.clouds:
            return []
        model = scene.robot.model
        data, gdata = model.createData(), pin.GeometryData(scene.gmodel)
        pin.updateGeometryPlacements(model, data, scene.gmodel, gdata, q)
        out = []
        for cloud, grid, thr in zip(self.clouds, self.grids(), self.thresholds, strict=True):
            best: tuple[float, str] = (math.inf, "")
            for i in range(scene.n_links):
                shape = scene.gmodel.geometryObjects[i].geometry
                found = nearest_sphere(grid, shape, local_box(shape), _tf(gdata.oMg[i]), thr)
                if found is not None and found.distance < best[0]:
                    best = (found.distance, scene.link_labels[i])
            if thr - best[0] > CHECK_TOLERANCE:
                detail = f"link {best[1]} at {best[0]:.4g} m < threshold {thr:.4g} m"
                name = self.check_name(f"cloud:{cloud.name}:{best[1]}")
                out.append(Violation(name, detail, float(thr) - best[0]))
        return out

    def with_margin(self, margin: float) -> CloudAvoidance:
        """Every threshold ``margin`` larger, rows on (solve mode)."""
        clouds = []
        for cloud, threshold in zip(self.clouds, self.thresholds, strict=True):
            c = copy.copy(cloud)
            c.threshold = float(threshold) + margin
            clouds.append(c)
        return CloudAvoidance(clouds, True, self.threshold + margin, self.gain)

    def fingerprint(self) -> tuple[Any, ...]:
        """The clouds (by identity), thresholds, rows, gain."""
        pairs = zip(self.clouds, self.thresholds, strict=True)
        clouds = tuple((c.name, id(c), float(t)) for c, t in pairs)
        return (clouds, self.threshold, self.rows, self.gain)


def cloud_config(engine: Any, name: str, grid: SphereGrid, threshold: float) -> Any:
    """One cloud's ``_engine.CloudConfig`` (its grid's arrays)."""
    return engine.CloudConfig(
        name=name,
        centres=grid.centres,
        radii=grid.radii,
        cell=grid.cell,
        low=grid.low,
        dims=np.asarray(grid.dims, dtype=np.int32),
        order=grid.order,
        start=grid.start,
        threshold=threshold,
    )


def _tf(M: pin.SE3) -> coal.Transform3s:
    return coal.Transform3s(M.rotation, M.translation)


class CloudRun(KindRun):
    """Link-cloud pairs in one run: certificates, candidates, rows, records.

    Attributes:
        dist_c: Per cloud, this sample's nearest link distance [m]: exact when within
            reach, else a lower bound.
        exact_c: Per cloud, whether ``dist_c`` is exact.
        link_c: Per cloud, the link geometry of ``dist_c``.
    """

    def __init__(self, kind: CloudAvoidance, setup: RunSetup) -> None:
        super().__init__(kind)
        self.kind: CloudAvoidance = kind
        self.scene: CollisionScene | None = setup.scene
        self.geometry = setup.geometry
        n_c = len(kind.clouds)
        n_links = 0 if self.scene is None else self.scene.n_links
        self.n_c, self.n_links = n_c, n_links
        self.grids = kind.grids()
        self.reach = kind.thresholds + SEARCH_MARGIN
        self.dist_c = np.full(n_c, np.inf)
        self.exact_c = np.zeros(n_c, dtype=bool)
        self.link_c = np.full(n_c, -1, dtype=np.int16)
        self.run_min = np.full(n_c, np.inf)
        self.run_min_link = [-1] * n_c
        self.run_min_t = np.zeros(n_c)
        self._replaced = np.zeros(n_c, dtype=bool)
        self.rec_dist = np.full((setup.n_rec, n_c), np.inf)
        self.rec_link = np.full((setup.n_rec, n_c), -1, dtype=np.int16)
        self._local = pin.SE3.Identity()
        self._lb = np.full((n_links, n_c), -np.inf)  # unknown at the start
        self._found = np.zeros((n_links, n_c), dtype=bool)  # lb exact when evaluated
        self._hint = np.full((n_links, n_c), -1)  # each pair's last nearest sphere
        self._pairs: dict[int, tuple[Nearest, int]] = {}
        if self.scene is None or not n_c:
            return
        scene = self.scene
        self.names = [[f"cloud:{c.name}:{link}" for c in kind.clouds] for link in scene.link_labels]
        self.rho = scene.motion_bounds()
        self.shapes = [scene.gmodel.geometryObjects[i].geometry for i in range(n_links)]
        self.boxes = [local_box(shape) for shape in self.shapes]

    def evaluate(self, s: Sample, out: list[Candidate]) -> None:
        """Pairs through certificates; candidates inside their threshold or active."""
        if self.scene is None or not self.n_c:
            return
        lb, n_c, kind = self._lb, self.n_c, self.kind
        if s.dq_abs is not None:
            lb -= self.rho.dot(s.dq_abs)[:, None]
        evaluated = np.zeros((self.n_links, n_c), dtype=bool)
        todo: list[Any] = np.argwhere(lb < kind.thresholds).tolist()
        todo += [divmod(item, n_c) for item in s.active_items(self)]
        for i, c in todo:
            if evaluated[i, c]:
                continue
            candidate = self._evaluate(s, int(i), int(c))
            evaluated[i, c] = True
            if candidate is None:
                continue  # nothing within reach: not a row (an active one is released)
            held = candidate.key in s.active_keys and not self._replaced[c]
            if kind.rows and (lb[i, c] < candidate.threshold or held):
                out.append(candidate)
        for c in range(n_c):  # each cloud's nearest link, exact within reach
            while True:
                i = int(lb[:, c].argmin())
                exact = bool(evaluated[i, c] and self._found[i, c])
                if evaluated[i, c] or not lb[i, c] < self.reach[c]:
                    break
                self._evaluate(s, i, c)
                evaluated[i, c] = True
            self.dist_c[c], self.exact_c[c], self.link_c[c] = lb[i, c], exact, i
        self._replaced[:] = False
        exact_d = np.where(self.exact_c, self.dist_c, np.inf)
        self.min_distance = float(exact_d.min())
        for c in np.flatnonzero(exact_d < self.run_min):
            self.run_min[c], self.run_min_t[c] = exact_d[c], s.tk
            self.run_min_link[c] = int(self.link_c[c])

    def _evaluate(self, s: Sample, i: int, c: int) -> Candidate | None:
        """Link geometry ``i`` against cloud ``c`` within reach: its certificate, its row."""
        assert self.geometry is not None and self.scene is not None
        s.place_geometries()
        M = self.geometry.gdata.oMg[i]
        reach = float(self.reach[c])
        grid, hint = self.grids[c], int(self._hint[i, c])
        found = nearest_sphere(grid, self.shapes[i], self.boxes[i], _tf(M), reach, hint)
        self._found[i, c] = found is not None
        if found is None:
            self._lb[i, c] = reach
            self._hint[i, c] = -1
            return None
        self._hint[i, c] = found.sphere
        self._lb[i, c] = found.distance
        thr = float(self.kind.thresholds[c])
        item = i * self.n_c + c
        self._pairs[item] = (found, int(self.scene.link_joint[i]))
        candidate = Candidate(self.names[i][c], self, item, thr - found.distance, thr, thr)
        candidate.witness = (found.on_link, found.on_cloud)
        return candidate

    def row(self, s: Sample, c: Candidate, out: np.ndarray) -> None:
        """Row (15), normalised, from the nearest sphere's witness pair; no feed-forward."""
        found, joint = self._pairs[c.item]
        Jp = point_jacobian(s.model, s.data, joint, found.on_link, self._local)
        c.error, c.feed = obstacle_row(
            "normalized", c.threshold, found.distance, found.on_link, found.on_cloud,
            found.normal, Jp, _AT_REST, out,
        )  # fmt: skip

    def replace_cloud(self, cloud: CloudObstacle) -> bool:
        """The cloud so named, replaced by new points (its certificates dropped).

        False: this kind has no cloud so named.
        """
        names = [c.name for c in self.kind.clouds]
        if cloud.name not in names:
            return False
        c = names.index(cloud.name)
        self.kind = self.kind.replaced_cloud(cloud)
        self.grids[c] = self.kind.grids()[c]
        self._lb[:, c] = -np.inf
        self._hint[:, c] = -1
        self._replaced[c] = True
        return True

    def observe_limits(self, tk: float, monitor: ViolationMonitor) -> None:
        """A link inside a cloud's sphere (a penetrating pair is always evaluated: exact)."""
        if self.min_distance < 0.0:
            for c in np.flatnonzero(self.dist_c < 0.0):
                monitor.observe_penetration(tk, self.names[int(self.link_c[c])][c], self.dist_c[c])

    def record(self, j: int) -> None:
        """Each cloud's nearest distance and link in slot ``j``."""
        if self.n_c:
            self.rec_dist[j] = self.dist_c
            self.rec_link[j] = self.link_c

    def records(self, n_rec: int) -> dict[str, Any]:
        """The distance record and the per-cloud minima (the engine's keys)."""
        if not self.n_c:
            return {}
        return {
            "cloud_distance": self.rec_dist,
            "cloud_link": self.rec_link,
            "run_min": self.run_min.copy(),
            "run_min_link": list(self.run_min_link),
            "run_min_t": self.run_min_t.copy(),
        }
