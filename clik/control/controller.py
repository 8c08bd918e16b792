"""The online controller: clik's loop one tick at a time (docs/method.md, "Online control").

Build it once with the robot's tasks, constraints, law and gains; at each control
tick give it each task's target (and, optionally, velocity) and command the joints it
returns. Each tick runs the one sample an offline run (``clik.track``) runs, in either
engine, and says what happened: the constraints activated or released, the rows
active, each task's error, and a verdict (``ok``, ``deadlock``, ``violated``,
``diverged``, ``off_track``, ``measurement_jump``) the caller may act on; the controller
goes on after any of them. Given the joints the robot reached (``q_measured``), a tick
runs from them (docs/method.md, "Measured joints").
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np

from clik.constraints.constraint_set import ConstraintSet
from clik.control.cloud_updates import cloud_names, new_cloud
from clik.control.measured import MEASURED_JUMP, MEASUREMENT_JUMP, MeasuredJoints
from clik.control.targets import as_floats, as_mapping
from clik.control.tick import Tick
from clik.control.ticks import PythonTicks, Session
from clik.engine import load
from clik.errors import InputError
from clik.loop.compiled_run import engine_run
from clik.loop.joint_speed import JointSpeed
from clik.loop.laws import LawName
from clik.loop.stop_checks import checked_settings
from clik.loop.tracker import JOINT_SPEED, Tracker
from clik.loop.tracking import _Run
from clik.loop.tracking_status import DEFAULT_SETTLING_TIME, DEFAULT_TOLERANCE, checked_tolerance
from clik.model.base import QUATERNION_TOLERANCE
from clik.objectives.objective import Objective
from clik.outputs.result import TrackingResult
from clik.tasks.goal import Goal
from clik.tasks.task import Task
from clik.trajectory.clock import Clock

RECORD_SIZE = 10_000
"""Samples a controller's record keeps by default (the last ones: a ring)."""

EVENT_SIZE = 10_000
"""Constraint events a controller keeps by default (the last ones; the others counted)."""


class Controller:
    """clik's closed-loop IK run one control tick at a time.

    Args:
        task: One frame task (:class:`~clik.tasks.task.Task`), named ``"task"``; or
        tasks: Several, as ``clik.Goal(task, name=..., priority=..., gain=...)`` (their
            trajectories None: the targets come tick by tick).
        objectives: Eq. (5)'s null-space objectives (law (10)).
        law: ``"pseudoinverse"`` (10, default), ``"transpose"`` (9) or ``"nonlinear"`` (8).
        gain: ``alpha`` [1/s], a scalar or one per task row.
        dt: The tick [s].
        damping: Law (10)'s constant damping.
        constraints: Constraint rows (obstacles, joint ranges...).
        engine: ``"compiled"`` (default) or ``"python"``.
        joint_speed: The joint speed limits the law keeps (default: the URDF's).
        q0: The first joints (default: the robot's reference configuration).
        record_every: Keep every k-th tick in the record, an integer >= 1.
        record_size: Ticks the record keeps (the last ones), an integer >= 1.
        event_size: Constraint events the controller keeps (the last ones, the others
            counted in the result's ``events_dropped``), an integer >= 1.
        tolerance: Position [m] and orientation [rad] tolerance of the ``off_track``
            verdict, which fires after ``settling_time`` [s] above it in one stretch.
        measured_jump: ``c`` of eq. (M3), > 0: a ``q_measured`` further than ``c``
            times a joint's speed limit (``model.velocityLimit``) times the time since
            the last accepted measurement is refused (verdict ``measurement_jump``).
        **checks: The stop checks' settings, as ``Tracker.run`` takes them
            (``deadlock_window``, ``deadlock_ratio``, ``deadlock_error``,
            ``max_joint_step``, ``stall_window``, ``stall_progress``).

    Raises:
        InputError: A bad setting (named), as ``clik.Tracker`` and ``Tracker.run`` refuse it.
        InfeasibleError: ``q0`` outside the robot's joint limits.

    One controller, one thread at a time: :meth:`step`, :meth:`reset`, :meth:`result`
    and :meth:`move_obstacle` called from several threads wait for each other (each runs
    whole); called from inside one of them in the same thread (a target's ``__array__``,
    a garbage-collection callback), they raise :class:`~clik.errors.InputError`. A tick,
    once returned, is its own: it may be read from any thread.

    Example:
        >>> ctl = clik.Controller(task, law="pseudoinverse", gain=100, q0=q0)
        >>> tick = ctl.step(target_pose)          # pin.SE3 or 4x4, this tick's target
        >>> robot_driver.command(tick.q)          # q_{k+1}
        >>> if tick.verdict != "ok": print(tick.verdict, tick.reason)
    """

    def __init__(
        self,
        task: Task | None = None,
        *,
        tasks: Sequence[Goal] | None = None,
        objectives: Sequence[Objective] | None = None,
        law: LawName = "pseudoinverse",
        gain: float | Sequence[float] = 100.0,
        dt: float = 1e-3,
        damping: float = 0.0,
        constraints: ConstraintSet | None = None,
        engine: str = "compiled",
        joint_speed: JointSpeed | None = JOINT_SPEED,
        q0: np.ndarray | Sequence[float] | None = None,
        record_every: int = 1,
        record_size: int = RECORD_SIZE,
        event_size: int = EVENT_SIZE,
        tolerance: tuple[float, float] = DEFAULT_TOLERANCE,
        settling_time: float = DEFAULT_SETTLING_TIME,
        measured_jump: float = MEASURED_JUMP,
        **checks: float,
    ) -> None:
        self.tracker = tr = Tracker(
            task, law=law, gain=gain, dt=dt, damping=damping, constraints=constraints,
            engine=engine, joint_speed=joint_speed, tasks=tasks, objectives=objectives,
        )  # fmt: skip
        self.robot = tr.robot
        self.dt = tr.dt
        defaults = {
            "deadlock_window": 0.1, "deadlock_ratio": 1e-4, "deadlock_error": 1e-3,
            "max_joint_step": 1.0, "stall_window": 0.5, "stall_progress": 0.01,
        }  # fmt: skip
        unknown = sorted(set(checks) - set(defaults))
        if unknown:
            raise InputError("Controller", f"settings among {sorted(defaults)}", unknown[0])
        self.settings = checked_settings(tr.dt, **{**defaults, **checks})
        self.tolerance = checked_tolerance(tolerance, settling_time)
        self.record_every = _count(record_every, "record_every")
        self.record_size = _count(record_size, "record_size")
        self.event_size = _count(event_size, "event_size")
        self.measured = MeasuredJoints(self.robot, _positive(measured_jump, "measured_jump"), tr.dt)
        """The measured joints' checks, eq. (M3), and their record."""
        self.names: list[str] = ["task"] if tr.stack is None else list(tr.stack.names)
        """The tasks' names, in order (the keys of the targets and of ``Tick.errors``)."""
        tasks_ = [tr.task] if tr.stack is None else [g.task for g in tr.stack.goals]
        engine_ = load()
        self._turn = engine_.Turn(InputError)
        if tr.engine == "python":
            self._ticks: Any = PythonTicks(
                self._turn, self.names, [t.tick_target() for t in tasks_], self.measured
            )
        else:
            Tick.register(engine_.Tick)  # the compiled engine's ticks are Ticks
            tol = self.tolerance
            self._ticks = engine_.Ticker(
                turn=self._turn, refuse=InputError, convert=as_floats, as_mapping=as_mapping,
                check_model=self.robot.check_model, names=self.names,
                tol_position=tol.position, tol_orientation=tol.orientation,
                settling_time=tol.settling_time, dt=tr.dt, jump_bound=self.measured.bound,
                rotations=self.measured.rotations, rotation_tolerance=QUATERNION_TOLERANCE,
                measured_words=self.measured.words,
                measured_velocity_words=self.measured.velocity_words,
            )  # fmt: skip
        self._tick = self._ticks.step  # step's call (bound once: it runs at every tick)
        self._session: Session
        self._current: dict[str, Any] = {}  # the obstacles moved, clouds replaced in this session
        self.reset(q0)

    @contextmanager
    def _held(self, who: str) -> Iterator[None]:
        """The controller's turn for ``who`` (one thread at a time)."""
        self._turn.take(who)
        try:
            yield
        finally:
            self._turn.give()

    def reset(self, q: np.ndarray | Sequence[float] | None = None) -> None:
        """Start a new session at ``q`` (default: the robot's reference configuration).

        The clock restarts at 0, the record, events and checks are emptied.

        Raises:
            InputError: ``q`` not a configuration of the robot.
            InfeasibleError: ``q`` outside the robot's joint limits.
        """
        robot, tr = self.robot, self.tracker
        with self._held("Controller.reset"):
            robot.check_model()
            q0 = robot.check_configuration(robot.q_reference if q is None else q, "q")
            robot.check_within_limits(q0, "q")
            tr._warn_stability(q0)
            run = _Run(
                tr, Clock(self.dt), None, self.record_every, self.settings, None,
                self.tolerance, q0, ring=self.record_size, events=self.event_size,
            )  # fmt: skip
            if tr.engine == "python":
                self._session = Session(run, self.measured)
                self._ticks.restart(run, q0, self._session)
            else:
                native = engine_run(run)
                self._session = Session(run, self.measured, native)
                self.measured.restart(q0, run.rec.capacity)
                m = self.measured
                self._ticks.restart(
                    native, np.array(q0, dtype=float), self._session.explain,
                    m.commanded, m.measured, m.qdot_measured,
                )  # fmt: skip
            self._current = {}

    @property
    def k(self) -> int:
        """The next tick's index (its time is ``k dt``)."""
        return int(self._ticks.k)

    @property
    def q(self) -> np.ndarray:
        """The joints the next tick starts from (a copy)."""
        return np.array(self._ticks.q, dtype=float)

    def move_obstacle(
        self,
        name: str,
        position: Sequence[float] | np.ndarray,
        rpy: Sequence[float] | None = None,
        velocity: Sequence[float] | np.ndarray | None = None,
    ) -> None:
        """An obstacle moved: at ``position`` [m] at the next tick, then ``velocity``.

        It moves with ``velocity`` [m/s] from then on (default: at rest), rotated by
        ``rpy`` [rad] (default: as it was).

        Its distances are measured again at the next tick (its certificates dropped).

        Raises:
            InputError: No obstacle so named, or not three finite numbers.
        """
        with self._held("Controller.move_obstacle"):
            self._move_one(name, position, rpy, velocity)

    def update_cloud(self, name: str, points: Any, robot_padding: float | None = None) -> None:
        """Cloud ``name`` given new points from the next tick on (as ``step(obstacles=)``).

        Args:
            name: The cloud's name.
            points: ``(N, 3)`` points [m] in the cloud's frame; NaN or infinite rows dropped.
            robot_padding: Also remove the points within this margin [m] of the robot at
                the controller's joints (a camera that sees the arm); None: keep them all.

        Raises:
            InputError: No cloud so named, points not ``(N, 3)`` numbers.
        """
        with self._held("Controller.update_cloud"):
            self._replace_cloud(name, points, robot_padding)

    def _replace_cloud(self, name: str, points: Any, robot_padding: float | None) -> None:
        """:meth:`update_cloud`, the turn held."""
        cset, q = self._session.run.cset, self.q
        cloud, threshold = new_cloud(cset, self._current, name, points, q, robot_padding)
        self._session.replace_cloud(cloud, threshold)

    def _move_one(self, name: str, position: Any, rpy: Any, velocity: Any) -> None:
        """:meth:`move_obstacle`, the turn held."""
        cset = self._session.run.cset
        names = [] if cset is None else [o.name for o in cset.obstacles]
        if name not in names:
            raise InputError("obstacles", f"an obstacle's name, one of {names}", name)
        current = self._current.get(name, cset.obstacles[names.index(name)])  # type: ignore[union-attr]
        obstacle = current.moved(position, rpy, (0.0, 0.0, 0.0) if velocity is None else velocity)
        self._current[name] = obstacle
        self._session.move_obstacle(obstacle, obstacle.position, self._session.run.t[self.k])

    def step(
        self,
        targets: Any,
        velocities: Any = None,
        obstacles: Any = None,
        *,
        q_measured: Any = None,
        qdot_measured: Any = None,
    ) -> Tick:
        """One tick: this tick's targets in, the next joints and a verdict out.

        Args:
            targets: Each task's target at this tick: with one task the target itself,
                else a mapping ``{name: target}`` (every task). A frame task's target is
                a ``pin.SE3`` or a 4x4 pose (a position (3,) for a position task, a
                rotation (3, 3) for an orientation task), a centre of mass's a position
                (3,) [m], a posture's its joints' values [rad or m]. A NumPy float64
                array is read as it is; anything else (other dtypes, layouts, lists) is
                converted once.
            velocities: Optionally, the targets' velocities (feed-forward ``xdot_d`` of
                (10)), alike: a frame task's ``(linear, angular)`` (6,) [m/s, rad/s]
                (or (3,) for a position or orientation task), a centre of mass's (3,),
                a posture's per joint. None (or a task left out): zero feed-forward,
                and the stall check takes the reference as at rest only while every
                target stays where it was at the previous tick.
            obstacles: Obstacles that moved, by name: a position (3,) [m] (then at rest)
                or ``(position, velocity)`` [m, m/s]; as :meth:`move_obstacle`, from this
                tick on. A cloud's new points: an ``(N, 3)`` array [m] in its frame
                (:meth:`update_cloud`).
            q_measured: The joints the robot reached (nq,) [rad or m], read at this tick:
                the law runs from them (eq. (M1)) and the commanded joints integrate its
                velocity, ``q = q_k (+) qdot dt`` (M2); unless they moved further than
                ``measured_jump`` allows since the last accepted ones (M3): then the law
                runs from the controller's own joints ``q_k`` and the verdict is
                ``measurement_jump``. None: the law runs from ``q_k`` (the previous
                tick's ``q``). Converted as a target is.
            qdot_measured: The robot's joint velocities (nv,) [rad/s or m/s], with
                ``q_measured``: recorded (the first-order law does not read them).

        Returns:
            The tick (:class:`~clik.control.tick.Tick`): ``q`` to command, ``qdot``,
            events, active rows, errors and the verdict; its arrays are its own.

        Raises:
            InputError: A missing or malformed target, velocity, obstacle, ``q_measured``
                or ``qdot_measured`` (named, with what was expected); the robot's model
                changed; a call from inside another of this controller's calls in the
                same thread (one thread at a time).
        """
        if obstacles is None:
            return self._tick(targets, velocities, q_measured, qdot_measured)
        with self._held("Controller.step"):
            self._move(obstacles)
            return self._ticks.step_held(targets, velocities, q_measured, qdot_measured)

    def _move(self, obstacles: Any) -> None:
        """:meth:`step`'s ``obstacles``: each moved, from this tick on (the turn held)."""
        if not isinstance(obstacles, Mapping):
            raise InputError(
                "obstacles",
                "a mapping of obstacle name to position or (position, velocity)",
                obstacles,
            )
        clouds = cloud_names(self._session.run.cset)
        for name, value in obstacles.items():
            if name in clouds:
                self._replace_cloud(name, value, None)
                continue
            pair = isinstance(value, tuple) and len(value) == 2
            position, velocity = value if pair else (value, None)
            self._move_one(name, position, None, velocity)

    def result(self) -> TrackingResult:
        """The session so far as a :class:`~clik.outputs.result.TrackingResult`.

        Its arrays hold the record's ticks (the last ``record_size`` kept); its events
        the last ``event_size`` (``events_dropped`` counts the others); its violations
        and task errors the whole session's. Its status is the worst verdict of the
        session (``completed`` when every tick was ``ok``), judged as an offline run's
        (limits crossed, tolerance, joint speeds). A session given measured joints
        also records, per kept tick, ``extra["q_commanded"]`` (nq, the joints the
        controller had commanded for it), ``extra["q_measured"]`` and
        ``extra["qdot_measured"]`` (NaN where none was given); ``q`` holds the joints
        each tick's law ran from. The ticks whose verdict was ``measurement_jump`` are
        counted in ``info["measurement_jumps"]`` and in the reason.
        """
        with self._held("Controller.result"):
            session = self._session
            session.sync()
            status, reason = session.worst
            judged = ("ok", "violated", "off_track", MEASUREMENT_JUMP)
            if status in judged:  # judged below, as an offline run
                status = "completed"
                reason = f"ran {self.k} ticks ({max(self.k - 1, 0) * self.dt:.6g} s)"
            if session.jumps:
                reason += f"; {session.jumps} measurement(s) refused ({MEASUREMENT_JUMP}, eq. (M3))"
            result = session.run.finished(status, reason, float(self._ticks.wall))
            if self._ticks.measured_given:
                result.extra.update(self.measured.record(session.run.rec.order()))
            result.info["measurement_jumps"] = session.jumps
            return result


def _positive(value: Any, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.number):
        raise InputError(field, "a finite number > 0", value)
    if not (np.isfinite(value) and value > 0):
        raise InputError(field, "a finite number > 0", value)
    return float(value)


def _count(value: Any, field: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise InputError(field, "an integer >= 1", value)
    return int(value)
