"""Tracking: integrate the closed-loop law along a reference trajectory.

One iteration per sample (docs/method.md, "Discrete time"), each a short step:

1. kinematics: the frame's placement and Jacobian at ``q_k`` (3);
2. task error ``e_k = x_d(t_k) - x(q_k)`` (6) on the task's rows;
3. constraint rows (13)-(19) into the extended task (24)-(25);
4. the law, (9), (8) or (10), gives ``qdot_k``;
5. stop checks (divergence, instability, deadlock) and limits crossed (violations);
6. recording, then ``q_{k+1} = q_k (+) qdot_k dt`` (``pin.integrate``).
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from clik.bounds import MAX_RECORD_BYTES, MAX_STEPS
from clik.constraints.constraint_run import ConstraintRun
from clik.constraints.violations import JointRange, ViolationMonitor
from clik.engine import ENGINES
from clik.errors import InputError
from clik.loop.compiled_run import compiled_samples
from clik.loop.gains import row_gains, stability_margin
from clik.loop.laws import LawName, check_law, finite, nonlinear, prioritized, transpose
from clik.loop.recording import Recorder, bytes_per_sample, kept_samples
from clik.loop.reference_stream import REFERENCE_CHUNK, ReferenceChunks
from clik.loop.stop_checks import StopChecks, StopSettings
from clik.model.reach import reach_bound
from clik.outputs.result import TrackingResult
from clik.tasks.extended_task import ExtendedTask
from clik.tasks.task import Task
from clik.trajectory import Trajectory, time_grid

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet
    from clik.model.robot import Robot

ProgressCallback = Callable[[int, int], None]


class ReachWarning(UserWarning):
    """The position reference leaves the frame's reach: the run will end in a deadlock."""


class StabilityWarning(UserWarning):
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
    one). Each run owns its extended task, its record and its constraint state
    (:class:`~clik.constraints.ConstraintRun`), so trackers and runs never share mutable state.

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
            ``"python"`` (this module's loop, the engine's readable specification).
            Both give the same statuses, events and joint trajectories.
    """

    def __init__(
        self,
        task: Task,
        law: LawName = "transpose",
        gain: float | Sequence[float] = 1000.0,
        dt: float = 1e-3,
        damping: float = 0.0,
        beta_max: float | None = None,
        constraints: ConstraintSet | None = None,
        engine: str = "compiled",
    ) -> None:
        if engine not in ENGINES:
            raise InputError("engine", " or ".join(repr(e) for e in ENGINES), engine)
        self.engine = engine
        self.task = task
        self.robot = task.robot
        self.law = check_law(law)
        self.dt = _positive(dt, "dt", "[s]")
        self.K_task = row_gains(gain, task.m, "gain")
        damping = float(damping)
        if not math.isfinite(damping) or damping < 0.0:
            raise InputError("damping", "a finite number >= 0", damping)
        self.damping = damping
        self.alpha = float(np.max(self.K_task))
        self.beta_max = (
            2.0 * self.alpha if beta_max is None else _positive(beta_max, "beta_max", "[1/s]")
        )
        self.constraints = constraints
        m, nv = task.m, self.robot.nv
        limit = constraints.row_limit(m, self.law) if constraints is not None else 0
        self.rows = m + limit
        self._b = np.zeros(self.rows)
        self._work = np.zeros(self.rows)
        self._jte = np.zeros(nv)

    # -- the law -----------------------------------------------------------------------

    def law_velocity(self, ext: ExtendedTask, r: int, out: np.ndarray) -> float:
        """Joint velocity [rad/s] of the law on the first ``r`` rows of the extended task.

        Returns:
            Law (10): the fraction of the task's demand the law could not realise
            (:func:`clik.loop.laws.prioritized`); laws (9) and (8): 0.
        """
        m = ext.m
        if self.law == "pseudoinverse":
            b = ext.demand(r, self._b[:r])
            return prioritized(ext.J[:m], b[:m], ext.J[m:r], b[m:r], out, self.damping, self.dt)
        J, e, K, ff, work = ext.J[:r], ext.e[:r], ext.K[:r], ext.ff[:r], self._work[:r]
        if self.law == "transpose":
            transpose(J, e, K, ff, out, work)
        else:
            nonlinear(J, e, K, ff, out, work, self._jte, self.beta_max)
        return 0.0

    # -- the loop ----------------------------------------------------------------------

    def run(
        self,
        trajectory: Trajectory,
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
    ) -> TrackingResult:
        """Track ``trajectory`` from ``q0`` (default: the robot's reference configuration).

        Args:
            trajectory: Desired task trajectory; sampled chunk by chunk on the time grid.
            q0: Initial configuration (nq,).
            record_every: Keep every k-th sample (and the last) in the result's arrays;
                scalars such as ``max_task_error`` still see every sample.
            progress: Called as ``progress(k, N)`` about a hundred times during the run.
            deadlock_window: Time [s] the deadlock condition must hold before stopping.
            deadlock_ratio: Laws (9), (8): deadlock when
                ``|J_e^T K e_e| <= ratio |J_e|_F |K e_e|``...
            deadlock_error: ... while the task error norm exceeds this [m or rad] (law
                (10): while most of the task's demand is not realised).
            max_joint_step: A joint step ``|qdot| dt`` above this [rad or m] stops the run
                with status ``diverged``; checked every sample.
            settle: Extra time [s] after the trajectory's end, holding its final value.
            stall_window: With the reference at rest, a task error that falls by less
                than ``stall_progress`` (a fraction) over this time [s] is a deadlock too.
            stall_progress: See ``stall_window``.

        Raises:
            InputError: A bad argument.
            InfeasibleError: ``q0`` outside the robot's joint limits.

        Warns:
            ReachWarning: A position of the reference lies beyond the frame's reach.
            StabilityWarning: The gains break explicit Euler's bound at ``q0``.
        """
        robot = self.robot
        q = robot.check_configuration(robot.q_reference if q0 is None else q0, "q0")
        robot.check_within_limits(q, "q0")
        if not isinstance(record_every, int | np.integer) or record_every < 1:
            raise InputError("record_every", "an integer >= 1", record_every)
        if not (math.isfinite(settle) and settle >= 0.0):
            raise InputError("settle", "a time >= 0 [s]", settle)
        self.check_size(trajectory.duration + settle, int(record_every))
        t = time_grid(trajectory.duration + settle, self.dt)
        chunks, out_of_reach = self._reference(trajectory, t)
        self._warn_stability(q)
        settings = StopSettings(
            deadlock_window, deadlock_ratio, deadlock_error, max_joint_step, stall_window,
            stall_progress,
        )  # fmt: skip
        run = _Run(self, t, chunks, int(record_every), settings, progress)
        return run.execute(q, out_of_reach)

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
        slots = 0 if cset is None else max(cset.row_limit(self.task.m, self.law), 1)
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
        """Warn when the gains break explicit Euler's bound at ``q0``."""
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
        margin = stability_margin(self.task.jacobian(q), self.K_task, self.dt)
        if margin >= 2.0:
            warnings.warn(
                f"gain: alpha dt lambda_max(J J^T) = {margin:.3g} >= 2 at q0: explicit Euler "
                "is unstable along the stiffest task direction; lower the gain or dt",
                StabilityWarning,
                stacklevel=3,
            )


class _Run:
    """One run of a :class:`Tracker`: its arrays, constraint state, checks and record."""

    def __init__(
        self,
        tracker: Tracker,
        t: np.ndarray,
        chunks: ReferenceChunks,
        record_every: int,
        settings: StopSettings,
        progress: ProgressCallback | None,
    ) -> None:
        self.tr = tracker
        self.task = task = tracker.task
        self.robot = robot = tracker.robot
        self.t, self.chunks, self.progress = t, chunks, progress
        self.dt = tracker.dt
        self.N = t.shape[0]
        m, nv = task.m, robot.nv
        self.ext = ExtendedTask(m, tracker.rows, nv, tracker.K_task)
        cset = tracker.constraints
        self.rec = Recorder(
            self.N, record_every, robot.nq, nv, task.has_position,
            task.has_orientation and task.has_position, cset is not None,
        )  # fmt: skip
        self.crun: ConstraintRun | None = (
            None
            if cset is None
            else ConstraintRun(
                cset, m, tracker.law, tracker.alpha, t, self.rec.capacity, task.frame_id, task.rows
            )
        )
        self.monitor = ViolationMonitor(_joint_range(robot, cset))
        self.checks = StopChecks(settings, tracker.law, self.dt)
        self.e6 = np.zeros(6)
        self.steps, self.max_err, self.err = 0, 0.0, 0.0
        rows = task.rows
        self.pos_rows = rows[rows < 3]
        self.rot_rows = rows[rows >= 3]

    def law(self, r: int, out: np.ndarray) -> float:
        """The tracker's law on the first ``r`` rows of this run's extended task."""
        return self.tr.law_velocity(self.ext, r, out)

    # -- one sample, in steps ----------------------------------------------------------

    def kinematics(self, q: np.ndarray) -> np.ndarray:
        """Frame placement and Jacobian (6, nv) at ``q``, eq. (3), ``LOCAL_WORLD_ALIGNED``.

        With constraints every joint's Jacobian is computed: their rows need them.
        """
        model, data, fid = self.robot.model, self.robot.data, self.task.frame_id
        if self.crun is None:
            return pin.computeFrameJacobian(model, data, q, fid, LWA)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacement(model, data, fid)
        return pin.getFrameJacobian(model, data, fid, LWA)

    def task_rows(self, J6: np.ndarray, p_d: np.ndarray | None, R_d: np.ndarray | None,
                  xdot_d: np.ndarray) -> None:  # fmt: skip
        """Task error (6) ``e = (p_d - p, log3(R_d R^T))`` and rows of ``J`` into the task rows."""
        placement = self.robot.data.oMf[self.task.frame_id]
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
        placement = self.robot.data.oMf[self.task.frame_id]
        j = self.rec.keep(k, q, qdot, placement.translation, p_d, err, err_rot)
        if self.crun is not None:
            assert self.rec.active is not None and self.rec.distance is not None
            self.rec.active[j] = r - self.task.m
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
        if status != "completed" and out_of_reach:
            reason += f"; {out_of_reach}"
        status, reason = self._final_status(status, reason)
        return self._result(status, reason, wall, self.steps, self.max_err, self.err)

    def samples(self, q: np.ndarray) -> tuple[str, str]:
        """The loop, one sample at a time (the specification of the compiled engine).

        Sets :attr:`steps`, :attr:`max_err` and :attr:`err`; returns the status and reason.
        """
        model, m, dt, N = self.robot.model, self.task.m, self.dt, self.N
        crun, rec, t = self.crun, self.rec, self.t
        qdot = np.zeros(self.robot.nv)
        dq = np.zeros(self.robot.nv)
        c0, c1, P_d, R_d, FF, at_rest = self.chunks.load(0)
        progress_every = max(1, N // 100)
        rec.start(q)
        for k in range(N):
            if k == c1:
                c0, c1, P_d, R_d, FF, at_rest = self.chunks.load(k)
            kk = k - c0
            p_d = None if P_d is None else P_d[kk]
            J6 = self.kinematics(q)
            self.task_rows(J6, p_d, None if R_d is None else R_d[kk], FF[kk])
            exact = rec.due(k)
            r = m if crun is None else m + crun.update(k, q, self.ext, self.law, exact)
            blocked = self.law(r, qdot)
            self.err, err_rot = self.error_norms()
            self.max_err = max(self.max_err, self.err)
            stop = self.stop(k, qdot, self.err, r, blocked, bool(at_rest[kk]))
            self.observe_limits(float(t[k]), q)
            if exact or stop is not None:
                self.record(k, q, qdot, p_d, self.err, err_rot, r)
            rec.every_sample(q, qdot)
            self.steps = k + 1
            if stop is not None:
                return stop
            if self.progress is not None and k % progress_every == 0:
                self.progress(k, N)
            if k + 1 < N:
                np.multiply(qdot, dt, out=dq)
                q = pin.integrate(model, q, dq)
        return "completed", f"reached the end of the trajectory at t = {t[-1]:.6g} s"

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
            "duration": float(self.chunks.trajectory.duration),
            "stability_margin_max": float(self.checks.worst_margin),
        }
        result = TrackingResult(
            t=self.t[self.rec.idx[: self.rec.j]],
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
            self.crun.finish(result, self.rec.j)
        return result

    # -- reasons -----------------------------------------------------------------------

    def active_clause(self, r: int) -> str:
        if self.crun is None or r == self.task.m:
            return ""
        return f"; active constraints: {', '.join(self.crun.active_names())}"

    def deadlock_reason(self, tk: float, err: float, r: int, qdot: np.ndarray) -> str:
        """Remark 2, with the task rows that cannot follow and the constraints that block them."""
        ext, m = self.ext, self.task.m
        b = ext.demand(m, np.zeros(m)) if self.tr.law == "pseudoinverse" else ext.K[:m] * ext.e[:m]
        residual = b - ext.J[:m].dot(qdot)
        size = float(np.abs(residual).max())
        axes = self.task.axes
        rows = [axes[i] for i in np.flatnonzero(np.abs(residual) >= 0.3 * size)] if size else axes
        head = (
            f"deadlock at t = {tk:.6g} s: the task error is {err:.4g} and the law cannot reduce "
            f"it (Remark 2); task rows that cannot follow: {', '.join(rows)}"
        )
        if self.crun is None or r == m:
            return head + "; no constraint is active: the task is singular or out of reach"
        wanted = (  # the joint motion the task asks for (an SVD only of finite numbers)
            np.linalg.pinv(ext.J[:m]).dot(residual)
            if finite(ext.J[:m], residual)
            else np.zeros(ext.J.shape[1])
        )
        blocking = []
        for s, c in enumerate(self.crun.active_rows()):
            row = ext.J[m + s]
            scale = float(np.linalg.norm(row) * np.linalg.norm(wanted))
            if scale > 0.0 and float(row.dot(wanted)) < -0.05 * scale:
                blocking.append(c.key)
        names = blocking or self.crun.active_names()
        return head + (
            f"; in conflict with: {', '.join(names)}; active constraints: "
            f"{', '.join(self.crun.active_names())}"
        )


def _joint_range(robot: Robot, cset: ConstraintSet | None) -> JointRange:
    """The robot's limits, tightened by the joint-range constraint's where it has one."""
    return JointRange(robot, None if cset is None else cset.joint_ranges())


LWA = pin.LOCAL_WORLD_ALIGNED


def track(
    task: Task,
    trajectory: Trajectory,
    *,
    q0: np.ndarray | Sequence[float] | None = None,
    law: LawName = "transpose",
    gain: float | Sequence[float] = 1000.0,
    dt: float = 1e-3,
    damping: float = 0.0,
    constraints: ConstraintSet | None = None,
    record_every: int = 1,
    progress: ProgressCallback | None = None,
    engine: str = "compiled",
) -> TrackingResult:
    """Track a Cartesian trajectory with a CLIK law (the one-call form of :class:`Tracker`).

    Example:
        >>> robot = clik.Robot.load("planar4r")
        >>> task = clik.Task(robot, "tip", "position", axes=["x", "y"])
        >>> q0 = np.radians([180, -30, -90, -30])
        >>> result = clik.track(task, clik.trajectory.Line(...), q0=q0)
    """
    tracker = Tracker(
        task, law=law, gain=gain, dt=dt, damping=damping, constraints=constraints, engine=engine
    )
    return tracker.run(trajectory, q0, record_every=record_every, progress=progress)
