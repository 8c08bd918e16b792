"""Tracking: integrate the closed-loop law along a reference trajectory.

One iteration per sample (METHOD.md, "Discrete time"): at ``t_k`` compute the
direct kinematics and Jacobian at ``q_k``, the error ``e_k = x_d(t_k) - x(q_k)``,
the joint velocity ``qdot_k`` from the law, then integrate on the
configuration manifold, ``q_{k+1} = q_k (+) qdot_k dt`` (``pin.integrate``).
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.gains import row_gains, stability_margin
from clik.laws import (
    LawName,
    check_law,
    nonlinear,
    pseudoinverse,
    transpose,
)
from clik.reference_stream import REFERENCE_CHUNK, ReferenceChunks
from clik.result import TrackingResult
from clik.task import Task
from clik.trajectory import Trajectory, time_grid

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet

ProgressCallback = Callable[[int, int], None]


MAX_STEPS = 100_000_000
"""Largest run, ``(duration + settle) / dt + 1`` samples (about 15 minutes at 8 us per
step): a typo in ``dt`` fails at once, not as a run that never ends or an allocation
that cannot succeed."""


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
    """The CLIK loop for one robot, task and law, with its arrays preallocated.

    Build once, then call :meth:`run` with a trajectory (and again with
    another one): nothing is rebuilt per step.

    Args:
        task: The task (frame, kind, mask).
        law: ``"transpose"`` (9), ``"nonlinear"`` (8) or ``"pseudoinverse"`` (10).
        gain: ``alpha`` [1/s], a scalar or one value per task row.
        dt: Sample time [s].
        damping: ``lambda`` of the damped pseudoinverse (law (10) only).
        beta_max: Bound on the nonlinear law's extra gain [1/s] (default ``2 alpha``).
        constraints: Optional constraint rows (obstacles, joint ranges), eq. (20)-(25).
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
    ) -> None:
        self.task = task
        self.robot = task.robot
        self.law = check_law(law)
        self.dt = _positive(dt, "dt", "[s]")
        self.K_task = row_gains(gain, task.m, "gain")
        damping = float(damping)
        if not math.isfinite(damping) or damping < 0.0:
            raise InputError("damping", "a finite number >= 0", damping)
        self.damping = damping
        alpha = float(np.max(self.K_task))
        self.beta_max = (
            2.0 * alpha if beta_max is None else _positive(beta_max, "beta_max", "[1/s]")
        )
        self.constraints = constraints
        nv, m = self.robot.nv, task.m
        rows = m + (constraints.max_rows if constraints is not None else 0)
        self.J_e = np.zeros((rows, nv))
        self.e_e = np.zeros(rows)
        self.K_e = np.zeros(rows)
        self.ff_e = np.zeros(rows)
        self.K_e[:m] = self.K_task
        self._work = np.zeros(rows)
        self._jte = np.zeros(nv)
        self._e6 = np.zeros(6)
        if constraints is not None:
            constraints.bind(self)

    # -- one step ----------------------------------------------------------------------

    def law_velocity(self, r: int, out: np.ndarray) -> np.ndarray:
        """Joint velocity of the law on the first ``r`` rows of the extended task."""
        J, e, K, ff = self.J_e[:r], self.e_e[:r], self.K_e[:r], self.ff_e[:r]
        work = self._work[:r]
        if self.law == "transpose":
            return transpose(J, e, K, ff, out, work)
        if self.law == "nonlinear":
            return nonlinear(J, e, K, ff, out, work, self._jte, self.beta_max)
        return pseudoinverse(J, e, K, ff, out, work, self.damping)

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
            trajectory: Desired task trajectory; sampled once on the time grid.
            q0: Initial configuration (nq,).
            record_every: Keep every k-th sample (and the last) in the result's arrays;
                scalars such as ``max_task_error`` still see every sample.
            progress: Called as ``progress(k, N)`` about a hundred times during the run.
            deadlock_window: Time [s] the deadlock condition must hold before stopping.
            deadlock_ratio: Deadlock when ``|J_e^T K e_e| <= ratio |J_e|_F |K e_e|``...
            deadlock_error: ... while the task error norm exceeds this [m or rad].
            stall_window: With the reference at rest, a task error that falls by less
                than ``stall_progress`` (a fraction) over this time [s] is a deadlock too.
            stall_progress: See ``stall_window``.
            settle: Extra time [s] after the trajectory's end, holding its final value.
            max_joint_step: A joint step ``|qdot| dt`` above this [rad or m] stops the run
                with status ``diverged`` (explicit Euler blowing up).
        """
        robot, task = self.robot, self.task
        model, data = robot.model, robot.data
        q = robot.check_configuration(robot.q_reference if q0 is None else q0, "q0")
        robot.check_within_limits(q, "q0")
        if not isinstance(record_every, int | np.integer) or record_every < 1:
            raise InputError("record_every", "an integer >= 1", record_every)
        if not (math.isfinite(settle) and settle >= 0.0):
            raise InputError("settle", "a time >= 0 [s]", settle)
        steps_needed = (trajectory.duration + settle) / self.dt + 1
        if steps_needed > MAX_STEPS:
            raise InputError(
                "dt",
                f"a step giving at most {MAX_STEPS:.0e} steps over the trajectory's "
                f"{trajectory.duration + settle:g} s (this one gives {steps_needed:.3g})",
                self.dt,
            )
        t = time_grid(trajectory.duration + settle, self.dt)
        N, m, nv, dt = t.shape[0], task.m, robot.nv, self.dt
        fid, rows, sl = task.frame_id, task.rows, task._slice
        has_pos, has_rot = task.has_position, task.has_orientation
        # The reference is sampled in chunks: a 10^6-sample run never holds it whole.
        chunk = ReferenceChunks(task, trajectory, t, REFERENCE_CHUNK)

        self._warn_stability(q, m)
        constraints = self.constraints

        # Preallocated record: every record_every-th sample, and the last one.
        n_rec = (N - 1) // record_every + 1 + (1 if (N - 1) % record_every else 0)
        rec_idx = np.empty(n_rec, dtype=np.intp)
        rec_q = np.empty((n_rec, robot.nq))
        rec_qdot = np.empty((n_rec, nv))
        rec_qddot = np.zeros((n_rec, nv))
        rec_pos = np.empty((n_rec, 3))
        rec_ref = np.empty((n_rec, 3)) if has_pos else None
        rec_err = np.empty(n_rec)
        rec_rot_err = np.empty(n_rec) if (has_rot and has_pos) else None
        if constraints is not None:
            constraints.reset(q, t, n_rec)
        rec_active = np.zeros(n_rec, dtype=np.int16) if constraints is not None else None
        rec_dist = np.full(n_rec, np.inf) if constraints is not None else None
        decimated = record_every > 1
        joint_min = q.copy()
        joint_max = q.copy()
        qdot_prev = np.zeros(nv)

        J_e, e_e, ff_e = self.J_e, self.e_e, self.ff_e
        J_task, e_task = J_e[:m], e_e[:m]
        e6, e6_pos, e6_rot = self._e6, self._e6[:3], self._e6[3:]
        # Without constraints a full pose task runs the law on Pinocchio's J and e6 directly.
        direct = constraints is None and m == 6
        qdot = np.zeros(nv)
        dq = np.zeros(nv)
        max_err = 0.0
        err = 0.0
        status, reason = "completed", f"reached the end of the trajectory at t = {t[-1]:.6g} s"
        window = max(1, round(deadlock_window / dt))
        check_every = 10
        stuck = 0
        stall_steps = max(1, round(stall_window / dt))
        stall_k, stall_err = -1, 0.0
        progress_every = max(1, N // 100)
        j = 0  # next record slot
        steps = 0
        LWA = pin.LOCAL_WORLD_ALIGNED
        # Live views on the frame's placement in data (updated by every kinematics call).
        pin.framesForwardKinematics(model, data, q)
        translation, rotation_T = data.oMf[fid].translation, data.oMf[fid].rotation.T
        P_d = R_d = FF = at_rest = None
        c0 = c1 = 0
        law = self.law
        K_task, work, damping = self.K_task, self._work[:m], self.damping
        start = time.perf_counter()
        with np.errstate(invalid="ignore", divide="ignore"):
            for k in range(N):
                if k == c1:
                    c0, c1, P_d, R_d, FF, at_rest = chunk.load(k)
                kk = k - c0
                if constraints is None:
                    J6 = pin.computeFrameJacobian(model, data, q, fid, LWA)
                else:  # every joint's kinematics and Jacobian: constraint rows need them
                    pin.computeJointJacobians(model, data, q)
                    pin.updateFramePlacement(model, data, fid)
                    J6 = pin.getFrameJacobian(model, data, fid, LWA)
                if has_pos:
                    np.subtract(P_d[kk], translation, out=e6_pos)
                if has_rot:
                    e6_rot[:] = pin.log3(R_d[kk].dot(rotation_T))
                if direct:
                    r = m
                    if law == "pseudoinverse":
                        pseudoinverse(J6, e6, K_task, FF[kk], qdot, work, damping)
                    elif law == "transpose":
                        transpose(J6, e6, K_task, FF[kk], qdot, work)
                    else:
                        nonlinear(J6, e6, K_task, FF[kk], qdot, work, self._jte, self.beta_max)
                else:
                    if sl is not None:
                        e_task[:] = e6[sl]
                        J_task[:] = J6[sl]
                    else:
                        np.take(e6, rows, out=e_task)
                        np.take(J6, rows, axis=0, out=J_task)
                    ff_e[:m] = FF[kk]
                    r = m if constraints is None else m + constraints.update(k, q)
                    self.law_velocity(r, qdot)
                err = math.sqrt(e6_pos.dot(e6_pos)) if has_pos else math.sqrt(e6_rot.dot(e6_rot))
                if err > max_err:
                    max_err = err
                stop = False
                if k % check_every == 0:
                    if direct:  # the deadlock test reads the task rows from J_e, e_e
                        J_task[:] = J6
                        e_task[:] = e6
                    jump = float(np.abs(qdot).max()) * dt
                    if not (math.isfinite(err) and math.isfinite(jump)):
                        status, stop = "diverged", True
                        reason = f"non-finite joint velocity or task error at t = {t[k]:.6g} s"
                    elif jump > max_joint_step:
                        status, stop = "diverged", True
                        reason = self._divergence_reason(t[k], jump, r, err)
                    elif err > deadlock_error and self._deadlocked(r, deadlock_ratio):
                        stuck += check_every
                        if stuck >= window:
                            status, stop = "deadlock", True
                            reason = self._deadlock_reason(t[k], err, r)
                    else:
                        stuck = 0
                    # The same condition seen through its effect: at rest, the error stalls.
                    if err > deadlock_error and at_rest[kk]:
                        if stall_k < 0:
                            stall_k, stall_err = k, err
                        elif k - stall_k >= stall_steps:
                            if err > (1.0 - stall_progress) * stall_err:
                                status, stop = "deadlock", True
                                reason = self._deadlock_reason(t[k], err, r) + (
                                    f"; the error fell by less than {stall_progress:.0%} in "
                                    f"{stall_window:g} s with the reference at rest"
                                )
                            stall_k, stall_err = k, err
                    else:
                        stall_k = -1
                if k % record_every == 0 or k == N - 1 or stop:
                    rec_idx[j] = k
                    rec_q[j] = q
                    rec_qdot[j] = qdot
                    rec_pos[j] = translation
                    rec_err[j] = err
                    if rec_ref is not None:
                        rec_ref[j] = P_d[kk]
                    if rec_rot_err is not None:
                        rec_rot_err[j] = math.sqrt(e6_rot.dot(e6_rot))
                    if decimated:
                        np.subtract(qdot, qdot_prev, out=rec_qddot[j])
                    if constraints is not None:
                        rec_active[j] = r - m
                        rec_dist[j] = constraints.min_distance
                        constraints.record(j)
                    j += 1
                if decimated:
                    np.minimum(joint_min, q, out=joint_min)
                    np.maximum(joint_max, q, out=joint_max)
                    qdot_prev[:] = qdot
                steps = k + 1
                if stop:
                    break
                if progress is not None and k % progress_every == 0:
                    progress(k, N)
                if k + 1 < N:
                    np.multiply(qdot, dt, out=dq)
                    q = pin.integrate(model, q, dq)
        wall = time.perf_counter() - start
        if progress is not None:
            progress(N if status == "completed" else steps, N)

        if constraints is not None and status == "completed":
            skipped = sorted(
                {e["constraint"] for e in constraints.events if e["action"] == "skipped"}
            )
            if skipped:
                reason += (
                    f"; {len(skipped)} violated constraint(s) found no free row (more than "
                    f"n - m at once) and were skipped: {', '.join(skipped)}"
                )
        n_rec = j  # fewer when the run stopped early
        sl_rec = slice(0, n_rec)
        rec_t = t[rec_idx[sl_rec]]
        rec_q, rec_qdot = rec_q[sl_rec], rec_qdot[sl_rec]
        if decimated:
            rec_qddot = rec_qddot[sl_rec] / dt
        else:  # backward differences, vectorised
            rec_qddot = np.zeros_like(rec_qdot)
            rec_qddot[1:] = np.diff(rec_qdot, axis=0) / dt
            joint_min = rec_q.min(axis=0)
            joint_max = rec_q.max(axis=0)
        info = {
            "robot": robot.name,
            "frame": task.frame,
            "task": task.kind,
            "axes": task.axes,
            "law": self.law,
            "gain": [float(g) for g in self.K_task],
            "dt": dt,
            "record_every": record_every,
            "duration": float(trajectory.duration),
        }
        result = TrackingResult(
            t=rec_t,
            q=rec_q,
            qdot=rec_qdot,
            qddot=rec_qddot,
            position=rec_pos[sl_rec],
            reference_position=None if rec_ref is None else rec_ref[sl_rec],
            task_error_norm=rec_err[sl_rec],
            orientation_error_norm=None if rec_rot_err is None else rec_rot_err[sl_rec],
            status=status,
            reason=reason,
            wall_time_s=wall,
            steps=steps,
            max_task_error=max_err,
            final_task_error=err,
            joint_min=joint_min,
            joint_max=joint_max,
            min_obstacle_distance=None if rec_dist is None else rec_dist[sl_rec],
            active_count=None if rec_active is None else rec_active[sl_rec],
            info=info,
            robot=robot,
        )
        if constraints is not None:
            constraints.finish(result, n_rec)
        return result

    # -- checks ------------------------------------------------------------------------

    def _deadlocked(self, r: int, ratio: float) -> bool:
        """Remark 2: ``|J_e^T K e_e|`` tiny relative to ``|J_e| |K e_e|``."""
        J, Ke = self.J_e[:r], self.K_e[:r] * self.e_e[:r]
        force = float(np.linalg.norm(J.T @ Ke))
        scale = float(np.linalg.norm(J)) * float(np.linalg.norm(Ke))
        return scale > 0.0 and force <= ratio * scale

    def _divergence_reason(self, t: float, jump: float, r: int, err: float) -> str:
        m = self.task.m
        head = f"a joint moved {jump:.3g} rad in one step at t = {t:.6g} s (task error {err:.3g}): "
        if r == m or self.constraints is None:
            return head + (
                "the gain is too high for dt (alpha dt lambda_max(J J^T) >= 2?), or the "
                "reference leaves the workspace through a singularity"
            )
        names = ", ".join(self.constraints.active_names())
        return head + (
            f"with {r - m} active constraint row(s) ({names}) the extended Jacobian J_e is "
            "near-singular (conflicting constraints) or the gain too high for dt"
        )

    def _deadlock_reason(self, t: float, err: float, r: int) -> str:
        active = self.constraints.active_names() if self.constraints is not None else []
        names = ", ".join(active) if active else "none"
        return (
            f"deadlock at t = {t:.6g} s: |J_e^T e_e| ~ 0 while the task error is {err:.4g} "
            f"(Remark 2); active constraints: {names}"
        )

    def _warn_stability(self, q: np.ndarray, m: int) -> None:
        if self.law == "pseudoinverse":
            return
        J = self.task.jacobian(q)
        margin = stability_margin(J, self.K_task, self.dt)
        if margin >= 2.0:
            warnings.warn(
                f"gain: alpha dt lambda_max(J J^T) = {margin:.3g} >= 2 at q0: explicit Euler "
                "is unstable along the stiffest task direction; lower the gain or dt",
                StabilityWarning,
                stacklevel=3,
            )


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
) -> TrackingResult:
    """Track a Cartesian trajectory with a CLIK law (the one-call form of :class:`Tracker`).

    Example:
        >>> robot = clik.Robot.load("planar4r")
        >>> task = clik.Task(robot, "tip", "position", axes=["x", "y"])
        >>> q0 = np.radians([180, -30, -90, -30])
        >>> result = clik.track(task, clik.trajectory.Line(...), q0=q0)
    """
    tracker = Tracker(task, law=law, gain=gain, dt=dt, damping=damping, constraints=constraints)
    return tracker.run(trajectory, q0, record_every=record_every, progress=progress)
