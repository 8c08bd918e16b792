"""One target for one task in solve mode: the target and settings checked, the iteration.

:class:`SolveProblem` is the specification of the iteration the compiled engine
runs too (``src/engine/solving/solve.cpp``): the error, ``log6(oMf^-1 oMd)`` with
its exact Jacobian ``Jlog6 J_local`` for a full pose, else the world-aligned error
(6) on the task's rows with ``J`` (3); one step of law (10) (Levenberg-Marquardt)
or (9), clipped into the joint limits; and an attempt, iterated until converged,
stalled (:data:`STALL_PROGRESS`, :data:`STALL_ITERATIONS`) or out of iterations.
The attempts and restarts around it are :mod:`clik.solving.solve_mode`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from clik.bounds import MAX_ITERATIONS, MAX_RESTARTS, in_range
from clik.errors import InputError
from clik.loop.laws import solve_small
from clik.tasks.task import Task


def _target_arrays(target: object) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Target position and rotation, each None where ``target`` has none."""
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


def checked_target(task: Task, target: object) -> tuple[np.ndarray, np.ndarray]:
    """Target position and rotation for ``task``, placeholders where it has no such rows.

    Raises:
        InputError: The target misses what the task needs, or is not finite.
    """
    p_d, R_d = _target_arrays(target)
    if task.has_position and p_d is None:
        raise InputError("target", f"a position for the {task.kind} task")
    if task.has_orientation and R_d is None:
        raise InputError("target", f"an orientation for the {task.kind} task")
    for arr in (p_d, R_d):
        if arr is not None and not np.all(np.isfinite(arr)):
            raise InputError("target", "finite values", arr.tolist())
    return (np.zeros(3) if p_d is None else p_d), (np.eye(3) if R_d is None else R_d)


@dataclass(frozen=True)
class SolveSettings:
    """What :func:`~clik.solving.solve_mode.solve` iterates with (see its arguments)."""

    law: str
    step: float
    damping: float
    mu: float
    tolerance: float
    orientation_tolerance: float
    max_iterations: int
    restarts: int


def check_settings(settings: SolveSettings) -> None:
    """Refuse settings the iteration cannot use, naming the argument."""
    if settings.law == "nonlinear":
        raise InputError("law", "'pseudoinverse' or 'transpose' in solve mode", settings.law)
    for name, low, high, bound in (
        ("max_iterations", 1, MAX_ITERATIONS, "clik.bounds.MAX_ITERATIONS, a C int"),
        ("restarts", 0, MAX_RESTARTS, "clik.bounds.MAX_RESTARTS"),
    ):
        value = getattr(settings, name)
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise InputError(name, f"an integer >= {low}", value)
        if value > high:
            raise InputError(name, f"an integer <= {high} ({bound})", value)
    for name in ("tolerance", "orientation_tolerance", "step"):
        value = getattr(settings, name)
        if not in_range(value, 0.0, strict=True):
            raise InputError(name, "a positive finite number", value)
    for name in ("damping", "mu"):
        value = getattr(settings, name)
        if not in_range(value, 0.0):
            raise InputError(name, "a finite number >= 0", value)


def check_seed(seed: object) -> None:
    """Refuse a seed of the restarts that is not None or an integer >= 0."""
    if seed is None or (type(seed) is int and seed >= 0):
        return
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise InputError("seed", "an integer >= 0 or None (fresh entropy)", seed)


class SolveProblem:
    """One target for one task: the error, its Jacobian and one step of the law.

    Args:
        task: The task (its mask selects the rows).
        target: What :func:`~clik.solving.solve_mode.solve` was given.
        settings: The iteration's settings.
    """

    def __init__(self, task: Task, target: object, settings: SolveSettings) -> None:
        self.task, self.settings = task, settings
        self.robot = task.robot
        self.data = task.robot.model.createData()
        """The solve's own Pinocchio data (never the robot's: solves may run in threads)."""
        # (unused placeholders where the task has no such rows)
        self.p_d, self.R_d = checked_target(task, target)
        self.full_pose = task.m == 6
        self.target_se3 = pin.SE3(self.R_d, self.p_d) if self.full_pose else None
        robot = self.robot
        bounded = np.isfinite(robot.lower) & np.isfinite(robot.upper) & (robot.nq == robot.nv)
        self.clip = bool(bounded.any())
        self.lo = np.where(bounded, robot.lower, -np.inf)
        self.hi = np.where(bounded, robot.upper, np.inf)
        self.e6 = np.zeros(6)
        self.diagonal = slice(None, None, task.m + 1)

    def error(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Task error ``e``, its Jacobian ``J``, position [m] and orientation [rad] norms.

        A full pose uses ``log6(oMf^-1 oMd)`` in the frame with its exact Jacobian
        ``Jlog6 J_local``; a masked task the world-aligned error (6) and ``J`` (3).
        """
        model, data, fid = self.robot.model, self.data, self.task.frame_id
        if self.full_pose:
            pin.computeJointJacobians(model, data, q)
            fMd = pin.updateFramePlacement(model, data, fid).actInv(self.target_se3)
            e = pin.log6(fMd).vector
            J = pin.Jlog6(fMd.inverse()).dot(pin.getFrameJacobian(model, data, fid, pin.LOCAL))
            return e, J, _norm3(e[:3]), _norm3(e[3:])
        J6 = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        oMf = data.oMf[fid]
        e6 = self.e6
        if self.task.has_position:
            np.subtract(self.p_d, oMf.translation, out=e6[:3])
        if self.task.has_orientation:
            e6[3:] = pin.log3(self.R_d.dot(oMf.rotation.T))
        rows = self.task.rows
        return e6[rows], J6[rows], _norm3(e6[:3]), _norm3(e6[3:])

    def world_errors(self) -> tuple[float, float]:
        """Position and orientation error norms in the world frame, at the last ``q``."""
        oMf = self.data.oMf[self.task.frame_id]
        pos = rot = 0.0
        if self.task.has_position:
            pos = float(np.linalg.norm(self.p_d - oMf.translation))
        if self.task.has_orientation:
            rot = float(np.linalg.norm(pin.log3(self.R_d.dot(oMf.rotation.T))))
        return pos, rot

    def step(self, q: np.ndarray, e: np.ndarray, J: np.ndarray, err2: float) -> np.ndarray:
        """One iteration, ``q (+) step qdot``, clipped into the joint limits.

        Law (10): ``qdot = J^T (J J^T + lambda^2 I)^-1 e`` with
        ``lambda^2 = lambda_0^2 + mu |e|^2`` (Levenberg-Marquardt); law (9):
        ``qdot = J^T e``.
        """
        s = self.settings
        if s.law == "pseudoinverse":
            A = J.dot(J.T)
            A.flat[self.diagonal] += s.damping * s.damping + s.mu * err2
            dq = J.T.dot(solve_small(A, e))
        else:
            dq = J.T.dot(e)
        dq *= s.step
        q = pin.integrate(self.robot.model, q, dq)
        if self.clip and ((q < self.lo).any() or (q > self.hi).any()):
            np.maximum(q, self.lo, out=q)
            np.minimum(q, self.hi, out=q)
        return q

    def attempt(self, q: np.ndarray) -> tuple[np.ndarray, bool, int, float, float]:
        """Iterate from ``q`` until converged, stalled or out of iterations.

        Returns:
            The last ``q``, whether it converged, the iterations used, and the
            position [m] and orientation [rad] error norms at the last ``q``.
        """
        s = self.settings
        best, since_best = math.inf, 0
        pos = rot = math.inf
        for iteration in range(s.max_iterations):
            e, J, pos, rot = self.error(q)
            if pos <= s.tolerance and rot <= s.orientation_tolerance:
                return q, True, iteration, *self.world_errors()
            q = self.step(q, e, J, pos * pos + rot * rot)
            if pos + rot < STALL_PROGRESS * best:
                best, since_best = pos + rot, 0
            else:
                since_best += 1
                if since_best >= STALL_ITERATIONS:
                    return q, False, iteration + 1, pos, rot
        return q, False, s.max_iterations, pos, rot


STALL_PROGRESS = 0.999
"""An iteration makes progress when the error falls below this fraction of the best."""

STALL_ITERATIONS = 15
"""Iterations without progress after which an attempt restarts."""


def _norm3(v: np.ndarray) -> float:
    a, b, c = v.tolist()
    return math.sqrt(a * a + b * b + c * c)
