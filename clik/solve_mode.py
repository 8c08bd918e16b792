"""Solve mode: reach one target pose from ``q0`` by iterating a CLIK law to tolerance.

The reference is held (``xdot_d = 0``) and the law is iterated as a
fixed-point map: ``q <- q (+) alpha dt J^+ e`` for law (10), with
``alpha dt = 1`` (a Gauss-Newton step, damped as Levenberg-Marquardt with
``lambda^2 = lambda_0^2 + mu |e|^2``, ``mu = 10^-2``), or ``q <- q (+) alpha dt J^T e`` for
law (9). For a full pose task the error is ``log6(oMf^-1 oMd)`` in the frame,
with its exact Jacobian ``Jlog6 J_local`` (far from the target this converges
where the world-frame ``log3`` error stalls). After each step joints are
clipped into their limits; an attempt that stalls (no 0.1 % progress in 15
iterations) or hits the iteration limit restarts from a seeded random
configuration inside the limits, up to ``restarts`` times.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.laws import LawName, check_law, solve_small
from clik.task import Task


@dataclass(frozen=True)
class SolveResult:
    """Outcome of :func:`solve`.

    Attributes:
        success: True when both tolerances were met.
        reason: Why the solver stopped, in words.
        q: Final configuration (nq,).
        iterations: Iterations over all attempts.
        attempts: Number of attempts (1 + restarts used).
        position_error: Final position error norm [m] (0 without position rows).
        orientation_error: Final orientation error norm [rad] (0 without orientation rows).
        wall_time_s: Wall time [s].
    """

    success: bool
    reason: str
    q: np.ndarray
    iterations: int
    attempts: int
    position_error: float
    orientation_error: float
    wall_time_s: float

    @property
    def status(self) -> str:
        """``"converged"`` or ``"max_iterations"``."""
        return "converged" if self.success else "max_iterations"


def _target_arrays(target: object) -> tuple[np.ndarray | None, np.ndarray | None]:
    if isinstance(target, pin.SE3):
        return target.translation.copy(), target.rotation.copy()
    arr = np.asarray(target, dtype=float)
    if arr.shape == (3,):
        return arr.copy(), None
    if arr.shape == (4, 4):
        return arr[:3, 3].copy(), arr[:3, :3].copy()
    if arr.shape == (3, 3):
        return None, arr.copy()
    raise InputError(
        "target", "a pin.SE3, a (4, 4) pose, a (3,) position or a (3, 3) rotation", arr.shape
    )


def solve(
    task: Task,
    target: pin.SE3 | np.ndarray | Sequence[float],
    q0: np.ndarray | Sequence[float] | None = None,
    *,
    law: LawName = "pseudoinverse",
    step: float = 1.0,
    damping: float = 1e-6,
    mu: float = 1e-2,
    tolerance: float = 1e-4,
    orientation_tolerance: float = 1e-3,
    max_iterations: int = 100,
    restarts: int = 50,
    seed: int | None = 0,
) -> SolveResult:
    """Iterate a CLIK law until the task error is within tolerance.

    Args:
        task: The task (its mask selects which components must match).
        target: Target pose (``pin.SE3`` or 4x4), position (3,) or rotation (3, 3).
        q0: Start configuration (default: the robot's reference configuration).
        law: ``"pseudoinverse"`` (10) (default) or ``"transpose"`` (9).
        step: ``alpha dt``, the fraction of the law's velocity applied per iteration.
        damping: ``lambda_0`` of the damped pseudoinverse.
        mu: Levenberg-Marquardt factor: ``lambda^2 = lambda_0^2 + mu |e|^2``.
        tolerance: Position tolerance [m].
        orientation_tolerance: Orientation tolerance [rad].
        max_iterations: Iterations per attempt.
        restarts: Random restarts (within joint limits) after a failed attempt.
        seed: Seed of the restarts' random generator.
    """
    law = check_law(law)
    if law == "nonlinear":
        raise InputError("law", "'pseudoinverse' or 'transpose' in solve mode", law)
    if not isinstance(max_iterations, int) or max_iterations < 1:
        raise InputError("max_iterations", "an integer >= 1", max_iterations)
    if not isinstance(restarts, int) or restarts < 0:
        raise InputError("restarts", "an integer >= 0", restarts)
    for name, value in (
        ("tolerance", tolerance),
        ("orientation_tolerance", orientation_tolerance),
        ("step", step),
    ):
        if not (math.isfinite(value) and value > 0):
            raise InputError(name, "a positive finite number", value)
    for name, value in (("damping", damping), ("mu", mu)):
        if not (math.isfinite(value) and value >= 0):
            raise InputError(name, "a finite number >= 0", value)
    robot = task.robot
    model, data = robot.model, robot.data
    p_d, R_d = _target_arrays(target)
    if task.has_position and p_d is None:
        raise InputError("target", f"a position for the {task.kind} task")
    if task.has_orientation and R_d is None:
        raise InputError("target", f"an orientation for the {task.kind} task")
    for arr in (p_d, R_d):
        if arr is not None and not np.all(np.isfinite(arr)):
            raise InputError("target", "finite values", arr.tolist())
    q = robot.check_configuration(robot.q_reference if q0 is None else q0, "q0")
    rng = None  # created at the first restart (it costs ~20 us)
    lower, upper = robot.lower, robot.upper
    bounded = np.isfinite(lower) & np.isfinite(upper) & (robot.nq == robot.nv)
    clip = bool(bounded.any())
    full_pose = task.m == 6
    target_se3 = pin.SE3(R_d, p_d) if full_pose else None
    lo, hi = np.where(bounded, lower, -np.inf), np.where(bounded, upper, np.inf)
    fid, rows = task.frame_id, task.rows
    has_pos, has_rot = task.has_position, task.has_orientation
    e6 = np.zeros(6)
    e_pos, e_rot = e6[:3], e6[3:]
    pos_err = rot_err = math.inf
    iterations = 0
    attempts = 0
    eye_diag = slice(None, None, task.m + 1)
    LWA = pin.LOCAL_WORLD_ALIGNED
    best_total, best_q, best_errors = math.inf, q.copy(), (math.inf, math.inf)
    start = time.perf_counter()
    with np.errstate(invalid="ignore", divide="ignore"):  # solve_small checks for NaN
        while attempts <= restarts:
            attempts += 1
            since_best = 0
            best = math.inf
            for _ in range(max_iterations):
                if full_pose:  # log6 error in the frame, with its exact Jacobian (Jlog6)
                    pin.computeJointJacobians(model, data, q)
                    fMd = pin.updateFramePlacement(model, data, fid).actInv(target_se3)
                    e = pin.log6(fMd).vector
                    a, b, c, x, y, z = e.tolist()
                    pos_err = math.sqrt(a * a + b * b + c * c)
                    rot_err = math.sqrt(x * x + y * y + z * z)
                    J = pin.Jlog6(fMd.inverse()).dot(
                        pin.getFrameJacobian(model, data, fid, pin.LOCAL)
                    )
                else:
                    J6 = pin.computeFrameJacobian(model, data, q, fid, LWA)
                    oMf = data.oMf[fid]
                    if has_pos:
                        np.subtract(p_d, oMf.translation, out=e_pos)
                    if has_rot:
                        e_rot[:] = pin.log3(R_d.dot(oMf.rotation.T))
                    pos_err = math.sqrt(e_pos.dot(e_pos))
                    rot_err = math.sqrt(e_rot.dot(e_rot))
                    e = e6[rows]
                    J = J6[rows]
                if pos_err <= tolerance and rot_err <= orientation_tolerance:
                    oMf = data.oMf[fid]
                    if has_pos:  # report the world-frame errors, not log6's components
                        pos_err = float(np.linalg.norm(p_d - oMf.translation))
                    if has_rot:
                        rot_err = float(np.linalg.norm(pin.log3(R_d.dot(oMf.rotation.T))))
                    return SolveResult(
                        True,
                        f"converged in {iterations} iterations",
                        q,
                        iterations,
                        attempts,
                        pos_err,
                        rot_err,
                        time.perf_counter() - start,
                    )
                iterations += 1
                if law == "pseudoinverse":
                    A = J.dot(J.T)
                    A.flat[eye_diag] += damping * damping + mu * (pos_err**2 + rot_err**2)
                    dq = J.T.dot(solve_small(A, e))
                else:
                    dq = J.T.dot(e)
                dq *= step
                q = pin.integrate(model, q, dq)
                if clip and ((q < lo).any() or (q > hi).any()):
                    np.maximum(q, lo, out=q)
                    np.minimum(q, hi, out=q)
                total = pos_err + rot_err
                if total < 0.999 * best:
                    best, since_best = total, 0
                else:
                    since_best += 1
                    if since_best >= 15:
                        break
            if pos_err + rot_err < best_total:  # keep the best attempt for a failure report
                best_total, best_q, best_errors = pos_err + rot_err, q.copy(), (pos_err, rot_err)
            if attempts <= restarts:
                if rng is None:
                    rng = np.random.default_rng(seed)
                q = robot.random_configuration(rng)
    pos_err, rot_err = best_errors
    reason = (
        f"no convergence after {attempts} attempt(s), {iterations} iterations; best attempt: "
        f"position error {pos_err:.3g} m, orientation error {rot_err:.3g} rad"
    )
    return SolveResult(
        False, reason, best_q, iterations, attempts, pos_err, rot_err, time.perf_counter() - start
    )
