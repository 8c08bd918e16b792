"""The robot's link geometry and the obstacles, in one Pinocchio GeometryModel.

Built once per robot and obstacle set (nothing is rebuilt per step):

- every collision geometry of the robot becomes a convex shape (meshes are
  replaced by their convex hulls, NOTES.md: 20-30x faster than BVH for the
  same distance), attached to its joint;
- obstacles are geometries attached to the world;
- every (link, obstacle) pair, and optionally (link, link) self-collision
  pairs, is a Pinocchio collision pair.

The scene is only read once built; each run has its own :class:`SceneRun`
(:meth:`CollisionScene.start`: its geometry data, joint origins and moving
obstacles), so runs on one scene, in any threads, never meet. Per step,
:meth:`SceneRun.place_geometries` places every geometry (one C++ call) when some
pair may be near. Link-obstacle pairs are pruned with the motion bounds of
:meth:`CollisionScene.motion_bounds` (distance certificates, kept by
:class:`~clik.constraints.ConstraintSet`); link-link pairs with bounding spheres
about each joint's origin (:meth:`SceneRun.place_joints`).
"""

from __future__ import annotations

import copy
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import coal
import numpy as np
import pinocchio as pin

from clik.constraints.obstacle import Obstacle, convex_hull
from clik.constraints.read_only import ReadOnlyList
from clik.errors import ClikWarning, GeometryError, InputError

if TYPE_CHECKING:
    from clik.model.robot import Robot

GJK_TOLERANCE = 1e-9
"""Tolerance of coal's GJK/EPA for link-obstacle and link-link distances [m]."""


_CHANGE_OBSTACLES = "ConstraintSet.set_obstacles([...]) or ConstraintSet.move_obstacle(...)"
"""How to change a set's obstacles (named by the error of a change in place)."""

_CHANGE_SCENE = "a new ConstraintSet (its obstacles: ConstraintSet.set_obstacles([...]))"
"""How to change a scene's link geometry."""


class NoCollisionGeometryWarning(ClikWarning):
    """Some links have no collision geometry: they cannot be kept away from obstacles."""


class SkippedGeometryWarning(ClikWarning):
    """A link geometry has no usable convex hull: it is left out, the others are checked."""


class CollisionScene:
    """Link geometry and obstacles with their collision pairs.

    Args:
        robot: The robot (its collision model gives the link geometry).
        obstacles: The obstacles.
        links: Optional subset of link (frame) names to check; default all links with
            collision geometry.
        self_collision: Also create link-link pairs (adjacent links, pairs closer
            than ``self_margin`` at the reference configuration and the robot's SRDF
            disabled pairs, ``robot.disabled_collision_pairs``, are excluded).

    Attributes:
        gmodel: Pinocchio geometry model (links first, then obstacles); only read after
            it is built (runs place geometries in their own data, :meth:`start`).
        link_names: Link (frame) name of each link geometry.
        link_joint: Parent joint index of each link geometry.
        obstacle_pairs: Pair index of (link geometry i, obstacle o), array (n_links, n_obs).
        self_pairs: (pair index, link geometry a, link geometry b) of each link pair.
        srdf_skipped_pairs: How many link geometry pairs the other rules keep were left
            out because the robot's SRDF disables their links' collisions (0 without
            self-collision).
        link_labels: Name of each link geometry in constraint names.

    The sequences are read-only (:class:`~clik.constraints.read_only.ReadOnlyList`), the
    arrays too: a scene changes only into a new scene (:meth:`moved`).
    """

    def __init__(
        self,
        robot: Robot,
        obstacles: Sequence[Obstacle] = (),
        links: Sequence[str] | None = None,
        self_collision: bool = False,
        self_margin: float = 0.0,
    ) -> None:
        self.robot = robot
        self.model = robot.model
        gmodel = pin.GeometryModel()
        self._add_links(gmodel, links)
        self._warn_links_without_geometry()
        if self.n_links == 0 and obstacles:
            names = ", ".join(repr(o.name) for o in obstacles)
            skipped = (
                f" (the hulls of {', '.join(self.skipped_geometries)} could not be built)"
                if self.skipped_geometries
                else ""
            )
            raise GeometryError(
                f"robot {robot.name} has no collision geometry "
                f"{'among the links ' + str(list(links)) + ' ' if links is not None else ''}"
                f"to keep away from the obstacles {names}{skipped}; remove the obstacles or "
                "use a URDF with <collision> elements"
            )
        self._bounding_spheres()
        self._add_obstacles(gmodel, obstacles)
        self.srdf_skipped_pairs = 0
        self_pairs = self._self_pairs(gmodel, robot, self_margin) if self_collision else []
        self.self_pairs = ReadOnlyList(self_pairs, "scene.self_pairs", _CHANGE_SCENE)
        self.gmodel = gmodel
        counts: dict[str, int] = {}
        for link in self.link_names:
            counts[link] = counts.get(link, 0) + 1
        self.link_labels = ReadOnlyList(
            (
                link if counts[link] == 1 else gmodel.geometryObjects[i].name
                for i, link in enumerate(self.link_names)
            ),
            "scene.link_labels",
            _CHANGE_SCENE,
        )
        """Per link geometry: its link's name, or the geometry's where a link has several."""
        for name in ("local_radius", "link_joint", "obstacle_pairs", "joint_radius", "link_slot"):
            getattr(self, name).flags.writeable = False  # read by runs: a change is a new scene
        self._own: SceneRun | None = None

    def _add_links(self, gmodel: pin.GeometryModel, links: Sequence[str] | None) -> None:
        """Each link collision geometry as a convex shape on its joint (a bad one is skipped)."""
        frame_names = [f.name for f in self.model.frames]
        source = self.robot.collision_model
        known = sorted({frame_names[g.parentFrame] for g in source.geometryObjects})
        if links is not None:
            bad = [name for name in links if name not in known]
            if bad:
                raise InputError(
                    "constraints.obstacles.links",
                    f"link names with collision geometry among {known}",
                    bad,
                )
        link_names: list[str] = []
        self.skipped_geometries: list[str] = []
        link_joint, local_radius = [], []
        for go in source.geometryObjects:
            link = frame_names[go.parentFrame]
            if links is not None and link not in links:
                continue
            try:
                geometry, radius = _convex(go, f"collision geometry {go.name!r}")
            except GeometryError as exc:  # one bad mesh must not disable the others
                self.skipped_geometries.append(go.name)
                warnings.warn(
                    f"{exc} (link {link!r}); this geometry is not checked against obstacles, "
                    "the link's other geometries and the other links are",
                    SkippedGeometryWarning,
                    stacklevel=4,
                )
                continue
            gmodel.addGeometryObject(
                pin.GeometryObject(go.name, go.parentJoint, go.parentFrame, go.placement, geometry)
            )
            link_names.append(link)
            link_joint.append(go.parentJoint)
            local_radius.append(float(np.linalg.norm(go.placement.translation)) + radius)
        self.link_names = ReadOnlyList(link_names, "scene.link_names", _CHANGE_SCENE)
        self.n_links = len(link_names)
        self.local_radius = np.asarray(local_radius, dtype=float)
        self.link_joint = np.asarray(link_joint, dtype=np.intp)

    def _warn_links_without_geometry(self) -> None:
        """Bodies drawn (visual geometry) with no collision geometry at all: reported once.

        The drawn links are the URDF's links with ``<visual>`` elements
        (``Robot.visual_links``, kept at loading): the visual model, slow to read, is
        never built here. A robot not made by ``Robot.load`` has none listed.
        """
        checked = {g.parentJoint for g in self.robot.collision_model.geometryObjects}
        self.links_without_geometry = sorted(
            link for link, joint in _drawn_links(self.robot) if joint > 0 and joint not in checked
        )
        if self.links_without_geometry:
            warnings.warn(
                "links with visual but no collision geometry (not checked against obstacles): "
                + ", ".join(self.links_without_geometry),
                NoCollisionGeometryWarning,
                stacklevel=4,
            )

    def _bounding_spheres(self) -> None:
        """One bounding sphere per joint, about the joint origin, enclosing its geometries."""
        self.joints = [int(j) for j in np.unique(self.link_joint)]
        self.joint_radius = np.array(
            [float(self.local_radius[self.link_joint == j].max()) for j in self.joints]
        )
        self._joint_slot = {j: i for i, j in enumerate(self.joints)}
        self.link_slot = np.array(
            [self._joint_slot[int(j)] for j in self.link_joint], dtype=np.intp
        )

    def _add_obstacles(self, gmodel: pin.GeometryModel, obstacles: Sequence[Obstacle]) -> None:
        """Obstacles as geometries on the world, and one pair per (link, obstacle)."""
        self.obstacles = ReadOnlyList(obstacles, "scene.obstacles", _CHANGE_OBSTACLES)
        self.obstacle_geom: list[int] = []
        for ob in self.obstacles:
            obj = pin.GeometryObject(f"obstacle:{ob.name}", 0, 0, ob.placement(0.0), ob.geometry)
            self.obstacle_geom.append(gmodel.addGeometryObject(obj))
        self.obstacle_pairs = np.zeros((self.n_links, len(self.obstacles)), dtype=np.intp)
        for i in range(self.n_links):
            for o, g in enumerate(self.obstacle_geom):
                self.obstacle_pairs[i, o] = len(gmodel.collisionPairs)
                gmodel.addCollisionPair(pin.CollisionPair(i, g))
        self._moving = [o for o, ob in enumerate(self.obstacles) if ob.moving]

    def _self_pairs(
        self, gmodel: pin.GeometryModel, robot: Robot, margin: float
    ) -> list[tuple[int, int, int]]:
        """Link-link pairs, but adjacent links, pairs in contact at the reference, SRDF pairs.

        The robot's SRDF pairs (``robot.disabled_collision_pairs``) that the other rules
        keep are counted in :attr:`srdf_skipped_pairs`.
        """
        disabled = robot.disabled_collision_pairs
        model = self.model
        parents = model.parents
        data = model.createData()
        gdata = pin.GeometryData(gmodel)
        pin.framesForwardKinematics(model, data, robot.q_reference)
        pin.updateGeometryPlacements(model, data, gmodel, gdata)
        pairs: list[tuple[int, int, int]] = []
        for a in range(self.n_links):
            for b in range(a + 1, self.n_links):
                ja, jb = int(self.link_joint[a]), int(self.link_joint[b])
                if ja == jb or parents[ja] == jb or parents[jb] == ja or parents[ja] == parents[jb]:
                    continue  # same body, adjacent or sibling links (as an SRDF would disable)
                req, res = coal.DistanceRequest(), coal.DistanceResult()
                dist = coal.distance(
                    gmodel.geometryObjects[a].geometry,
                    _tf(gdata.oMg[a]),
                    gmodel.geometryObjects[b].geometry,
                    _tf(gdata.oMg[b]),
                    req,
                    res,
                )
                if dist <= margin:
                    continue
                names = sorted((self.link_names[a], self.link_names[b]))
                if (names[0], names[1]) in disabled:
                    self.srdf_skipped_pairs += 1
                    continue
                pairs.append((len(gmodel.collisionPairs), a, b))
                gmodel.addCollisionPair(pin.CollisionPair(a, b))
        return pairs

    # -- per step ----------------------------------------------------------------------

    def motion_bounds(self) -> np.ndarray:
        """``rho`` (n_links, nv): ``|pdot| <= rho_i . |qdot|`` for any point ``p`` of link ``i``.

        ``rho_ij`` bounds the distance from joint ``j``'s axis to any point of link ``i``'s
        geometry (configuration independent: the chain of joint offsets from ``j`` to ``i``'s
        joint plus the geometry's radius about that joint); 1 for a prismatic joint, 0 for
        a joint that does not move link ``i``. Computed once per scene (read-only after).
        """
        cached = getattr(self, "_rho", None)
        if cached is not None:
            return cached
        model = self.model
        offset = [float(np.linalg.norm(M.translation)) for M in model.jointPlacements]
        rho = np.zeros((self.n_links, model.nv))
        for i in range(self.n_links):
            j, length = int(self.link_joint[i]), 0.0
            while j > 0:
                joint = model.joints[j]
                arm = length + float(self.local_radius[i])
                name = joint.shortname()
                if joint.nv > 1:  # planar, spherical, free-flyer: rotations and translations
                    bound = arm + 1.0
                elif name.startswith("JointModelP"):  # prismatic: a point moves by |dq|
                    bound = 1.0
                else:  # revolute
                    bound = arm
                rho[i, joint.idx_v : joint.idx_v + joint.nv] = bound
                length += offset[j]
                j = model.parents[j]
        rho.flags.writeable = False
        self._rho = rho
        return rho

    def start(self) -> SceneRun:
        """The scene's state for one run: its own geometry data (each run has one)."""
        moving = [(self.obstacle_geom[o], self.obstacles[o]) for o in self._moving]
        return SceneRun(self.model, self.gmodel, self.joints, moving)

    def moved(self, o: int, obstacle: Obstacle) -> CollisionScene:
        """A new scene with ``obstacle`` (same shape, new pose or velocity) in slot ``o``.

        Nothing is rebuilt: the link geometry, hulls and pairs are shared; the new scene
        has its own ``GeometryModel`` (the geometries themselves shared), so a run that
        started on this scene keeps it as it was.
        """
        out = copy.copy(self)
        out.gmodel = self.gmodel.copy()
        out.gmodel.geometryObjects[self.obstacle_geom[o]].placement = obstacle.placement()
        out.obstacles = ReadOnlyList(
            (obstacle if i == o else ob for i, ob in enumerate(self.obstacles)),
            "scene.obstacles",
            _CHANGE_OBSTACLES,
        )
        out._moving = [i for i, ob in enumerate(out.obstacles) if ob.moving]
        out._own = None
        return out

    # -- the scene's own state, for single-threaded callers (views, tests) ---------------

    def _state(self) -> SceneRun:
        if self._own is None:
            self._own = self.start()
        return self._own

    @property
    def gdata(self) -> pin.GeometryData:
        """The geometry data of :meth:`update` and :meth:`distance` (not a run's)."""
        return self._state().gdata

    def place_joints(self, data: pin.Data) -> np.ndarray:
        """Joint origins (n_joints, 3) [m] from ``data.oMi`` (see :meth:`SceneRun.place_joints`)."""
        return self._state().place_joints(data)

    def place_geometries(self, data: pin.Data, t: float) -> None:
        """Place every geometry at ``data``'s kinematics and time ``t`` [s] (:attr:`gdata`)."""
        self._state().place_geometries(data, t)

    def update(self, data: pin.Data, t: float) -> None:
        """Joint origins and every geometry at the current kinematics and time ``t`` [s].

        This and :meth:`distance` use the scene's own geometry data, one for every
        caller: a view or a test. A run has its own (:meth:`start`), so runs on one
        scene may share it across threads; these two may not.
        """
        state = self._state()
        state.place_joints(data)
        state.place_geometries(data, t)

    def distance(self, pair: int) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        """Signed distance of a pair, its witness points and the normal (:meth:`update`)."""
        return self._state().distance(pair)

    def engine_config(self) -> Any:
        """The scene as the compiled engine's ``SceneConfig`` (the GeometryModel borrowed)."""
        from clik.engine import load

        return load().SceneConfig(
            gmodel=self.gmodel,
            n_links=int(self.n_links),
            link_joint=[int(j) for j in self.link_joint],
            local_radius=np.asarray(self.local_radius, dtype=float),
            obstacle_pairs=np.asarray(self.obstacle_pairs, dtype=np.int32).reshape(
                self.n_links, len(self.obstacles)
            ),
            self_pairs=[(int(p), int(a), int(b)) for p, a, b in self.self_pairs],
            link_labels=list(self.link_labels),
        )


class SceneRun:
    """One run's state of a scene: its geometry data, joint origins, moving obstacles.

    The scene's ``GeometryModel`` is only read; every placement and distance is written
    here, so runs on one scene do not meet (the engine's ``CollisionScene`` does the
    same, ``src/engine/constraints/collision_scene.hpp``). A moving obstacle's placement
    at time ``t`` is written into this run's ``oMg``, not into the model.

    Args:
        model: The robot's model.
        gmodel: The scene's geometry model (read only).
        joints: The joints whose origins :meth:`place_joints` gives.
        moving: ``(geometry index, obstacle)`` of each moving obstacle.

    Attributes:
        gdata: The run's geometry data (coal's requests at :data:`GJK_TOLERANCE`,
            warm-started from each pair's last query).
    """

    def __init__(
        self,
        model: pin.Model,
        gmodel: pin.GeometryModel,
        joints: Sequence[int],
        moving: Sequence[tuple[int, Obstacle]],
    ) -> None:
        self.model, self.gmodel, self.joints, self.moving = model, gmodel, joints, moving
        self.gdata = pin.GeometryData(gmodel)
        for request in self.gdata.distanceRequests:
            # GJK's default 1e-6 m tolerance makes hull-hull witness points jitter by that
            # much between samples; rows are derivatives, so ask for 1e-9 m.
            request.gjk_tolerance = GJK_TOLERANCE
            request.epa_tolerance = GJK_TOLERANCE
            # Warm start: GJK begins where the pair's last query ended (samples are close).
            request.gjk_initial_guess = coal.GJKInitialGuess.CachedGuess
        self._joint_pos = np.zeros((len(joints), 3))

    def place_joints(self, data: pin.Data) -> np.ndarray:
        """Joint origins (n_joints, 3) [m] from ``data.oMi``: bounding-sphere centres."""
        pos = self._joint_pos
        oMi = data.oMi
        for s, j in enumerate(self.joints):
            pos[s] = oMi[j].translation
        return pos

    def place_geometries(self, data: pin.Data, t: float) -> None:
        """Place every geometry (one C++ call) and the moving obstacles at time ``t`` [s]."""
        pin.updateGeometryPlacements(self.model, data, self.gmodel, self.gdata)
        oMg = self.gdata.oMg
        for g, obstacle in self.moving:  # a world-attached geometry's oMg is its placement
            oMg[g] = obstacle.placement(t)

    def distance(self, pair: int) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        """Signed distance of a pair, its witness points (first on the link) and the normal."""
        res = pin.computeDistance(self.gmodel, self.gdata, pair)
        self.gdata.distanceRequests[pair].updateGuess(res)
        return res.min_distance, res.getNearestPoint1(), res.getNearestPoint2(), res.normal


def _drawn_links(robot: Robot) -> list[tuple[str, int]]:
    """(link name, parent joint index) of each link with visual geometry in the model."""
    model = robot.model
    body = pin.FrameType.BODY  # a link's frame (kept where a fixed or locked joint merged it)
    return [
        (link, int(model.frames[model.getFrameId(link, body)].parentJoint))
        for link in sorted(robot.visual_links or ())
        if model.existFrame(link, body)
    ]


def _tf(M: pin.SE3) -> coal.Transform3s:
    return coal.Transform3s(M.rotation, M.translation)


def _convex(go: pin.GeometryObject, field: str) -> tuple[coal.CollisionGeometry, float]:
    """A convex version of a link geometry and its bounding radius about its own origin."""
    geom = go.geometry
    if isinstance(geom, coal.BVHModelBase):
        return convex_hull(geom, field)
    if isinstance(geom, coal.ConvexBase):
        return geom, float(np.max(np.linalg.norm(np.asarray(geom.points()), axis=1)))
    if isinstance(geom, coal.Sphere):
        return geom, geom.radius
    if isinstance(geom, coal.Box):
        return geom, float(np.linalg.norm(geom.halfSide))
    if isinstance(geom, coal.Capsule):
        return geom, geom.halfLength + geom.radius
    if isinstance(geom, coal.Cylinder):
        return geom, float(np.hypot(geom.halfLength, geom.radius))
    raise GeometryError(f"{field}: unsupported geometry type {type(geom).__name__}")
