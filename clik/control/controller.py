"""The online controller: clik's loop one tick at a time (docs/method.md, "Online control").

Build it once with the robot's tasks, constraints, law and gains; at each control
tick give it each task's target (and, optionally, velocity) and command the joints it
returns. Each tick runs the one sample an offline run (``clik.track``) runs, in either
engine, and says what happened: the constraints activated or released, the rows
active, each task's error, and a verdict (``ok``, ``deadlock``, ``violated``,
``diverged``, ``off_track``) the caller may act on; the controller goes on after any
of them.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from typing import Any
from weakref import WeakMethod

import numpy as np

from clik.constraints.constraint_set import ConstraintSet
from clik.constraints.obstacle import Obstacle
from clik.control.targets import by_name, one_sample
from clik.control.tick import Tick
from clik.control.ticks import CompiledTicks, PythonTicks
from clik.errors import InputError
from clik.loop.joint_speed import JointSpeed
from clik.loop.laws import LawName
from clik.loop.reference_stream import rows_at_rest, task_reference
from clik.loop.stop_checks import checked_settings
from clik.loop.tracker import JOINT_SPEED, Tracker
from clik.loop.tracking import _Run
from clik.loop.tracking_status import DEFAULT_SETTLING_TIME, DEFAULT_TOLERANCE, checked_tolerance
from clik.objectives.objective import Objective
from clik.outputs.result import TrackingResult
from clik.tasks.goal import Goal
from clik.tasks.task import Task
from clik.trajectory.clock import Clock

RECORD_SIZE = 10_000
"""Samples a controller's record keeps by default (the last ones: a ring)."""

_RANK = {"diverged": 4, "deadlock": 3, "violated": 2, "off_track": 1, "ok": 0}


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
        tolerance: Position [m] and orientation [rad] tolerance of the ``off_track``
            verdict, which fires after ``settling_time`` [s] above it in one stretch.
        **checks: The stop checks' settings, as ``Tracker.run`` takes them
            (``deadlock_window``, ``deadlock_ratio``, ``deadlock_error``,
            ``max_joint_step``, ``stall_window``, ``stall_progress``).

    Raises:
        InputError: A bad setting (named), as ``clik.Tracker`` and ``Tracker.run`` refuse it.
        InfeasibleError: ``q0`` outside the robot's joint limits.

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
        tolerance: tuple[float, float] = DEFAULT_TOLERANCE,
        settling_time: float = DEFAULT_SETTLING_TIME,
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
        self.names: list[str] = ["task"] if tr.stack is None else list(tr.stack.names)
        """The tasks' names, in order (the keys of the targets and of ``Tick.errors``)."""
        self._tasks = [tr.task] if tr.stack is None else [g.task for g in tr.stack.goals]
        self.reset(q0)

    def reset(self, q: np.ndarray | Sequence[float] | None = None) -> None:
        """Start a new session at ``q`` (default: the robot's reference configuration).

        The clock restarts at 0, the record, events and checks are emptied.

        Raises:
            InputError: ``q`` not a configuration of the robot.
            InfeasibleError: ``q`` outside the robot's joint limits.
        """
        robot, tr = self.robot, self.tracker
        robot.check_model()
        q0 = robot.check_configuration(robot.q_reference if q is None else q, "q")
        robot.check_within_limits(q0, "q")
        tr._warn_stability(q0)
        self._run = _Run(
            tr, Clock(self.dt), None, self.record_every, self.settings, None, self.tolerance,
            q0, ring=self.record_size,
        )  # fmt: skip
        ticks = PythonTicks if tr.engine == "python" else CompiledTicks
        self._ticks = ticks(self._run, q0)
        self.__dict__.pop("step", None)
        if isinstance(self._ticks, CompiledTicks) and tr.stack is None:
            # the fast path: step() is the engine's own call, which hands anything but a
            # one-task float64 target to _general_step (the method below)
            ticker = self._ticks.ticker
            ticker.serving(WeakMethod(self._general_step), WeakMethod(self._tick_verdict))
            self.step = ticker.serve  # type: ignore[method-assign]
        self._worst: tuple[str, str] = ("ok", "")
        self._wall = 0.0
        self._current: dict[str, Obstacle] = {}  # the obstacles moved in this session
        self._previous: tuple[np.ndarray | None, ...] | None = None  # a packed tick's
        self._previous_k = -1  # ... and its index (a tick of the engine's fast path between)

    @property
    def k(self) -> int:
        """The next tick's index (its time is ``k dt``)."""
        return self._ticks.k

    @property
    def q(self) -> np.ndarray:
        """The joints the next tick starts from (a copy)."""
        return self._ticks.q.copy()

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
        cset = self._run.cset
        names = [] if cset is None else [o.name for o in cset.obstacles]
        if name not in names:
            raise InputError("obstacles", f"an obstacle's name, one of {names}", name)
        current = self._current.get(name, cset.obstacles[names.index(name)])  # type: ignore[union-attr]
        obstacle = current.moved(position, rpy, (0.0, 0.0, 0.0) if velocity is None else velocity)
        self._current[name] = obstacle
        self._ticks.move_obstacle(obstacle, obstacle.position, self._run.t[self.k])

    def step(self, targets: Any, velocities: Any = None, obstacles: Any = None) -> Tick:
        """One tick: this tick's targets in, the next joints and a verdict out.

        Args:
            targets: Each task's target at this tick: with one task the target itself,
                else a mapping ``{name: target}`` (every task). A frame task's target is
                a ``pin.SE3`` or a 4x4 pose (a position (3,) for a position task, a
                rotation (3, 3) for an orientation task), a centre of mass's a position
                (3,) [m], a posture's its joints' values [rad or m].
            velocities: Optionally, the targets' velocities (feed-forward ``xdot_d`` of
                (10)), alike: a frame task's ``(linear, angular)`` (6,) [m/s, rad/s]
                (or (3,) for a position or orientation task), a centre of mass's (3,),
                a posture's per joint. None (or a task left out): zero feed-forward,
                and the stall check takes the reference as at rest only while every
                target stays where it was at the previous tick.

            obstacles: Obstacles that moved, by name: a position (3,) [m] (then at rest)
                or ``(position, velocity)`` [m, m/s]; as :meth:`move_obstacle`, from this
                tick on.

        Returns:
            The tick (:class:`~clik.control.tick.Tick`): ``q`` to command, ``qdot``,
            events, active rows, errors and the verdict.

        Raises:
            InputError: A missing or malformed target or velocity (named).
        """
        if obstacles is not None:
            self._move(obstacles)
        return self._step(targets, velocities)

    _general_step = step  # the fast path's fallback (the engine's Ticker.serve calls it)

    def _tick_verdict(self, tick: Any) -> None:
        """A fast-path tick's verdict other than ok: its reason, kept if the worst."""
        ticks: Any = self._ticks  # CompiledTicks
        verdict, reason = ticks.verdict_of(tick.code, tick.t)
        tick.reason = reason
        self._note(verdict, reason)

    def _move(self, obstacles: Any) -> None:
        """:meth:`step`'s ``obstacles``: each moved, from this tick on."""
        if not isinstance(obstacles, Mapping):
            raise InputError(
                "obstacles",
                "a mapping of obstacle name to position or (position, velocity)",
                obstacles,
            )
        for name, value in obstacles.items():
            pair = isinstance(value, tuple) and len(value) == 2
            position, velocity = value if pair else (value, None)
            self.move_obstacle(name, position, velocity=velocity)

    def _step(self, targets: Any, velocities: Any) -> Tick:
        """:meth:`step` with the targets packed in Python (any tasks, any form)."""
        start = time.perf_counter()
        k, ticks = self.k, self._ticks
        tk = self._run.t[k]
        refs = self._references(targets, velocities, tk)
        verdict, reason = ticks.tick(k, refs)
        self._note(verdict, reason)
        events = ticks.new_events()
        errors = dict(zip(self.names, ticks.errors(), strict=True))
        self._wall += time.perf_counter() - start
        return Tick(
            q=ticks.q.copy(), qdot=ticks.qdot, t=tk, k=k, verdict=verdict, reason=reason,
            events=events, active=ticks.active(), errors=errors,
        )  # fmt: skip

    def _note(self, verdict: str, reason: str) -> None:
        """Keep the session's worst verdict (its result's status)."""
        if _RANK[verdict] > _RANK[self._worst[0]]:
            self._worst = (verdict, reason)

    def _references(self, targets: Any, velocities: Any, tk: float) -> tuple[Any, ...]:
        """This tick's references as the loop reads them (one-sample arrays)."""
        given = by_name(targets, self.names, "targets")
        missing = [n for n in self.names if n not in given]
        if missing:
            raise InputError("targets", f"a target for every task ({', '.join(self.names)})")
        speeds = {} if velocities is None else by_name(velocities, self.names, "velocities")
        samples = [
            one_sample(task, given[name], speeds.get(name), tk, name)
            for task, name in zip(self._tasks, self.names, strict=True)
        ]
        P_d, R_d, FF = task_reference(self.tracker.task, samples[0])
        at_rest = rows_at_rest(FF)
        g_ref = g_ff = None
        if len(samples) > 1:
            arrays = [
                t.reference_arrays(s) for t, s in zip(self._tasks[1:], samples[1:], strict=True)
            ]
            g_ref = np.ascontiguousarray(np.concatenate([a for a, _ in arrays], axis=1))
            g_ff = np.ascontiguousarray(np.concatenate([b for _, b in arrays], axis=1))
            at_rest = at_rest & rows_at_rest(g_ff)
        P_d = None if P_d is None else np.ascontiguousarray(P_d)
        R_d = None if R_d is None else np.ascontiguousarray(R_d)
        task = self.tracker.task
        refs = (P_d if task.has_position else None, R_d if task.has_orientation else None, g_ref)
        if len(speeds) < len(self.names):  # a velocity not given: at rest only if unmoved
            at_rest = at_rest & self._unmoved(refs)
        self._previous, self._previous_k = refs, self.k
        return P_d, R_d, np.ascontiguousarray(FF), at_rest, g_ref, g_ff

    def _unmoved(self, refs: tuple[np.ndarray | None, ...]) -> bool:
        """Whether every target is the previous tick's (the stall check's "at rest").

        With every velocity given, the reference is at rest where they are all zero, as
        offline; a target given without its velocity may move with a zero feed-forward,
        so it counts as at rest only while it stays where it was.
        """
        before = self._previous
        return (
            before is not None
            and self._previous_k == self.k - 1
            and all(
                (a is None and b is None)
                or (a is not None and b is not None and np.array_equal(a, b))
                for a, b in zip(refs, before, strict=True)
            )
        )

    def result(self) -> TrackingResult:
        """The session so far as a :class:`~clik.outputs.result.TrackingResult`.

        Its arrays hold the record's ticks (the last ``record_size`` kept); its events,
        violations and task errors the whole session's. Its status is the worst
        verdict of the session (``completed`` when every tick was ``ok``), judged as an
        offline run's (limits crossed, tolerance, joint speeds).
        """
        self._ticks.sync()
        status, reason = self._worst
        if status in ("ok", "violated", "off_track"):  # judged below, as an offline run
            status = "completed"
            reason = f"ran {self.k} ticks ({max(self.k - 1, 0) * self.dt:.6g} s)"
        ticks: Any = self._ticks
        wall = ticks.ticker.wall if isinstance(ticks, CompiledTicks) else self._wall
        return self._run.finished(status, reason, wall)


def _count(value: Any, field: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise InputError(field, "an integer >= 1", value)
    return int(value)
