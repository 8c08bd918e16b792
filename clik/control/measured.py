"""Measured joints: a controller's tick run from the joints the robot reached.

``Controller.step(targets, q_measured=...)`` closes the loop on the robot
(docs/method.md, "Measured joints", (M1)-(M5)): the tick's law runs from the
measured joints ``q_m`` instead of the controller's own ``q_k`` (M1), and the
joints it returns integrate the commanded ones, ``q_{k+1} = q_k (+) qdot_k dt``
(M2). A measurement that moved further since the last accepted one than the robot
can move, ``|q_m (-) q_a|_i > c vmax_i dt n`` (M3), is refused: the law runs from
``q_k`` and the verdict is :data:`MEASUREMENT_JUMP`.

:class:`MeasuredJoints` is the specification of the compiled engine's
(``src/engine/loop/bind_ticker.cpp``, ``Measured``): the same checks in the same
order, the same jump, the same record.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.control.targets import as_floats
from clik.errors import InputError
from clik.model.base import QUATERNION_TOLERANCE
from clik.model.joints import CONTINUOUS, FREE_FLYER, PLANAR, joint_kind
from clik.outputs.velocity_report import velocity_names

if TYPE_CHECKING:
    from clik.model.robot import Robot

MEASURED_JUMP = 3.0
"""Default ``measured_jump`` ``c`` of (M3): a measurement may move at most ``c`` times the
joints' speed limits times the time since the last accepted one."""

MEASUREMENT_JUMP = "measurement_jump"
"""The verdict of a tick whose ``q_measured`` broke (M3) (docs/method.md, "Verdicts")."""

JumpFound = tuple[int, float, float, int, int]
"""A jump of (M3): the velocity coordinate ``i``, ``|q_m (-) q_a|_i``, its bound ``b_i n``,
the tick ``k_a`` of ``q_a`` and ``n``."""


def jump_bound(robot: Robot, factor: float, dt: float) -> np.ndarray:
    """Eq. (M3)'s per-tick bound ``b_i = c vmax_i dt`` (nv,) [rad or m].

    ``vmax_i`` is ``model.velocityLimit`` (the URDF's, a base's as clik writes them); a
    coordinate with none (0 or not finite) has no bound (``inf``).
    """
    vmax = np.asarray(robot.model.velocityLimit, dtype=float)
    has = np.isfinite(vmax) & (vmax > 0.0)
    return np.where(has, factor * np.where(has, vmax, 0.0) * dt, np.inf)


def rotation_slices(robot: Robot) -> list[tuple[int, int, str]]:
    """The unit rotations in ``q``: ``(start, size, expected)`` of each, in order.

    A continuous joint's or a planar base's ``(cos, sin)``, a floating base's quaternion
    (docs/method.md, "Mobile and floating bases").
    """
    out = []
    for joint in robot.model.joints[1:]:
        kind = joint_kind(joint)
        if kind in (PLANAR, CONTINUOUS):
            i = joint.idx_q + (2 if kind == PLANAR else 0)
            out.append((i, 2, f"a (cos, sin) pair of norm 1 at q_measured[{i}:{i + 2}]"))
        elif kind == FREE_FLYER:
            i = joint.idx_q + 3
            out.append((i, 4, f"a quaternion (x, y, z, w) of norm 1 at q_measured[{i}:{i + 4}]"))
    return out


class MeasuredJoints:
    """A controller's measured joints: their checks, the jump (M3) and their record.

    Args:
        robot: The controller's robot.
        factor: ``measured_jump``, ``c`` of (M3), > 0.
        dt: The tick [s].
    """

    def __init__(self, robot: Robot, factor: float, dt: float) -> None:
        self.model = robot.model
        self.nq, self.nv = robot.nq, robot.nv
        self.factor, self.dt = factor, dt
        self.bound = jump_bound(robot, factor, dt)
        self.names = velocity_names(robot.model)
        self.rotations = rotation_slices(robot)
        self.words = f"{self.nq} finite joint values (nq,) [rad or m] for {robot.name}"
        self.velocity_words = f"{self.nv} finite joint velocities (nv,) [rad/s or m/s]"
        self.restart(np.zeros(self.nq), 1)

    def restart(self, q0: np.ndarray, capacity: int) -> None:
        """A new session from ``q0``, its record of ``capacity`` slots (the run's ring)."""
        self.q_accepted = np.array(q0, dtype=float)  # q_a of (M3)
        self.k_accepted = 0
        self.commanded = np.full((capacity, self.nq), np.nan)
        self.measured = np.full((capacity, self.nq), np.nan)
        self.qdot_measured = np.full((capacity, self.nv), np.nan)

    # -- staging: the caller's values, checked --------------------------------------------

    def stage(self, q_measured: Any, qdot_measured: Any) -> tuple[np.ndarray, np.ndarray | None]:
        """``q_measured`` (nq,) and ``qdot_measured`` (nv,) as float64 arrays, checked.

        Raises:
            InputError: Either not finite numbers of its size; a rotation of ``q_measured``
                whose norm is off 1 by more than ``QUATERNION_TOLERANCE`` (normalised when
                within); ``qdot_measured`` without ``q_measured``.
        """
        if q_measured is None:
            raise InputError("qdot_measured", "given with q_measured", "no q_measured")
        q = _floats(q_measured, "q_measured", self.nq, self.words)
        for i, n, expected in self.rotations:
            norm = float(np.sqrt(np.sum(q[i : i + n] ** 2)))
            if not abs(norm - 1.0) <= QUATERNION_TOLERANCE:
                raise InputError("q_measured", expected, q[i : i + n].tolist())
            q[i : i + n] /= norm
        if qdot_measured is None:
            return q, None
        return q, _floats(qdot_measured, "qdot_measured", self.nv, self.velocity_words)

    # -- (M3) ---------------------------------------------------------------------------

    def jump(self, q: np.ndarray, k: int) -> JumpFound | None:
        """Eq. (M3) at tick ``k``: the worst coordinate beyond its bound, or None (accepted).

        ``d = q (-) q_a`` (``pin.difference``, nv), ``n = max(k - k_a, 1)`` ticks since
        ``q_a``; the coordinate of the largest ``|d_i| / (b_i n)`` when it is above 1.
        """
        d = np.abs(pin.difference(self.model, self.q_accepted, q))
        n = max(k - self.k_accepted, 1)
        limit = self.bound * n
        ratio = np.divide(d, limit, out=np.zeros_like(d), where=np.isfinite(limit))
        i = int(np.argmax(ratio)) if ratio.size else 0
        if ratio.size == 0 or not ratio[i] > 1.0:
            return None
        return i, float(d[i]), float(limit[i]), self.k_accepted, n

    def accept(self, q: np.ndarray, k: int) -> None:
        """``q`` is ``q_a`` of (M3) from tick ``k`` on."""
        self.q_accepted[:] = q
        self.k_accepted = k

    def keep(self, j: int, commanded: np.ndarray, q: np.ndarray | None,
             qdot: np.ndarray | None) -> None:  # fmt: skip
        """Record slot ``j``: the commanded joints and the measurement (NaN: none given)."""
        self.commanded[j] = commanded
        self.measured[j] = np.nan if q is None else q
        self.qdot_measured[j] = np.nan if qdot is None else qdot

    def reason(self, jump: JumpFound) -> str:
        """The :data:`MEASUREMENT_JUMP` verdict's reason, with its numbers."""
        i, size, limit, k_a, n = jump
        return (
            f"{MEASUREMENT_JUMP}: q_measured moved {size:.4g} in {self.names[i]} since the "
            f"last accepted measurement (t = {k_a * self.dt:.6g} s), more than the bound "
            f"{limit:.4g} (measured_jump {self.factor:g} x its speed limit x {n} tick(s) of "
            f"{self.dt:g} s); the tick ran from the controller's own joints"
        )

    def record(self, order: np.ndarray | slice) -> dict[str, np.ndarray]:
        """The record's arrays in ``order`` (the run's kept samples, oldest first)."""
        return {
            "q_commanded": self.commanded[order].copy(),
            "q_measured": self.measured[order].copy(),
            "qdot_measured": self.qdot_measured[order].copy(),
        }


def _floats(value: Any, field: str, size: int, expected: str) -> np.ndarray:
    """``value`` as a new float64 array of ``size`` finite numbers, else InputError."""
    array = as_floats(value, field, expected)
    if array.shape != (size,):
        raise InputError(field, expected, f"shape {array.shape}")
    if not np.isfinite(array).all():
        raise InputError(field, f"finite numbers: {expected}", array.tolist())
    return np.array(array)  # its own (as_floats may return the caller's array)
