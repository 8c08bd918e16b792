"""The tracker: a task, a law and its gains, checked once; each run checked before it starts.

:class:`Tracker` validates its settings at construction (the law, gains [1/s],
``dt`` [s], damping, the rows the constraints may add) and, before each run, the
run's size (:data:`~clik.bounds.MAX_STEPS`, :data:`~clik.bounds.MAX_RECORD_BYTES`), the
reference's reach (:class:`ReachWarning`), Euler's stability bound at ``q0``
(:class:`StabilityWarning`). The run: :mod:`clik.loop.tracking`; one call: :func:`track`.
"""

from __future__ import annotations

import copy
import math
import warnings
from collections.abc import Sequence

import numpy as np

from clik.bounds import MAX_RECORD_BYTES, MAX_STEPS, in_range, real
from clik.constraints.constraint_set import ConstraintSet
from clik.engine import ENGINES
from clik.errors import ClikWarning, InputError
from clik.loop.gains import row_gains, stability_margin
from clik.loop.joint_speed import JointSpeed, JointSpeedBounds
from clik.loop.laws import LawName, check_law, nonlinear, prioritized, transpose
from clik.loop.levels import prioritized_levels
from clik.loop.recording import bytes_per_sample, kept_samples
from clik.loop.reference_stream import REFERENCE_CHUNK, ReferenceChunks
from clik.loop.start_checks import warn_start
from clik.loop.stop_checks import checked_settings
from clik.loop.task_stack import checked_tasks
from clik.loop.tracking import ProgressCallback, _Run
from clik.loop.tracking_status import DEFAULT_SETTLING_TIME, DEFAULT_TOLERANCE, checked_tolerance
from clik.model.reach import reach_bound
from clik.objectives.objective import Objective
from clik.outputs.result import TrackingResult
from clik.tasks.extended_task import ExtendedTask
from clik.tasks.goal import Goal
from clik.tasks.kind import BaseTask
from clik.tasks.task import Task
from clik.trajectory import Trajectory, time_grid

JOINT_SPEED = JointSpeed()
"""The default: the law keeps every joint within its URDF velocity limit."""


class ReachWarning(ClikWarning):
    """The position reference leaves the frame's reach: the run will end in a deadlock."""


class StabilityWarning(ClikWarning):
    """The gains break ``alpha dt lambda_max(J J^T) < 2``: explicit Euler may go unstable."""


def _positive(value: float, field: str, unit: str) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InputError(field, f"a positive number {unit}", value) from None
    if not math.isfinite(value) or value <= 0.0:
        raise InputError(field, f"a positive finite number {unit}", value)
    return value


class Tracker:
    """The CLIK loop for one robot, task and law.

    Build once, then call :meth:`run` with a trajectory (and again with another
    one). Each run owns everything it writes: its Pinocchio data, extended task and
    the law's scratch arrays, its record, its constraint state
    (:class:`~clik.constraints.ConstraintRun`, on a snapshot of the constraint set taken
    when the run starts, with its own collision geometry data). The tracker, its task,
    robot and constraint set are only read by a run, so one tracker (or several on the
    same robot and set) may run in several threads at once, each run giving what it
    gives alone, in either engine. A change to the constraint set (``set_obstacles``,
    ``move_obstacle``) applies to the runs that start after it; the robot's model may
    not change at all (refused: :meth:`~clik.model.robot.Robot.check_model`).

    Args:
        task: The task (frame, kind, mask).
        law: ``"transpose"`` (9), ``"nonlinear"`` (8) or ``"pseudoinverse"`` (10).
        gain: ``alpha`` [1/s], a scalar or one value per task row.
        dt: Sample time [s].
        damping: Constant damping ``lambda_0`` of law (10) (on top of the automatic
            damping near singularities, see :func:`clik.loop.laws.damped_solve`).
        beta_max: Bound on the nonlinear law's extra gain [1/s] (default ``2 alpha``).
        constraints: Optional constraint rows (obstacles, joint ranges), eq. (20)-(25).
        engine: ``"compiled"`` (default: the samples run in ``clik._engine``) or
            ``"python"`` (the loop of :mod:`clik.loop.tracking`, the engine's readable
            specification).
            Both give the same statuses, events and joint trajectories.
        joint_speed: Joint speed (and acceleration) limits the law keeps at every
            sample (:class:`~clik.loop.joint_speed.JointSpeed`, docs/method.md "Joint
            speed limits in the law"); default: every joint within its URDF velocity
            limit. None (or ``JointSpeed(enabled=False)``): no limit in the law.

    Raises:
        InputError: A bad setting (named); ``constraints`` not a ``ConstraintSet`` built
            on the task's robot; or the robot's model changed after loading.
        JointNotFound: A per-joint speed limit for a joint the robot does not have.

    Warns:
        SpeedLimitWarning: Joints without a URDF velocity limit (``default_velocity``).
    """

    def __init__(
        self,
        task: Task | None = None,
        law: LawName = "transpose",
        gain: float | Sequence[float] = 1000.0,
        dt: float = 1e-3,
        damping: float = 0.0,
        beta_max: float | None = None,
        constraints: ConstraintSet | None = None,
        engine: str = "compiled",
        joint_speed: JointSpeed | None = JOINT_SPEED,
        *,
        tasks: Sequence[Goal] | None = None,
        objectives: Sequence[Objective] | None = None,
    ) -> None:
        if engine not in ENGINES:
            raise InputError("engine", " or ".join(repr(e) for e in ENGINES), engine)
        if task is not None and not (isinstance(task, BaseTask) and task.leads):
            raise InputError("task", "a clik.Task", type(task).__name__)
        task, self.stack, self.objectives = checked_tasks(task, tasks, objectives, law, gain)
        task.robot.check_model()
        if constraints is not None and not isinstance(constraints, ConstraintSet):
            raise InputError("constraints", "a ConstraintSet or None", type(constraints).__name__)
        if constraints is not None and constraints.robot is not task.robot:
            raise InputError("constraints", "a ConstraintSet built on the task's robot")
        self._engine = engine
        self.task = task
        self.robot = task.robot
        self.law = check_law(law)
        self.dt = _positive(dt, "dt", "[s]")
        self.K_task = row_gains(gain, task.m, "gain") if self.stack is None else self.stack.K
        self.m = task.m if self.stack is None else self.stack.m
        """All task rows (the primary task's, then the other tasks')."""
        self.ends = [task.m] if self.stack is None else self.stack.ends
        """The end row of each priority level."""
        damping = float(damping)
        if not math.isfinite(damping) or damping < 0.0:
            raise InputError("damping", "a finite number >= 0", damping)
        self.damping = damping
        self.alpha = float(np.max(self.K_task))
        self.beta_max = (
            2.0 * self.alpha if beta_max is None else _positive(beta_max, "beta_max", "[1/s]")
        )
        self.constraints = constraints
        self.engine = engine  # checked again: several tasks need an engine built with them
        m = self.m
        limit = constraints.row_limit(m, self.law) if constraints is not None else 0
        self.rows = m + limit
        if joint_speed is not None and not isinstance(joint_speed, JointSpeed):
            raise InputError("joint_speed", "a clik.JointSpeed or None", type(joint_speed).__name__)
        self.joint_speed = joint_speed
        self.speed: JointSpeedBounds | None = (
            None if joint_speed is None else joint_speed.bounds(self.robot)
        )
        """The bounds the law keeps every joint within (None: no speed limit in the law)."""

    @property
    def engine(self) -> str:
        """``"compiled"`` or ``"python"``: the engine the runs use (may be changed)."""
        return self._engine

    @engine.setter
    def engine(self, engine: str) -> None:
        if engine not in ENGINES:
            raise InputError("engine", " or ".join(repr(e) for e in ENGINES), engine)
        if engine == "compiled" and (self.m != self.task.m or self.leveled):
            _check_engine_goals()
        self._engine = engine

    def without_speed_limits(self) -> Tracker:
        """A copy of this tracker whose law keeps no joint speed limit (re-timing passes)."""
        other = copy.copy(self)
        other.joint_speed, other.speed = None, None
        return other

    @property
    def leveled(self) -> bool:
        """Whether law (10) runs level by level (several levels, or objectives)."""
        return self.law == "pseudoinverse" and (len(self.ends) > 1 or bool(self.objectives))

    # -- the law -----------------------------------------------------------------------

    def law_velocity(
        self, ext: ExtendedTask, r: int, out: np.ndarray, out_c: np.ndarray | None = None,
        parts: np.ndarray | None = None, z: Sequence[tuple[int, np.ndarray]] = (),
    ) -> float:  # fmt: skip
        """Joint velocity [rad/s] of the law on the first ``r`` rows of the extended task.

        ``out_c``: law (10) writes its constraint level's part there (for the speed step).
        ``parts`` (1 + L, nv) and ``z``, when :attr:`leveled`: law (10) level by level
        (:func:`clik.loop.levels.prioritized_levels`), the objectives' ``(level, z)``.

        Returns:
            Law (10): the fraction of the task's demand the law could not realise
            (:func:`clik.loop.laws.prioritized`); laws (9) and (8): 0.
        """
        m = ext.m
        if parts is not None:
            b = ext.demand(r, ext.demand_out[:r])
            return prioritized_levels(
                ext.J[:m], b[:m], self.ends, ext.J[m:r], b[m:r], out, self.damping, self.dt,
                parts, z, budget_blocks=self.speed is None,
            )  # fmt: skip
        if self.law == "pseudoinverse":
            b = ext.demand(r, ext.demand_out[:r])
            return prioritized(
                ext.J[:m], b[:m], ext.J[m:r], b[m:r], out, self.damping, self.dt, out_c,
                budget_blocks=self.speed is None,
            )  # fmt: skip
        J, e, K, ff, work = ext.J[:r], ext.e[:r], ext.K[:r], ext.ff[:r], ext.work[:r]
        if self.law == "transpose":
            transpose(J, e, K, ff, out, work)
        else:
            nonlinear(J, e, K, ff, out, work, ext.jte, self.beta_max)
        return 0.0

    # -- the loop ----------------------------------------------------------------------

    def run(
        self,
        trajectory: Trajectory | None = None,
        q0: np.ndarray | Sequence[float] | None = None,
        *,
        record_every: int = 1,
        progress: ProgressCallback | None = None,
        deadlock_window: float = 0.1,
        deadlock_ratio: float = 1e-4,
        deadlock_error: float = 1e-3,
        max_joint_step: float = 1.0,
        settle: float = 0.0,
        stall_window: float = 0.5,
        stall_progress: float = 0.01,
        tolerance: tuple[float, float] = DEFAULT_TOLERANCE,
        settling_time: float = DEFAULT_SETTLING_TIME,
    ) -> TrackingResult:
        """Track ``trajectory`` from ``q0`` (default: the robot's reference configuration).

        Every argument is checked here, before the run, in both engines (a finite number
        in its range; an :class:`~clik.errors.InputError` names the argument otherwise).

        Args:
            trajectory: Desired task trajectory; sampled chunk by chunk on the time grid.
                None with ``tasks=[...]``: each goal has its own (the run lasts as long
                as the longest).
            q0: Initial configuration (nq,).
            record_every: Keep every k-th sample (and the last) in the result's arrays, an
                integer >= 1; scalars such as ``max_task_error`` still see every sample.
                One at least the run's sample count keeps the first and last samples only
                (it is taken as that count).
            progress: Called as ``progress(k, N)`` about a hundred times during the run,
                or None. It may change the constraint set (``set_obstacles``,
                ``move_obstacle``): the change applies to the next run.
            deadlock_window: Time [s] the deadlock condition must hold before stopping,
                > 0 and at most ``clik.bounds.MAX_STEPS * dt``.
            deadlock_ratio: Laws (9), (8): deadlock when
                ``|J_e^T K e_e| <= ratio |J_e|_F |K e_e|``, in [0, 1]...
            deadlock_error: ... while the task error norm exceeds this [m or rad], >= 0
                (law (10): while most of the task's demand is not realised).
            max_joint_step: A joint step ``|qdot| dt`` above this [rad or m], > 0, stops
                the run with status ``diverged``; checked every sample.
            settle: Extra time [s] after the trajectory's end, holding its final value,
                >= 0.
            stall_window: With the reference at rest, a task error that falls by less
                than ``stall_progress`` over this time [s] is a deadlock too; in the range
                of ``deadlock_window``.
            stall_progress: See ``stall_window``: a fraction in [0, 1].
            tolerance: Task error tolerance (position [m], orientation [rad]), each > 0:
                a run that reached its end with its error above it for longer than
                ``settling_time``, or at its last sample, is ``off_track``
                (:mod:`clik.loop.tracking_status`).
            settling_time: Longest time [s] the error may stay above ``tolerance``, > 0.

        Raises:
            InputError: A bad argument; or the robot's model changed after loading
                (``robot.model``).
            InfeasibleError: ``q0`` outside the robot's joint limits.

        Warns:
            ReachWarning: A position of the reference lies beyond the frame's reach.
            StabilityWarning: The gains break explicit Euler's bound at ``q0``.
        """
        (robot := self.robot).check_model()
        q = robot.check_configuration(robot.q_reference if q0 is None else q0, "q0")
        robot.check_within_limits(q, "q0")
        trajectory, duration = self._checked_trajectory(trajectory, record_every, progress, settle)
        self.check_size(duration + settle, int(record_every))
        settings = checked_settings(
            self.dt, deadlock_window=deadlock_window, deadlock_ratio=deadlock_ratio,
            deadlock_error=deadlock_error, max_joint_step=max_joint_step,
            stall_window=stall_window, stall_progress=stall_progress,
        )  # fmt: skip
        tol = checked_tolerance(tolerance, settling_time)
        t = time_grid(duration + settle, self.dt)
        chunks, out_of_reach = self._reference(trajectory, t)
        self._warn_stability(q)
        every = min(int(record_every), t.shape[0])  # beyond N: the first and last samples
        run = _Run(self, t, chunks, every, settings, progress, tol, q)
        return run.execute(q, out_of_reach)

    def _checked_trajectory(
        self, trajectory: Trajectory | None, record_every: int, progress: object, settle: float
    ) -> tuple[Trajectory, float]:
        """The primary task's trajectory, checked, and the run's duration [s] (the longest)."""
        trajectory = self._primary_trajectory(trajectory)
        duration = self._check_run(trajectory, record_every, progress, settle)
        if self.stack is not None:
            duration = max(duration, self.stack.duration())
        return trajectory, duration

    def _primary_trajectory(self, trajectory: Trajectory | None) -> Trajectory:
        """The primary task's trajectory: the one given, or its goal's with ``tasks``."""
        if self.stack is None:
            if trajectory is None:
                raise InputError("trajectory", "the task's trajectory (a clik.trajectory)")
            return trajectory
        if trajectory is not None:
            raise InputError("trajectory", "None with tasks=[...] (each goal has its own)")
        for goal, name in zip(self.stack.goals, self.stack.names, strict=True):
            if goal.trajectory is None:
                expected = "a trajectory (None only in a clik.Controller, given it tick by tick)"
                raise InputError(f"tasks[{name!r}].trajectory", expected, None)
            duration = real(getattr(goal.trajectory, "duration", None))
            if not in_range(duration, 0.0):
                expected = "a trajectory whose duration is a finite time >= 0 [s]"
                raise InputError(f"tasks[{name!r}].trajectory.duration", expected, duration)
        return self.stack.primary.trajectory

    def _check_run(
        self, trajectory: Trajectory, record_every: int, progress: object, settle: float
    ) -> float:
        """Refuse a bad trajectory, ``record_every``, ``progress`` or ``settle``.

        Returns:
            The trajectory's duration [s].
        """
        if not callable(getattr(trajectory, "sample", None)):
            expected = "a clik.trajectory.Trajectory (a duration and sample(t))"
            raise InputError("trajectory", expected, type(trajectory).__name__)
        if isinstance(record_every, bool) or not isinstance(record_every, int | np.integer):
            raise InputError("record_every", "an integer >= 1", record_every)
        if record_every < 1:
            raise InputError("record_every", "an integer >= 1", record_every)
        if progress is not None and not callable(progress):
            raise InputError("progress", "a callable progress(k, N) or None", progress)
        duration = real(getattr(trajectory, "duration", None))
        if not in_range(duration, 0.0):
            expected = "a trajectory whose duration is a finite time >= 0 [s]"
            raise InputError("trajectory.duration", expected, getattr(trajectory, "duration", None))
        if not in_range(settle, 0.0, MAX_STEPS * self.dt):
            raise InputError("settle", f"a time >= 0 and <= {MAX_STEPS * self.dt:g} [s]", settle)
        return duration

    def check_size(self, duration: float, record_every: int) -> None:
        """Refuse a run too long or whose record would not fit in memory.

        At most :data:`~clik.bounds.MAX_STEPS` samples, and a record within
        :data:`~clik.bounds.MAX_RECORD_BYTES`.

        Args:
            duration: The run's time span, trajectory and settling [s].
            record_every: The decimation asked for.

        Raises:
            InputError: ``dt`` too small for ``duration``; or ``record_every`` too small
                for this run, the message giving the smallest that fits.
        """
        steps_needed = duration / self.dt + 1
        if steps_needed > MAX_STEPS:
            raise InputError(
                "dt",
                f"a step giving at most {MAX_STEPS:.0e} steps over the trajectory's "
                f"{duration:g} s (this one gives {steps_needed:.3g})",
                self.dt,
            )
        N = round(duration / self.dt) + 1
        cset = self.constraints
        n_obs = 0 if cset is None else len(cset.obstacles)
        slots = 0 if cset is None else max(cset.row_limit(self.m, self.law), 1)
        size = bytes_per_sample(self.robot.nq, self.robot.nv, n_obs, slots)
        if kept_samples(N, record_every) * size <= MAX_RECORD_BYTES:
            return
        fits = MAX_RECORD_BYTES // size  # kept_samples(N, every) = ceil((N - 1) / every) + 1
        least = -(-(N - 1) // (fits - 1))
        mb = kept_samples(N, record_every) * size / 2**20
        raise InputError(
            "record_every",
            f"an integer >= {least} for this run: keeping "
            + ("all" if record_every == 1 else f"every {record_every}-th")
            + f" of its {N} samples ({size} bytes each) takes {mb:.0f} MB, above the budget of "
            f"{MAX_RECORD_BYTES // 2**20} MB (clik.bounds.MAX_RECORD_BYTES)",
            record_every,
        )

    def _reference(self, trajectory: Trajectory, t: np.ndarray) -> tuple[ReferenceChunks, str]:
        """The reference in chunks, and why it is out of reach ("" when it is not).

        A position beyond the frame's reach is named here, before the run, by a warning.
        """
        task = self.task
        center, reach, first = (None, math.inf, "")
        if task.has_position:
            center, reach, first = reach_bound(self.robot, task.frame_id)
        finite = math.isfinite(reach)
        chunks = ReferenceChunks(task, trajectory, t, REFERENCE_CHUNK, center if finite else None)
        farthest, when = chunks.farthest
        if not (finite and farthest > reach + 1e-9):
            return chunks, ""
        out_of_reach = (
            f"the reference is out of reach: at t = {when:.6g} s it lies {farthest:.4g} m "
            f"from joint {first!r}, farther than the {reach:.4g} m that frame "
            f"{task.frame!r} can reach (the sum of the chain's link offsets)"
        )
        warnings.warn(out_of_reach, ReachWarning, stacklevel=4)
        return chunks, out_of_reach

    def _warn_stability(self, q: np.ndarray) -> None:
        """Warn when the gains break explicit Euler's bound at ``q0``, or ``q0`` is a poor start."""
        warn_start(self.task, q, self.constraints)  # clik.loop.start_checks
        if self.law == "pseudoinverse":
            gains = [self.alpha]
            if self.constraints is not None:
                gains += [k.gain for k in self.constraints.kinds if k.gain is not None]
            kdt = max(gains) * self.dt
            if kdt >= 2.0:
                warnings.warn(
                    f"gain: K dt = {kdt:.3g} >= 2: law (10) is unstable (its error map is "
                    "e_{k+1} = (1 - K dt) e_k); lower the gain or dt",
                    StabilityWarning,
                    stacklevel=3,
                )
            return
        margin = stability_margin(self.task.jacobian(q), self.K_task[: self.task.m], self.dt)
        if margin >= 2.0:
            warnings.warn(
                f"gain: alpha dt lambda_max(J J^T) = {margin:.3g} >= 2 at q0: explicit Euler "
                "is unstable along the stiffest task direction; lower the gain or dt",
                StabilityWarning,
                stacklevel=3,
            )


def _check_engine_goals() -> None:
    """Refuse several tasks or objectives with a compiled engine built without them."""
    from clik.engine import load

    if not hasattr(load(), "FrameGoal"):
        raise InputError(
            "engine", "'python' for several tasks or objectives: this build of the compiled "
            "engine has none (rebuild it: make demo)", "compiled",
        )  # fmt: skip


def track(
    task: Task | None = None,
    trajectory: Trajectory | None = None,
    *,
    tasks: Sequence[Goal] | None = None,
    objectives: Sequence[Objective] | None = None,
    q0: np.ndarray | Sequence[float] | None = None,
    law: LawName = "transpose",
    gain: float | Sequence[float] = 1000.0,
    dt: float = 1e-3,
    damping: float = 0.0,
    constraints: ConstraintSet | None = None,
    record_every: int = 1,
    progress: ProgressCallback | None = None,
    engine: str = "compiled",
    joint_speed: JointSpeed | None = JOINT_SPEED,
    settle: float = 0.0,
    tolerance: tuple[float, float] = DEFAULT_TOLERANCE,
    settling_time: float = DEFAULT_SETTLING_TIME,
) -> TrackingResult:
    """Track a Cartesian trajectory with a CLIK law (the one-call form of :class:`Tracker`).

    The arguments are :class:`Tracker`'s and :meth:`Tracker.run`'s, checked the same
    way before the run (an :class:`~clik.errors.InputError` names a bad one).

    Example:
        >>> robot = clik.Robot.load("planar4r")
        >>> task = clik.Task(robot, "tip", "position", axes=["x", "y"])
        >>> q0 = np.radians([180, -30, -90, -30])
        >>> result = clik.track(task, clik.trajectory.Line(...), q0=q0)

    Several tasks (docs/method.md, "Several tasks"): ``tasks=[clik.Goal(task,
    trajectory, name=..., priority=..., gain=...), ...]`` instead of ``task`` and
    ``trajectory``, and eq. (5)'s ``objectives=[clik.Objective(...)]`` (law (10)).
    """
    tracker = Tracker(
        task, law=law, gain=gain, dt=dt, damping=damping, constraints=constraints, engine=engine,
        joint_speed=joint_speed, tasks=tasks, objectives=objectives,
    )  # fmt: skip
    return tracker.run(
        trajectory, q0, record_every=record_every, progress=progress, settle=settle,
        tolerance=tolerance, settling_time=settling_time,
    )  # fmt: skip
