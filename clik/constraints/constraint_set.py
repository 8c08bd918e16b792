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

import copy
import warnings
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from clik.bounds import in_range
from clik.constraints.collision_scene import (
    CollisionScene,
    NoCollisionGeometryWarning,
    SkippedGeometryWarning,
)
from clik.constraints.dexterity import Dexterity
from clik.constraints.joint_limits import JointLimits, robot_limit_rows
from clik.constraints.kind import ConstraintKind
from clik.constraints.link_pairs import LinkPairs
from clik.constraints.obstacle import Obstacle
from clik.constraints.obstacle_avoidance import ObstacleAvoidance
from clik.constraints.read_only import ReadOnlyList
from clik.errors import GeometryError, InputError

if TYPE_CHECKING:
    from clik.model.robot import Robot

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
        kinds: Further kinds of rows (:class:`~clik.constraints.kind.ConstraintKind`:
            workspace boxes, tool cones, ...), each with its own gain; their rows
            follow the ones above.
        release: ``"projection"`` (default) or ``"sign"``.
        hysteresis: With the sign rule, release only when the error is below
            ``-hysteresis * threshold``.
        max_active: Bound on active rows, an integer >= 0 (default and maximum: ``n - m``
            under laws (9) and (8), eq. (22); ``n`` under law (10), see :meth:`row_limit`;
            a larger one is taken as ``n``).
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

    Sharing: a set may serve any number of trackers, runs and solves, in any threads.
    Each run takes a :meth:`snapshot` when it starts and keeps its own state (its
    geometry data, its rows); what the set shows (:attr:`obstacles`, the kinds' names
    and limits) is read-only, and the set changes only through :meth:`set_obstacles`,
    :meth:`move_obstacle` and its checked settings, each of which applies to the runs
    that start afterwards. A robot whose model changed after loading is refused.

    Raises:
        InputError: A bad setting (the field is named), or a robot whose model changed
            after it was loaded.
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
        kinds: Sequence[ConstraintKind] = (),
        release: str = "projection",
        hysteresis: float = 0.0,
        max_active: int | None = None,
        monitor_margin: float = 0.1,
    ) -> None:
        robot.check_model()
        for field, value in (
            ("obstacle_threshold", obstacle_threshold),
            ("self_threshold", self_threshold),
        ):
            if not in_range(value, 0.0, strict=True):
                raise InputError(f"constraints.{field}", "a positive distance [m]", value)
        for field, gain in (
            ("obstacle_gain", obstacle_gain),
            ("joint_gain", joint_gain),
            ("self_gain", self_gain),
            ("dexterity_gain", dexterity_gain),
        ):
            if gain is not None and not in_range(gain, 0.0, strict=True):
                raise InputError(f"constraints.{field}", "a positive gain [1/s]", gain)
        if dexterity is not None and not isinstance(dexterity, Dexterity):
            raise InputError("constraints.dexterity", "a Dexterity(threshold=...)", dexterity)
        if joint_limits is not None and not isinstance(joint_limits, JointLimits):
            raise InputError("constraints.joint_limits", "a JointLimits(robot, ...)", joint_limits)
        for i, kind in enumerate(kinds):
            if not isinstance(kind, ConstraintKind) or isinstance(
                kind, (JointLimits, Dexterity, ObstacleAvoidance, LinkPairs)
            ):
                raise InputError(
                    f"constraints.kinds[{i}]",
                    "a constraint kind (Workspace, Cone, ...); joint ranges, obstacles, link "
                    "pairs and dexterity have their own keywords",
                    kind,
                )
        own: list[ConstraintKind] = []
        if joint_limits is not None:
            own.append(_with_gain(joint_limits, joint_gain))
        own.append(
            ObstacleAvoidance(obstacles, obstacle_rows, obstacle_threshold, form, obstacle_gain)
        )
        if self_collision:
            own.append(LinkPairs(self_threshold, self_gain))
        if dexterity is not None:
            own.append(_with_gain(dexterity, dexterity_gain))
        self._setup(
            robot, own + list(kinds), links, release, hysteresis, max_active, monitor_margin
        )

    def _setup(
        self,
        robot: Robot,
        kinds: list[ConstraintKind],
        links: Sequence[str] | None,
        release: str,
        hysteresis: float,
        max_active: int | None,
        monitor_margin: float,
    ) -> None:
        self.robot = robot
        self.kinds: tuple[ConstraintKind, ...] = tuple(kinds)
        """The set's kinds of rows, in the order their rows are evaluated and named."""
        self.release_rule = release
        self.hysteresis = hysteresis
        self.max_active = max_active
        self.monitor_margin = monitor_margin
        self._links = None if links is None else tuple(links)
        self._obstacle_kind = next(k for k in kinds if isinstance(k, ObstacleAvoidance))
        self._self_collision = any(isinstance(k, LinkPairs) for k in kinds)
        self._build_scene()

    def _build_scene(self) -> None:
        obstacles = self._obstacle_kind.obstacles
        need_scene = bool(obstacles) or self._self_collision
        need_scene = need_scene or any(k.needs_scene for k in self.kinds)  # clouds
        self.scene = (
            CollisionScene(self.robot, obstacles, self._links, self._self_collision)
            if need_scene
            else None
        )
        if self.scene is not None and self.scene.n_links == 0:  # clouds without link geometry
            raise GeometryError(f"robot {self.robot.name} has no collision geometry for its clouds")

    @property
    def srdf_skipped_pairs(self) -> int:
        """Link pairs left out of the self-collision rows by the robot's SRDF.

        Pairs of link geometries that are neither adjacent nor touching at the reference
        but whose links the SRDF's ``<disable_collisions>`` name (0 without
        ``self_collision``; see ``robot.disabled_collision_pairs``).
        """
        return 0 if self.scene is None else self.scene.srdf_skipped_pairs

    def with_margin(self, margin: float) -> ConstraintSet:
        """A new set whose rows hold ``margin`` beyond every threshold (solve mode's rows).

        Every kind gives its own copy (:meth:`ConstraintKind.with_margin`); without
        joint-range rows, rows :data:`~clik.constraints.joint_limits.ROBOT_LIMIT_ROWS`
        inside the robot's own limits keep the joints there.
        """
        kinds = [k.with_margin(margin) for k in self.kinds]
        if not any(getattr(k, "covers_robot_limits", False) for k in kinds):
            kinds.insert(0, robot_limit_rows(self.robot))
        out = ConstraintSet.__new__(ConstraintSet)
        with warnings.catch_warnings():  # this set has warned about its geometry already
            warnings.simplefilter("ignore", NoCollisionGeometryWarning)
            warnings.simplefilter("ignore", SkippedGeometryWarning)
            out._setup(
                self.robot, kinds, self._links, self.release_rule, self.hysteresis,
                self.max_active, self.monitor_margin,
            )  # fmt: skip
        return out

    def snapshot(self) -> ConstraintSet:
        """The set as it is now, for one run: later changes to this set do not reach it.

        A change (:meth:`set_obstacles`, :meth:`move_obstacle`, a new ``max_active``...)
        replaces what it changes on this set, never the kinds or scene objects a
        snapshot holds, so a copy of the set's attributes is enough.

        Raises:
            InputError: The robot's model changed since the set was built.
        """
        self.robot.check_model(full=False)  # the whole model: at the set, tracker, solve
        return copy.copy(self)

    # -- settings, checked when set --------------------------------------------------------

    @property
    def release_rule(self) -> str:
        """``"projection"`` or ``"sign"`` (:data:`RELEASE_RULES`)."""
        return self._release_rule

    @release_rule.setter
    def release_rule(self, value: str) -> None:
        if value not in RELEASE_RULES:
            raise InputError("constraints.release", "'projection' or 'sign'", value)
        self._release_rule = value

    @property
    def hysteresis(self) -> float:
        """The sign rule's hysteresis, a fraction of the threshold (>= 0)."""
        return self._hysteresis

    @hysteresis.setter
    def hysteresis(self, value: float) -> None:
        if not in_range(value, 0.0):
            raise InputError("constraints.hysteresis", "a number >= 0", value)
        self._hysteresis = float(value)

    @property
    def max_active(self) -> int | None:
        """The bound on active rows given (None: the law's, :meth:`row_limit`).

        An integer >= 0; one above the robot's ``nv`` is taken as ``nv`` (no more rows can
        hold at once), so the engine never sees a count beyond the robot's.
        """
        return self._max_active

    @max_active.setter
    def max_active(self, value: int | None) -> None:
        if value is not None and (
            isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0
        ):
            raise InputError(
                "constraints.max_active", "an integer >= 0 or None (the law's bound)", value
            )
        self._max_active = None if value is None else min(int(value), self.robot.nv)

    @property
    def monitor_margin(self) -> float:
        """Distance beyond a threshold still evaluated exactly [m] (> 0)."""
        return self._monitor_margin

    @monitor_margin.setter
    def monitor_margin(self, value: float) -> None:
        if not in_range(value, 0.0, strict=True):
            raise InputError("constraints.monitor_margin", "a positive distance [m]", value)
        self._monitor_margin = float(value)

    def fingerprint(self) -> tuple[Any, ...]:
        """What a prepared solve depends on: a set changed since is prepared again."""
        return (
            id(self.scene), self.release_rule, self.hysteresis, self.max_active,
            self.monitor_margin, tuple(k.fingerprint() for k in self.kinds),
        )  # fmt: skip

    # -- obstacles between runs ----------------------------------------------------------

    def set_obstacles(self, obstacles: Sequence[Obstacle]) -> None:
        """Replace the obstacles (add, remove) between runs, keeping the robot as loaded.

        The link hulls are computed once per robot; only the collision pairs are rebuilt.
        A run takes the obstacles as they are when it starts (both engines): a change
        made during a run (from its ``progress`` callback, or another thread) applies to
        the next run.
        """
        old = self._obstacle_kind
        new = ObstacleAvoidance(obstacles, old.rows, old.threshold, old.form, old.gain)
        self.kinds = tuple(new if k is old else k for k in self.kinds)
        self._obstacle_kind = new
        self._build_scene()

    def move_obstacle(
        self,
        name: str,
        position: Sequence[float] | np.ndarray,
        rpy: Sequence[float] | None = None,
        velocity: Sequence[float] | None = None,
    ) -> None:
        """Move an obstacle between runs (no rebuild): new position [m], rpy [rad], velocity.

        As :meth:`set_obstacles`, a run takes the obstacles as they are when it starts:
        a move during a run applies to the next run.

        Raises:
            InputError: An unknown name, or not three finite numbers.
        """
        names = [o.name for o in self.obstacles]
        if name not in names:
            raise InputError("obstacle", f"one of {names}", name)
        i = names.index(name)
        moved = self.obstacles[i].moved(position, rpy, velocity)
        kind = self._obstacle_kind.moved(i, moved)
        assert self.scene is not None
        self.scene = self.scene.moved(i, moved)
        self.kinds = tuple(kind if k is self._obstacle_kind else k for k in self.kinds)
        self._obstacle_kind = kind

    # -- what the kinds say, read whole ----------------------------------------------------

    def _kind(self, cls: type[K]) -> K | None:
        return next((k for k in self.kinds if isinstance(k, cls)), None)

    @property
    def obstacles(self) -> ReadOnlyList[Obstacle]:
        """The obstacles (always monitored), read-only.

        Change them with :meth:`set_obstacles` or :meth:`move_obstacle`: a change in place
        (``append``, item assignment...) raises an :class:`~clik.errors.InputError`.
        """
        return self._obstacle_kind.obstacles

    @property
    def obstacle_rows(self) -> bool:
        """Whether obstacle rows may enter the task."""
        return self._obstacle_kind.rows

    @property
    def obstacle_threshold(self) -> float:
        """Default ``d_o`` [m]."""
        return self._obstacle_kind.threshold

    @property
    def form(self) -> str:
        """The obstacle rows' form."""
        return self._obstacle_kind.form

    @property
    def obs_threshold(self) -> np.ndarray:
        """``d_o`` per obstacle [m]."""
        return self._obstacle_kind.thresholds

    @property
    def obs_vel(self) -> np.ndarray:
        """Velocity per obstacle (n_obs, 3) [m/s]."""
        return self._obstacle_kind.velocities

    @property
    def joint_limits(self) -> JointLimits | None:
        """The joint-range rows, or None."""
        return self._kind(JointLimits)

    @property
    def dexterity(self) -> Dexterity | None:
        """The dexterity row, or None."""
        return self._kind(Dexterity)

    @property
    def self_threshold(self) -> float:
        """Threshold of link pairs [m] (the default without self-collision rows)."""
        pairs = self._kind(LinkPairs)
        return 0.01 if pairs is None else pairs.threshold

    @property
    def gains(self) -> Mapping[str, float | None]:
        """Each kind's gain by kind name (None: the law's default), read-only.

        A gain is the kind's own (``cset.dexterity.gain``, ``Workspace(..., gain=...)``);
        this view only reads them, so writing into it raises instead of doing nothing.
        """
        out: dict[str, float | None] = dict.fromkeys(("obstacle", "joint", "self", "dexterity"))
        for k in reversed(self.kinds):  # the first kind of a name wins
            out[k.name] = k.gain
        return MappingProxyType(out)

    @property
    def link_labels(self) -> list[str]:
        """Per link geometry, its name in constraint names."""
        return [] if self.scene is None else list(self.scene.link_labels)

    @property
    def immovable_pairs(self) -> set[str]:
        """Constraints no joint motion changes (a link geometry on the fixed base)."""
        out: set[str] = set()
        scene = self.scene
        if scene is None:
            return out
        for label, joint in zip(scene.link_labels, scene.link_joint, strict=True):
            if joint == 0:
                out.update(f"obstacle:{o.name}:{label}" for o in self.obstacles)
        return out

    def joint_ranges(self) -> dict[str, tuple[float, float]]:
        """Joint limits tighter than the robot's, from the kinds (violations)."""
        out: dict[str, tuple[float, float]] = {}
        for k in self.kinds:
            out.update(k.joint_ranges())
        return out

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
        rows_wanted = any(k.wants_rows for k in self.kinds)
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
        return self._obstacle_kind.info()

    def engine_config(self) -> Any:
        """The set as the compiled engine's typed ``ConstraintSetConfig``.

        The engine reads no Python attribute by name: each kind gives its settings as a
        small bound struct (:meth:`ConstraintKind.engine_config`), in the order their rows
        are evaluated and named; the collision scene as a ``SceneConfig`` (its
        ``pin.GeometryModel`` borrowed, never copied). Each struct checks its sizes when
        built (``ValueError``); the set checks them against the robot's model and scene.
        """
        from clik.engine import load

        return load().ConstraintSetConfig(
            model=self.robot.model,
            kinds=[k.engine_config() for k in self.kinds],
            scene=None if self.scene is None else self.scene.engine_config(),
            release=self.release_rule,
            hysteresis=float(self.hysteresis),
            max_active=None if self.max_active is None else int(self.max_active),
            monitor_margin=float(self.monitor_margin),
        )


K = TypeVar("K", bound=ConstraintKind)


def _with_gain(kind: K, gain: float | None) -> K:
    """``kind`` with ``gain`` (a copy: the user's object is left as given)."""
    return kind if gain is None or kind.gain == gain else kind.replaced(gain=gain)
