r"""A run's constraints: obstacles, joint ranges, link pairs, dexterity, and how their rows behave.

The augmented task (docs/method.md, eqs. (20)-(25)) stacks the task rows and
the *active* constraint rows: ``J_e = (J; J_o; U)`` (24), ``e_e = (e; e_o; e_q)``
(25). A :class:`ConstraintSet` holds what the constraints are (obstacles and
their collision scene, thresholds, gains, the release rule, the bound on active
rows). Each run builds its own state on it, a
:class:`~clik.constraints.constraint_run.ConstraintRun`, which fills rows into
the run's extended task and never keeps a tracker: one set can serve any
number of trackers and runs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.constraints.collision_scene import CollisionScene
from clik.constraints.dexterity import Dexterity
from clik.constraints.joint_limits import JointLimits
from clik.constraints.obstacle import Obstacle
from clik.constraints.obstacle_rows import FORMS
from clik.errors import InputError

if TYPE_CHECKING:
    from clik.robot import Robot

RELEASE_RULES = ("projection", "sign")


class ConstraintSet:
    """Obstacle, joint-range, self-collision and dexterity constraints of one run.

    Args:
        robot: The robot.
        obstacles: Obstacles; their distances are always monitored (recorded per sample).
        obstacle_rows: Whether obstacle rows may enter the task (False: monitor only).
        obstacle_threshold: Default ``d_o`` [m] (an obstacle's own threshold wins).
        obstacle_gain: Gain of obstacle rows [1/s]; None: the default of the law (see below).
        form: ``"normalized"`` (default) or ``"squared"`` (the paper's eq. (13)).
        links: Link names checked against obstacles (default: all with collision geometry).
        joint_limits: Joint-range rows (:class:`JointLimits`), or None.
        joint_gain: Gain of joint-range rows [1/s]; None: default of the law.
        self_collision: Link-link rows.
        self_threshold: Threshold of link-link pairs [m].
        self_gain: Gain of link-link rows [1/s]; None: default of the law.
        dexterity: The dexterity row (:class:`Dexterity`, ``w >= w_min`` on the task's
            manipulability, (D1)-(D3)), or None.
        dexterity_gain: Gain of the dexterity row [1/s]; None: default of the law.
        release: ``"projection"`` (default) or ``"sign"``.
        hysteresis: With the sign rule, release only when the error is below
            ``-hysteresis * threshold``.
        max_active: Bound on active rows (default and maximum: ``n - m`` under laws (9)
            and (8), eq. (22); ``n`` under law (10), see :meth:`row_limit`).
        monitor_margin: An obstacle's nearest distance is evaluated exactly within
            ``threshold + monitor_margin`` [m] on every sample (and on recorded samples
            everywhere); beyond it, only a lower bound is kept between recordings
            (``min_obstacle_distance_exact_by_obstacle`` in the summary says which).

    Default gains: with law (10) every row gets the task's largest gain ``alpha``
    (``J_e^+`` normalises rows). With laws (9) and (8) a row adds about
    ``K dt |j|^2`` to ``dt lambda_max(K J_e J_e^T)``, which the task rows already
    bring near 1 when ``alpha = 1/dt``; the default ``K = alpha / (2 max(1, |j|^2))``
    keeps the sum below 2 (a row with ``K = alpha`` makes the case study's
    explicit Euler oscillate, measured).
    """

    def __init__(
        self,
        robot: Robot,
        *,
        obstacles: Sequence[Obstacle] = (),
        obstacle_rows: bool = True,
        obstacle_threshold: float = 0.03,
        obstacle_gain: float | None = None,
        form: str = "normalized",
        links: Sequence[str] | None = None,
        joint_limits: JointLimits | None = None,
        joint_gain: float | None = None,
        self_collision: bool = False,
        self_threshold: float = 0.01,
        self_gain: float | None = None,
        dexterity: Dexterity | None = None,
        dexterity_gain: float | None = None,
        release: str = "projection",
        hysteresis: float = 0.0,
        max_active: int | None = None,
        monitor_margin: float = 0.1,
    ) -> None:
        if form not in FORMS:
            raise InputError("constraints.obstacles.form", "'normalized' or 'squared'", form)
        if release not in RELEASE_RULES:
            raise InputError("constraints.release", "'projection' or 'sign'", release)
        for field, value in (
            ("obstacle_threshold", obstacle_threshold),
            ("self_threshold", self_threshold),
            ("monitor_margin", monitor_margin),
        ):
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"constraints.{field}", "a positive distance [m]", value)
        for field, gain in (
            ("obstacle_gain", obstacle_gain),
            ("joint_gain", joint_gain),
            ("self_gain", self_gain),
            ("dexterity_gain", dexterity_gain),
        ):
            if gain is not None and not (math.isfinite(gain) and gain > 0):
                raise InputError(f"constraints.{field}", "a positive gain [1/s]", gain)
        if dexterity is not None and not isinstance(dexterity, Dexterity):
            raise InputError("constraints.dexterity", "a Dexterity(threshold=...)", dexterity)
        if not (math.isfinite(hysteresis) and hysteresis >= 0):
            raise InputError("constraints.hysteresis", "a number >= 0", hysteresis)
        self.robot = robot
        self.obstacles = list(obstacles)
        self.obstacle_rows = obstacle_rows
        self.obstacle_threshold = float(obstacle_threshold)
        self.gains = {
            "obstacle": obstacle_gain,
            "joint": joint_gain,
            "self": self_gain,
            "dexterity": dexterity_gain,
        }
        self.form = form
        self.joint_limits = joint_limits
        self.dexterity = dexterity
        self.self_threshold = float(self_threshold)
        self.release_rule = release
        self.hysteresis = float(hysteresis)
        self.max_active = max_active
        self.monitor_margin = float(monitor_margin)
        self._links = links
        self._self_collision = self_collision
        self.set_obstacles(self.obstacles)

    # -- obstacles between runs ----------------------------------------------------------

    def set_obstacles(self, obstacles: Sequence[Obstacle]) -> None:
        """Replace the obstacles (add, remove) between runs, keeping the robot as loaded.

        The link hulls are computed once per robot; only the collision pairs are rebuilt.
        """
        obstacles = list(obstacles)
        names = [o.name for o in obstacles]
        if len(set(names)) != len(names):
            raise InputError("obstacles", "distinct obstacle names", names)
        self.obstacles = obstacles
        need_scene = bool(obstacles) or self._self_collision
        self.scene = (
            CollisionScene(self.robot, obstacles, self._links, self._self_collision)
            if need_scene
            else None
        )
        self._setup_scene()

    def move_obstacle(
        self,
        name: str,
        position: Sequence[float] | np.ndarray,
        rpy: Sequence[float] | None = None,
        velocity: Sequence[float] | None = None,
    ) -> None:
        """Move an obstacle between runs (no rebuild): new position [m], rpy [rad], velocity."""
        names = [o.name for o in self.obstacles]
        if name not in names:
            raise InputError("obstacle", f"one of {names}", name)
        i = names.index(name)
        ob = self.obstacles[i]
        moved = Obstacle.__new__(Obstacle)
        moved.__dict__.update(ob.__dict__)
        moved.position = np.array(position, dtype=float)
        if moved.position.shape != (3,) or not np.all(np.isfinite(moved.position)):
            raise InputError(f"obstacles.{name}.position", "three finite numbers", position)
        if rpy is not None:
            moved.rpy = np.array(rpy, dtype=float)
            moved.rotation = pin.rpy.rpyToMatrix(*moved.rpy)
        if velocity is not None:
            moved.velocity = np.array(velocity, dtype=float)
        self.obstacles[i] = moved
        assert self.scene is not None
        self.scene.replace_obstacle(i, moved)
        self.obs_vel[i] = moved.velocity

    # -- set-up ------------------------------------------------------------------------

    def _setup_scene(self) -> None:
        scene = self.scene
        n_obs = len(self.obstacles)
        self.obs_threshold = np.array(
            [
                o.threshold if o.threshold is not None else self.obstacle_threshold
                for o in self.obstacles
            ]
        )
        self.obs_vel = np.array([o.velocity for o in self.obstacles]).reshape(n_obs, 3)
        if scene is None:
            self.link_labels: list[str] = []
            self.immovable_pairs: set[str] = set()
            return
        counts: dict[str, int] = {}
        for link in scene.link_names:
            counts[link] = counts.get(link, 0) + 1
        geoms = scene.gmodel.geometryObjects
        self.link_labels = [
            link if counts[link] == 1 else geoms[i].name for i, link in enumerate(scene.link_names)
        ]
        self.pair_names = [
            [f"obstacle:{o.name}:{label}" for o in self.obstacles] for label in self.link_labels
        ]
        self.immovable_pairs = {  # a geometry on the fixed base: its distance never changes
            name
            for names, joint in zip(self.pair_names, scene.link_joint, strict=True)
            if joint == 0
            for name in names
        }
        if scene.self_pairs:
            sp = np.array([(a, b) for _, a, b in scene.self_pairs])
            self.self_slots = (scene.link_slot[sp[:, 0]], scene.link_slot[sp[:, 1]])
        self.rho = scene.motion_bounds()
        self.thr_matrix = np.broadcast_to(self.obs_threshold, (scene.n_links, n_obs)).copy()
        self.margin = self.obs_threshold + self.monitor_margin

    def row_limit(self, m: int, law: str) -> int:
        """The bound on active rows for a task of ``m`` rows under ``law``.

        Laws (9) and (8): ``v <= n - m`` (22), the extended task's rows. Law (10) puts
        the constraints first and the task in their null space (docs/method.md,
        "Conflicts"), so up to ``n`` constraint rows can hold while the task takes what
        is left; ``max_active`` lowers either bound.

        Raises:
            InputError: No row can be active (``n - m <= 0`` under laws (9) and (8)).
        """
        nv = self.robot.nv
        free = nv if law == "pseudoinverse" else nv - m
        limit = free if self.max_active is None else min(int(self.max_active), free)
        rows_wanted = (
            self.obstacle_rows or self.joint_limits is not None or self.dexterity is not None
        )
        if limit <= 0 and rows_wanted:
            raise InputError(
                "constraints",
                f"a redundant task (n - m > 0) for constraint rows with law {law!r}: "
                f"n = {nv}, m = {m}; use law 'pseudoinverse' (constraints first) or a "
                "smaller task mask",
            )
        return limit

    def obstacle_info(self) -> list[dict[str, Any]]:
        """Each obstacle as a run's ``info["obstacles"]`` lists it (threshold included)."""
        return [
            {
                "name": o.name,
                "shape": o.shape,
                "position": o.position.tolist(),
                "rpy": o.rpy.tolist(),
                "velocity": o.velocity.tolist(),
                "threshold": float(self.obs_threshold[i]),
                **o.params,
            }
            for i, o in enumerate(self.obstacles)
        ]

    def dexterity_used(self) -> dict[str, Any] | None:
        """The dexterity row's settings, as a run's summary reports them (None: no row)."""
        if self.dexterity is None:
            return None
        return {"threshold": self.dexterity.threshold, "gain": self.gains["dexterity"]}

    def joint_limits_used(self) -> dict[str, Any] | None:
        """The joint-range rows' limits and thresholds, as a run's summary reports them."""
        jl = self.joint_limits
        if jl is None:
            return None
        return {
            "lower": jl.lower.tolist(),
            "upper": jl.upper.tolist(),
            "threshold": jl.threshold.tolist(),
            "q_index": [int(i) for i in jl.q_index],
            "joint_names": list(jl.joint_names),
        }
