r"""What every kind of constraint row says, and what the shared core asks of it.

A constraint contributes, while active, one row to the extended task (24)-(25):
an error ``e_c`` (positive inside its threshold), a Jacobian row ``j_c`` and a
feed-forward ``f_c`` with ``edot_c = f_c - j_c qdot``. The core
(:class:`~clik.constraints.constraint_run.ConstraintRun`) owns what every kind
shares: candidates, activation and release, the bound on active rows (22),
events, the active rows' record, and it never names a kind. A kind owns:

- its settings and its gain (:class:`ConstraintKind`, one Python class; one C++
  type in ``src/engine/constraints/`` built from :meth:`ConstraintKind.engine_config`);
- its per-run state (:class:`KindRun`, made by :meth:`ConstraintKind.start`): the
  candidates it offers each sample (:meth:`KindRun.evaluate`), their rows
  (:meth:`KindRun.row`), the limits it guards (:meth:`KindRun.observe_limits`),
  what it records (:meth:`KindRun.record`, :meth:`KindRun.records`);
- its summary fields (:meth:`ConstraintKind.finish`, from the records of either
  engine) and its check of a single pose (:meth:`ConstraintKind.check`, solve mode);
- its words: the keys it owns (:meth:`ConstraintKind.owns`, ``<name>:...``), the pose
  check's name of a key (:meth:`ConstraintKind.check_name`), how its depths and its
  crossed limits read (:attr:`ConstraintKind.depth_measure`,
  :attr:`ConstraintKind.limit_words`), and how the 3-D view draws a region it reports
  (:meth:`ConstraintKind.region`).

A new kind is one subclass of each, registered in :mod:`clik.constraints.registry`;
``tests/constraints/test_kind_protocol.py`` fails while any part is missing.
"""

from __future__ import annotations

import copy
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, TypeVar

import numpy as np

from clik.bounds import in_range, real
from clik.constraints.region import Region
from clik.constraints.words import AS_IS, LimitWords, Measure
from clik.errors import InputError
from clik.schema import MAX_GAIN_DT, Table

if TYPE_CHECKING:
    import pinocchio as pin

    from clik.clouds.cloud_obstacle import CloudObstacle
    from clik.constraints.collision_scene import CollisionScene, SceneRun
    from clik.constraints.obstacle import Obstacle
    from clik.constraints.violations import ViolationMonitor
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult
    from clik.trajectory.clock import Clock


CHECK_TOLERANCE = 1e-12
"""Accepted shortfall of an error in a pose check [m or rad] (rounding only)."""


@dataclass(frozen=True)
class Violation:
    """One constraint that a configuration does not satisfy (solve mode's check).

    Attributes:
        constraint: The constraint in words: ``"obstacle 'table'"``,
            ``"joint range of panda_joint4"`` or ``"link pair panda_link2-panda_link6"``.
        detail: Where and by how much, with units.
        shortfall: How far inside the threshold [m or rad], > 0.
    """

    constraint: str
    detail: str
    shortfall: float

    def describe(self) -> str:
        """``"obstacle 'table' blocks: link panda_link7 at 0.012 m < threshold 0.05 m"``."""
        return f"{self.constraint} blocks: {self.detail}"


class PoseCheck(Protocol):
    """What a kind's check of one configuration reads.

    :class:`clik.constraints.pose_check.PoseCheck` is the one clik uses.
    """

    scene: CollisionScene | None

    def distances(self, q: np.ndarray) -> Any:
        """Coal's distance results of every pair of the scene at ``q``."""

    def frame_placement(self, q: np.ndarray, frame_id: int) -> pin.SE3:
        """A frame's placement in the world at ``q``."""

    def task_jacobian(self, q: np.ndarray) -> np.ndarray | None:
        """The task's Jacobian (m, nv) at ``q``, or None without a task."""


class Candidate:
    """One constraint whose row may enter the extended task at this sample.

    Attributes:
        key: Constraint name (``joint:<joint>:lower``, ``obstacle:<obstacle>:<link>``, ...).
        run: The kind's run that offered it (its rows are that run's to write).
        item: The kind's own index of the constraint (a joint row, a pair, a wall).
        error: Its error, positive inside the threshold [m, rad, m^2 or m^p].
        scale: Its threshold in the error's unit (activation compares ``error / scale``).
        threshold: The threshold ``d_o``, ``d_q``, ``w_min``, ... in the kind's unit.
        feed: Feed-forward ``f_c`` of its row (14), set with the row.
        witness: The pair of points ``(a, b)`` a distance row is measured between
            (recorded and drawn), or None.
    """

    __slots__ = ("error", "feed", "item", "key", "run", "scale", "threshold", "witness")

    def __init__(
        self, key: str, run: KindRun, item: int, error: float, scale: float, threshold: float
    ) -> None:
        self.key, self.run, self.item = key, run, item
        self.error, self.scale, self.threshold = error, scale, threshold
        self.feed = 0.0
        self.witness: tuple[np.ndarray, np.ndarray] | None = None


@dataclass
class RunSetup:
    """What a kind's run is made with (one per run, :meth:`ConstraintKind.start`).

    Attributes:
        robot: The robot.
        m: Task rows.
        law: The law's name.
        t: The run's time grid [s].
        n_rec: Recorded samples.
        frame_id: The task's frame (-1: none given).
        task_rows: The task's rows among ``(x, y, z, rx, ry, rz)``.
        scene: The set's collision scene (link geometry, obstacles), or None.
        monitor_margin: Distance beyond a threshold still evaluated exactly [m].
        geometry: The run's own state of ``scene`` (placements, distances), or None.
    """

    robot: Robot
    m: int
    law: str
    t: np.ndarray | Clock
    n_rec: int
    frame_id: int
    task_rows: np.ndarray
    scene: CollisionScene | None
    monitor_margin: float
    geometry: SceneRun | None = None

    @property
    def dt(self) -> float:
        """The run's sample time [s] (0 for a single sample)."""
        return float(self.t[1] - self.t[0]) if self.t.shape[0] > 1 else 0.0


class Sample:
    """What the kinds see at one sample (filled by the core, read by every kind).

    Attributes:
        tk: The sample's time [s].
        q: Configuration (kinematics and joint Jacobians computed at it).
        dq_abs: ``|dq|`` since the previous sample (nv,), or None at the first.
        model, data: The robot's model and the run's data (kinematics at ``q``).
        J_task: The task rows of ``J_e`` (m, nv), eq. (3).
        exact: This sample is recorded (distances are made exact).
        active: The active constraints, in row order.
        active_keys: Their keys.
    """

    __slots__ = (
        "J_task",
        "_placed",
        "_scene",
        "active",
        "active_keys",
        "data",
        "dq_abs",
        "exact",
        "model",
        "q",
        "tk",
    )

    def __init__(
        self,
        tk: float,
        q: np.ndarray,
        dq_abs: np.ndarray | None,
        robot: Robot,
        J_task: np.ndarray,
        exact: bool,
        active: list[Candidate],
        scene: SceneRun | None,
        data: pin.Data | None = None,
    ) -> None:
        self.tk, self.q, self.dq_abs, self.exact = tk, q, dq_abs, exact
        self.model = robot.model
        self.data = robot.data if data is None else data
        self.J_task = J_task
        self.active = active
        self.active_keys = {c.key for c in active}
        self._scene, self._placed = scene, False

    def place_geometries(self) -> None:
        """Place the run's scene geometry at this sample (once, for every kind)."""
        if not self._placed and self._scene is not None:
            self._scene.place_geometries(self.data, self.tk)
            self._placed = True

    def active_items(self, run: KindRun) -> list[int]:
        """The items of ``run``'s constraints that are active, in row order."""
        return [c.item for c in self.active if c.run is run]


class KindRun(ABC):
    """One kind's state during one run (nothing of it is shared between runs).

    Attributes:
        kind: The kind it runs.
        min_distance: This sample's exact nearest obstacle distance [m] (``inf``: the
            kind measures none), recorded per sample by the loop.
    """

    min_distance: float = math.inf

    def __init__(self, kind: ConstraintKind) -> None:
        self.kind = kind

    @abstractmethod
    def evaluate(self, s: Sample, out: list[Candidate]) -> None:
        """Append the candidates of this sample: error > 0, or active (``s.active_keys``)."""

    @abstractmethod
    def row(self, s: Sample, c: Candidate, out: np.ndarray) -> None:
        """Write candidate ``c``'s row ``j_c`` into ``out`` (nv,); set ``c.error``, ``c.feed``."""

    def move_obstacle(self, obstacle: Obstacle) -> bool:
        """An obstacle moved by a controller (from ``t = 0``): whether this kind has it.

        The obstacle kind moves it; the others have no obstacles.
        """
        return False

    def replace_cloud(self, cloud: CloudObstacle) -> bool:
        """A cloud replaced by a controller: whether this kind has it (the cloud kind)."""
        return False

    def observe_limits(self, tk: float, monitor: ViolationMonitor) -> None:  # noqa: B027
        """Tell ``monitor`` every limit this kind guards that is crossed at this sample."""

    def record(self, j: int) -> None:  # noqa: B027
        """Keep this sample's kind-specific record in slot ``j``."""

    def records(self, n_rec: int) -> dict[str, Any]:
        """The kind's records after the run (the compiled engine returns the same keys)."""
        return {}


K = TypeVar("K", bound="ConstraintKind")


class ConstraintKind(ABC):
    """A kind of constraint row: its settings, gain and everything particular to it.

    Attributes:
        name: The kind's name (``"joint"``, ``"obstacle"``, ...), which begins each of its
            keys: rows' keys ``<name>:...`` (or ``<name>`` alone), regions' names.
        depth_measure: How its errors read (a depth inside a threshold, in a recovery
            record's clause): :data:`~clik.constraints.words.MILLIMETRES` for lengths,
            else :data:`~clik.constraints.words.AS_IS`.
        limit_words: How a crossed limit of its constraints reads in a reason (a violation
            record's words), or None: it guards no limit. Every kind states both itself
            (``tests/constraints/test_kind_protocol.py`` asks); the defaults here only keep
            a run's words readable meanwhile.
        table: Its scenario table, ``[[constraints.<table>]]`` (an array: one entry per
            constraint), or None for the kinds with their own ``[constraints.*]`` table.
        gain: The rows' gain [1/s]; None: the law's default (see
            :class:`clik.constraints.ConstraintSet`).
        per_sample: The keys of its run's records (:meth:`KindRun.records`) whose first
            axis is the recorded samples (a controller's ring unrolls them); the others
            are the run's (per obstacle, ...).
    """

    name: ClassVar[str]
    depth_measure: ClassVar[Measure] = AS_IS
    limit_words: ClassVar[LimitWords | None] = None
    table: ClassVar[str | None] = None
    per_sample: ClassVar[tuple[str, ...]] = ()
    needs_scene: bool = False
    """Whether its rows measure the links' collision geometry (the set builds its scene)."""
    _gain: float | None = None

    @property
    def gain(self) -> float | None:
        """The rows' gain [1/s]; None: the law's default."""
        return self._gain

    @gain.setter
    def gain(self, value: float | None) -> None:
        self._gain = checked_gain(value, f"{type(self).__name__}.gain")

    @classmethod
    def owns(cls, key: str) -> bool:
        """Whether ``key`` (a row's key, a region's name) is this kind's: ``<name>[:...]``."""
        return key.partition(":")[0] == cls.name

    @classmethod
    @abstractmethod
    def check_name(cls, key: str) -> str:
        """The name its pose check (:meth:`check`) gives the constraint of row ``key``.

        ``obstacle:ball:link4`` -> ``obstacle 'ball'``: the :attr:`Violation.constraint`
        a recovery record measures its row's depth by.
        """

    @classmethod
    def region(cls, spec: dict[str, Any]) -> Region:
        """How the 3-D view draws a region :meth:`finish` put in ``info["shapes"]``.

        Only kinds that report regions define it.

        Raises:
            NotImplementedError: The kind reports no region.
        """
        raise NotImplementedError(
            f"{cls.__name__} reports a region in info['shapes'] ({spec.get('name')!r}) "
            f"but does not say how it is drawn: define {cls.__name__}.region(spec)"
        )

    @classmethod
    def read_table(cls, table: Table, dt: float) -> dict[str, Any]:
        """One ``[[constraints.<table>]]`` entry, checked, as plain values.

        ``dt`` [s] bounds the gain.
        """
        raise NotImplementedError(f"{cls.__name__} has no scenario table")

    @classmethod
    def from_spec(cls, robot: Robot, spec: dict[str, Any]) -> ConstraintKind:
        """The kind of an entry read by :meth:`read_table`: its keys are the arguments."""
        return cls(robot, **spec)  # type: ignore[call-arg]

    def replaced(self: K, **changes: Any) -> K:
        """A copy with some attributes changed (``threshold=...``, ``gain=...``)."""
        out = copy.copy(self)
        for name, value in changes.items():
            setattr(out, name, value)
        return out

    @property
    def wants_rows(self) -> bool:
        """Whether this kind may add rows (a set of kinds that add none needs no free row)."""
        return True

    @abstractmethod
    def start(self, setup: RunSetup) -> KindRun:
        """This kind's state for one run."""

    @abstractmethod
    def engine_config(self) -> Any:
        """The kind's settings as the compiled engine's typed config."""

    def finish(  # noqa: B027
        self, result: TrackingResult, records: dict[str, Any], n_rec: int, extra: dict[str, Any]
    ) -> None:
        """Put the kind's records (either engine's) and summary fields into the result."""

    def joint_ranges(self) -> dict[str, tuple[float, float]]:
        """Limits tighter than the robot's, per joint name [rad or m] (violations)."""
        return {}

    def immovable(self) -> set[str]:
        """Constraints that no joint motion can change (a link on the fixed base)."""
        return set()

    def check(self, checker: PoseCheck, q: np.ndarray) -> list[Violation]:
        """Every constraint of this kind that ``q`` does not satisfy (solve mode)."""
        return []

    def with_margin(self, margin: float) -> ConstraintKind:
        """A copy whose rows hold ``margin`` beyond each threshold (solve mode's rows)."""
        return self

    def fingerprint(self) -> tuple[Any, ...]:
        """What a prepared solve depends on (a changed kind is prepared again)."""
        return (id(self), self.gain)


def checked_gain(value: object, field: str) -> float | None:
    """A row gain as given: None (the law's default) or a positive finite number [1/s].

    Raises:
        InputError: Anything else, naming ``field``.
    """
    if value is None:
        return None
    if not in_range(value, 0.0, strict=True):
        raise InputError(field, "a positive finite gain [1/s] or None", value)
    return real(value)


def read_gain(table: Table, dt: float) -> float | None:
    """A table's optional row ``gain`` [1/s]: > 0, ``gain * dt <= MAX_GAIN_DT``."""
    value = table.number("gain", None, minimum=0.0, strict=True, unit="[1/s]")
    if value is not None and value * dt > MAX_GAIN_DT:
        raise table.error("gain", f"a gain [1/s] with gain * solver.dt <= {MAX_GAIN_DT:g}", value)
    return None if value is None else float(value)
