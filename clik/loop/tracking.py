"""Tracking: integrate the closed-loop law along a reference trajectory.

One iteration per sample (docs/method.md, "Discrete time"), each a short step:

1. kinematics: the frame's placement and Jacobian at ``q_k`` (3);
2. task error ``e_k = x_d(t_k) - x(q_k)`` (6) on the task's rows;
3. constraint rows (13)-(19) into the extended task (24)-(25);
4. the law, (9), (8) or (10), gives ``qdot_k``, within the joint speed limits
   (S1)-(S3) (:mod:`clik.loop.speed_step`);
5. stop checks (divergence, instability, deadlock) and limits crossed (violations);
6. recording, then ``q_{k+1} = q_k (+) qdot_k dt`` (``pin.integrate``).

This module is one run, :meth:`_Run.samples` the specification of the compiled
engine's loop (:mod:`clik.loop.compiled_run`); the run is started, its settings
and inputs checked, by :class:`~clik.loop.tracker.Tracker`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import pinocchio as pin

from clik.constraints.constraint_run import ConstraintRun
from clik.constraints.recovery import recovery_clause, recovery_records
from clik.constraints.registry import limit_words
from clik.constraints.violations import JointRange, ViolationMonitor
from clik.loop.compiled_run import compiled_samples
from clik.loop.goal_rows import task_errors
from clik.loop.goal_state import GoalState
from clik.loop.laws import finite
from clik.loop.recording import Recorder
from clik.loop.speed_step import SpeedStep
from clik.loop.stop_checks import StopChecks, StopSettings
from clik.loop.tracking_status import Tolerance, judge
from clik.outputs.result import TrackingResult
from clik.tasks.extended_task import ExtendedTask

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet
    from clik.loop.joint_speed import JointSpeedBounds
    from clik.loop.laws import LawName
    from clik.loop.reference_stream import ReferenceChunks
    from clik.loop.task_stack import TaskStack
    from clik.model.robot import Robot
    from clik.objectives.objective import Objective
    from clik.tasks.task import Task
    from clik.trajectory.clock import Clock

ProgressCallback = Callable[[int, int], None]


class TrackerSettings(Protocol):
    """What a run reads of the :class:`~clik.loop.tracker.Tracker` that starts it."""

    task: Task
    robot: Robot
    law: LawName
    m: int
    ends: list[int]
    stack: TaskStack | None
    objectives: list[Objective]

    @property
    def leveled(self) -> bool: ...  # noqa: D102

    @property
    def engine(self) -> str: ...  # noqa: D102

    dt: float
    K_task: np.ndarray
    alpha: float
    damping: float
    beta_max: float
    rows: int
    constraints: ConstraintSet | None
    speed: JointSpeedBounds | None

    def law_velocity(  # noqa: D102
        self, ext: ExtendedTask, r: int, out: np.ndarray, out_c: np.ndarray | None = None,
        parts: np.ndarray | None = None, z: Sequence[tuple[int, np.ndarray]] = (),
    ) -> float: ...  # fmt: skip


class _Run:
    """One run of a ``Tracker``: its arrays, constraint state, checks and record.

    Everything a run writes is its own: its Pinocchio data (:attr:`data`), its extended
    task and the law's scratch arrays, its constraint state on a snapshot of the
    tracker's constraint set (:attr:`cset`: a set changed during the run, e.g. by
    ``set_obstacles`` from ``progress``, applies to the next run), its record. Robots,
    tasks, trackers and constraint sets are only read, so runs may share them across
    threads.
    """

    def __init__(
        self,
        tracker: TrackerSettings,
        t: np.ndarray | Clock,
        chunks: ReferenceChunks | None,
        record_every: int,
        settings: StopSettings,
        progress: ProgressCallback | None,
        tolerance: Tolerance | None = None,
        q0: np.ndarray | None = None,
        ring: int | None = None,
        events: int = 0,
    ) -> None:
        self.tr = tracker
        self.event_size = events  # the constraint events kept (0: every one)
        self.tolerance = Tolerance() if tolerance is None else tolerance
        self.task = task = tracker.task
        self.robot = robot = tracker.robot
        self.t, self.chunks, self.progress = t, chunks, progress
        self.dt = tracker.dt
        self.N = t.shape[0]
        self.m = m = tracker.m  # every task's rows; the primary's are the first task.m
        nv = robot.nv
        self.ext = ExtendedTask(m, tracker.rows, nv, tracker.K_task)
        python = tracker.engine == "python"
        self.data: pin.Data  # the run's own (the Python engine's: the compiled one's is in C++)
        if python:
            self.data = robot.model.createData()
        self.cset = cset = None if tracker.constraints is None else tracker.constraints.snapshot()
        self.rec = Recorder(
            self.N, record_every, robot.nq, nv, task.has_position,
            task.has_orientation and task.has_position, cset is not None, ring,
        )  # fmt: skip
        self.crun: ConstraintRun | None = None
        if cset is not None and python:  # the compiled engine's is in C++
            self.crun = ConstraintRun(
                cset, m, tracker.law, tracker.alpha, t, self.rec.capacity, task.frame_id,
                task.rows, self.data, events,
            )  # fmt: skip
        self.goals = GoalState(
            tracker, t, None if chunks is None else chunks.size, self.rec.capacity, q0
        )
        self.q = np.zeros(robot.nq)  # this sample's configuration (the objectives read it)
        self.speed_step: SpeedStep | None = None  # the compiled engine's is in C++
        if tracker.speed is not None and python:
            self.speed_step = SpeedStep(tracker.speed, self.dt)
        joints = JointRange(robot, None if cset is None else cset.joint_ranges())  # the robot's,
        self.monitor = ViolationMonitor(joints, limit_words)  # tightened by a joint-range kind
        self.checks = StopChecks(settings, tracker.law, self.dt)
        self.e6 = np.zeros(6)
        self.steps, self.max_err, self.err, self.err_rot, self.r = 0, 0.0, 0.0, 0.0, 0
        self.qdot, self.dq = np.zeros(nv), np.zeros(nv)  # qdot_k (the law's), qdot_k dt
        self.pos_rows, self.rot_rows = task.rows[task.rows < 3], task.rows[task.rows >= 3]

    def law(self, r: int, out: np.ndarray) -> float:
        """The tracker's law on the first ``r`` rows of this run's extended task."""
        step, goals = self.speed_step, self.goals
        if goals.parts is not None:
            z = goals.objective_gradients(self.robot.model, self.data, self.ext, self.q)
            return self.tr.law_velocity(self.ext, r, out, None, goals.parts, z)
        return self.tr.law_velocity(self.ext, r, out, None if step is None else step.c)

    def within_speed_limits(self, r: int, qdot: np.ndarray) -> None:
        """The law's ``qdot`` within the joint speed limits, (S1)-(S3), when the run has them."""
        if self.speed_step is not None:
            parts = self.goals.parts
            if parts is not None:
                self.speed_step.apply_parts(qdot, parts)
            else:
                self.speed_step.apply(qdot, self.ext, r, self.tr.law == "pseudoinverse")

    # -- one sample, in steps ----------------------------------------------------------

    def kinematics(self, q: np.ndarray) -> np.ndarray:
        """Frame placement and Jacobian (6, nv) at ``q``, eq. (3), ``LOCAL_WORLD_ALIGNED``.

        With constraints every joint's Jacobian is computed: their rows need them.
        """
        model, data, fid = self.robot.model, self.data, self.task.frame_id
        if self.crun is None and self.goals.rows is None and not self.goals.objectives:
            return pin.computeFrameJacobian(model, data, q, fid, LWA)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacement(model, data, fid)
        return pin.getFrameJacobian(model, data, fid, LWA)

    def task_rows(self, J6: np.ndarray, p_d: np.ndarray | None, R_d: np.ndarray | None,
                  xdot_d: np.ndarray) -> None:  # fmt: skip
        """Task error (6) ``e = (p_d - p, log3(R_d R^T))`` and rows of ``J`` into the task rows."""
        placement = self.data.oMf[self.task.frame_id]
        e6, rows, m = self.e6, self.task.rows, self.task.m
        if p_d is not None and self.task.has_position:
            np.subtract(p_d, placement.translation, out=e6[:3])
        if R_d is not None and self.task.has_orientation:
            e6[3:] = pin.log3(R_d.dot(placement.rotation.T))
        ext = self.ext
        np.take(e6, rows, out=ext.e[:m])
        np.take(J6, rows, axis=0, out=ext.J[:m])
        ext.ff[:m] = xdot_d

    def error_norms(self) -> tuple[float, float]:
        """Norms of the task's own position rows [m] and orientation rows [rad].

        The first is the run's task error (for a pure orientation task, the orientation
        rows'); only the rows the task keeps count (a mask ``["x"]`` is the x error).
        """
        e6 = self.e6
        rot = math.sqrt(float(np.sum(e6[self.rot_rows] ** 2))) if self.rot_rows.size else 0.0
        if not self.pos_rows.size:
            return rot, rot
        return math.sqrt(float(np.sum(e6[self.pos_rows] ** 2))), rot

    def stop(self, k: int, qdot: np.ndarray, err: float, r: int, blocked: float,
             at_rest: bool) -> tuple[str, str] | None:  # fmt: skip
        """The status and reason when the run must stop at sample ``k``, else None."""
        tk = float(self.t[k])
        checks = self.checks
        why = checks.divergence(tk, qdot, err)
        if why is None:
            why = checks.instability(k, self.ext, r, err)
        if why is not None:
            return "diverged", why + self.active_clause(r)
        if checks.deadlock(self.ext, r, err, blocked):
            return "deadlock", self.deadlock_reason(tk, err, r, qdot)
        if checks.stall(k, err, at_rest):
            return "deadlock", self.stall_reason(tk, err, r, qdot)
        return None

    def stall_reason(self, tk: float, err: float, r: int, qdot: np.ndarray) -> str:
        """A deadlock found by the stall check (the reference at rest)."""
        s = self.checks.s
        return self.deadlock_reason(tk, err, r, qdot) + (
            f"; the error fell by less than {s.stall_progress:.0%} in "
            f"{s.stall_window:g} s with the reference at rest"
        )

    def observe_limits(self, tk: float, q: np.ndarray) -> None:
        """Record every limit crossed at this sample: joints, and what each kind guards."""
        self.monitor.observe_joints(tk, q)
        crun = self.crun
        if crun is None:
            return
        crun.observe_limits(tk, self.monitor)

    def record(self, k: int, q: np.ndarray, qdot: np.ndarray, p_d: np.ndarray | None,
               err: float, err_rot: float, r: int) -> None:  # fmt: skip
        """Keep sample ``k``."""
        placement = self.data.oMf[self.task.frame_id]
        j = self.rec.keep(k, q, qdot, placement.translation, p_d, err, err_rot)
        if self.goals.rows is not None:
            self.goals.rows.keep(j)
        if self.crun is not None:
            if self.rec.ring:  # a ring's slot held an older sample
                self.crun.clear(j)
            assert self.rec.active is not None and self.rec.distance is not None
            self.rec.active[j] = r - self.m
            self.rec.distance[j] = self.crun.min_distance
            self.crun.record(j)

    # -- the loop ----------------------------------------------------------------------

    def execute(self, q: np.ndarray, out_of_reach: str = "") -> TrackingResult:
        """Run every sample from ``q``; returns the result.

        Args:
            q: Start configuration.
            out_of_reach: Why the reference is out of reach, added to a failed run's reason.
        """
        start = time.perf_counter()
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            if self.tr.engine == "compiled":
                status, reason = compiled_samples(self, q)
            else:
                status, reason = self.samples(q)
        wall = time.perf_counter() - start
        if self.progress is not None:
            self.progress(self.N if status == "completed" else self.steps, self.N)
        return self.finished(status, reason, wall, out_of_reach)

    def finished(
        self, status: str, reason: str, wall: float, out_of_reach: str = ""
    ) -> TrackingResult:
        """The result of the samples run so far, judged (violations, tolerance, speeds).

        Args:
            status: How the samples ended: ``"completed"`` or a check's status.
            reason: Its reason.
            wall: Wall time of the samples [s].
            out_of_reach: Why the reference is out of reach, added to a failed run's reason.
        """
        if status != "completed" and out_of_reach:
            reason += f"; {out_of_reach}"
        status, reason = self._final_status(status, reason)
        result = self._result(status, reason, wall, self.steps, self.max_err, self.err)
        records = [] if self.cset is None else recovery_records(result, self.cset, self.task)
        judge(result, self.tolerance, records, recovery_clause(records))
        if result.status != status and out_of_reach:  # off_track, velocity_limit
            result.reason += f"; {out_of_reach}"
        return result

    def samples(self, q: np.ndarray) -> tuple[str, str]:
        """The loop: :meth:`sample` at every sample of the grid (the engine's specification).

        Sets :attr:`steps`, :attr:`max_err` and :attr:`err`; returns the status and reason.
        """
        N, goals, t = self.N, self.goals, self.t
        assert self.chunks is not None  # an offline run (a controller's has none)
        c0, c1, P_d, R_d, FF, at_rest = self.chunks.load(0)
        G_ref, G_ff, at_rest = goals.load(0, at_rest)
        progress_every = max(1, N // 100)
        self.rec.start(q)
        for k in range(N):
            if k == c1:
                c0, c1, P_d, R_d, FF, at_rest = self.chunks.load(k)
                G_ref, G_ff, at_rest = goals.load(k, at_rest)
            kk = k - c0
            stop = self.sample(
                k, q, None if P_d is None else P_d[kk], None if R_d is None else R_d[kk],
                FF[kk], bool(at_rest[kk]), None if G_ref is None else G_ref[kk],
                None if G_ff is None else G_ff[kk],
            )  # fmt: skip
            if stop is not None:
                return stop
            if self.progress is not None and k % progress_every == 0:
                self.progress(k, N)
            if k + 1 < N:
                q = self.integrate(q)
        return "completed", f"reached the end of the trajectory at t = {t[-1]:.6g} s"

    def sample(
        self, k: int, q: np.ndarray, p_d: np.ndarray | None, R_d: np.ndarray | None,
        ff: np.ndarray, at_rest: bool, g_ref: np.ndarray | None = None,
        g_ff: np.ndarray | None = None,
    ) -> tuple[str, str] | None:  # fmt: skip
        """One sample (one tick of a controller): steps 1-5 and the record, at ``q``.

        Args:
            k: The sample's index (its time is ``t[k]``).
            q: ``q_k``.
            p_d: The primary task's reference position (3,) at ``t_k`` [m], or None.
            R_d: Its reference rotation (3, 3), or None.
            ff: Its rows' feed-forward (m0,).
            at_rest: Whether every feed-forward of this sample is zero (the stall check).
            g_ref: The other goals' references (D,), or None.
            g_ff: Their feed-forward (M,), or None.

        Returns:
            The status and reason of a check that fired, else None. :attr:`qdot` holds
            ``qdot_k``; :meth:`integrate` gives ``q_{k+1}``.
        """
        goals, crun, rec, qdot = self.goals, self.crun, self.rec, self.qdot
        J6 = self.kinematics(q)
        self.task_rows(J6, p_d, R_d, ff)
        if goals.rows is not None and g_ref is not None and g_ff is not None:
            goals.rows.fill(self.robot.model, self.data, q, g_ref, g_ff, self.ext)
        self.q = q
        exact = rec.due(k)
        r = self.m if crun is None else self.m + crun.update(k, q, self.ext, self.law, exact)
        blocked = self.law(r, qdot)
        self.within_speed_limits(r, qdot)
        self.err, self.err_rot = self.error_norms()
        self.max_err = max(self.max_err, self.err)
        worst = self.err if goals.rows is None else max(self.err, goals.rows.errors(self.ext))
        stop = self.stop(k, qdot, worst, r, blocked, at_rest)
        self.observe_limits(float(self.t[k]), q)
        if exact or stop is not None:
            self.record(k, q, qdot, p_d, self.err, self.err_rot, r)
        rec.every_sample(q, qdot)
        self.steps = k + 1
        self.r = r
        return stop

    def integrate(self, q: np.ndarray) -> np.ndarray:
        """``q_{k+1} = q_k (+) qdot_k dt`` (``pin.integrate``)."""
        return pin.integrate(self.robot.model, q, np.multiply(self.qdot, self.dt, out=self.dq))

    def _final_status(self, status: str, reason: str) -> tuple[str, str]:
        """``completed`` becomes ``violated`` when a limit was crossed; skipped rows named."""
        crun = self.crun
        if crun is not None and status == "completed":
            skipped = crun.skipped_names()
            if skipped:
                reason += (
                    f"; {len(skipped)} violated constraint(s) found no free row (more than "
                    f"the {crun.limit} allowed at once) and were skipped: {', '.join(skipped)}"
                )
        worst = self.monitor.worst()
        if worst is None:
            return status, reason
        n = len(self.monitor.records)
        crossed = f"{n} constraint limit(s) crossed, the worst: {worst.describe()}"
        stuck = sorted(set(self.monitor.records) & crun.cset.immovable_pairs) if crun else []
        if stuck:
            crossed += (
                f"; {', '.join(stuck)}: on a link no joint moves (the robot's fixed base), "
                "so no motion can clear it"
            )
        if status == "completed":
            return "violated", f"{crossed} (the trajectory was run to its end)"
        return status, f"{reason}; {crossed}"

    def _result(
        self, status: str, reason: str, wall: float, steps: int, max_err: float, err: float
    ) -> TrackingResult:
        tr, task = self.tr, self.task
        arrays = self.rec.trimmed(self.dt)
        info = {
            "robot": self.robot.name,
            "frame": task.frame,
            "task": task.kind,
            "axes": task.axes,
            "law": tr.law,
            "engine": tr.engine,
            "gain": [float(g) for g in tr.K_task],
            "dt": self.dt,
            "record_every": self.rec.every,
            "duration": self._duration(),
            "stability_margin_max": float(self.checks.worst_margin),
            "joint_speed": None if tr.speed is None else tr.speed.as_info(),
        }
        result = TrackingResult(
            t=self.t[self.rec.idx[self.rec.order()]],
            status=status,
            reason=reason,
            wall_time_s=wall,
            steps=steps,
            max_task_error=max_err,
            final_task_error=err,
            info=info,
            robot=self.robot,
            violations=self.monitor.as_list(),
            **arrays,  # type: ignore[arg-type]
        )
        if self.crun is not None:
            rec = self.rec
            self.crun.finish(result, rec.j, (rec.j, rec.capacity) if rec.ring else None)
        self._task_errors(result, max_err, err)
        return result

    def _duration(self) -> float:
        """The reference's duration [s]; an open run's: the time of its samples so far."""
        if self.chunks is None:
            return float(max(self.steps - 1, 0) * self.dt)
        stack = self.tr.stack
        return float(self.chunks.trajectory.duration if stack is None else stack.duration())

    def _task_errors(self, result: TrackingResult, max_err: float, err: float) -> None:
        """Each task's errors by name (``result.task_errors``) and the others' record."""
        primary: dict[str, Any] = {"max": float(max_err), "final": float(err)}
        o = result.orientation_error_norm
        if o is not None and o.size and self.task.has_position:
            primary["max_orientation"] = float(np.max(o))
            primary["final_orientation"] = float(o[-1])
        rows = self.goals.rows
        result.task_errors = task_errors(self.tr.stack, self.task, primary, rows)
        if rows is not None:
            result.extra["task_errors"] = rows.record[self.rec.order()].copy()
            result.info["tasks"] = list(result.task_errors)

    # -- reasons -----------------------------------------------------------------------

    def active_clause(self, r: int) -> str:
        if self.crun is None or r == self.m:
            return ""
        return f"; active constraints: {', '.join(self.crun.active_names())}"

    def deadlock_reason(self, tk: float, err: float, r: int, qdot: np.ndarray) -> str:
        """Remark 2, with the task rows that cannot follow and the constraints that block them."""
        ext, m = self.ext, self.tr.ends[0]  # the first level's rows (lower ones give way)
        b = ext.demand(m, np.zeros(m)) if self.tr.law == "pseudoinverse" else ext.K[:m] * ext.e[:m]
        residual = b - ext.J[:m].dot(qdot)
        size = float(np.abs(residual).max())
        axes = self.task.axes if self.tr.stack is None else self.tr.stack.row_labels()[:m]
        rows = [axes[i] for i in np.flatnonzero(np.abs(residual) >= 0.3 * size)] if size else axes
        head = (
            f"deadlock at t = {tk:.6g} s: the task error is {err:.4g} and the law cannot reduce "
            f"it (Remark 2); task rows that cannot follow: {', '.join(rows)}"
        )
        if self.crun is None or r == self.m:
            return head + "; no constraint is active: the task is singular or out of reach"
        wanted = (  # the joint motion the task asks for (an SVD only of finite numbers)
            np.linalg.pinv(ext.J[:m]).dot(residual)
            if finite(ext.J[:m], residual)
            else np.zeros(ext.J.shape[1])
        )
        blocking = []
        for s, c in enumerate(self.crun.active_rows()):
            row = ext.J[self.m + s]
            scale = float(np.linalg.norm(row) * np.linalg.norm(wanted))
            if scale > 0.0 and float(row.dot(wanted)) < -0.05 * scale:
                blocking.append(c.key)
        names = blocking or self.crun.active_names()
        return head + (
            f"; in conflict with: {', '.join(names)}; active constraints: "
            f"{', '.join(self.crun.active_names())}"
        )


LWA = pin.LOCAL_WORLD_ALIGNED
