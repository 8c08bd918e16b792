r"""Step 4b of a sample: the law's joint velocity within the joint speed limits.

docs/method.md, "Joint speed limits in the law" (clik's addition), eqs. (S1)-(S4).
The law's joint velocity is split into the constraint rows' part ``c`` and the
task's part ``t = qdot - c`` (law (10): its two priority levels; laws (9) and (8):
``c = J_c^T K_c e_c``, the constraint rows' share of (23)). When ``qdot`` is within
the box ``|qdot_i| <= v_i`` (and the acceleration bound) it is kept as it is;
otherwise

- (S1) ``u = sigma_c c``, ``sigma_c = min(1, min_i v_i / |c_i|)``: the constraints
  first, their direction kept;
- (S2) ``qdot = u + sigma_t t``, ``sigma_t`` the largest in ``[0, 1]`` keeping every
  joint in the box: the task with what is left, its direction kept (the task slows
  down along its path instead of leaving it);
- (S3) with acceleration limits, ``qdot = p + sigma_a (qdot - p)`` from the previous
  sample's ``p`` (0 at the first: the arm starts at rest), ``sigma_a`` the largest in
  ``[0, 1]`` with ``|qdot_i - p_i| <= a_i dt``.

The compiled engine's ``SpeedStep`` (``src/engine/loop/speed_step.cpp``) does the same.
"""

from __future__ import annotations

import numpy as np

from clik.loop.joint_speed import JointSpeedBounds
from clik.tasks.extended_task import ExtendedTask

NEGLIGIBLE = 1e-9
"""(S2) leaves out a part's components below this fraction of its largest: rounding (a
null-space part's 1e-16 on a joint the levels above hold at its bound would stop the
whole level); the final clip keeps the box."""


class SpeedStep:
    """One run's speed step: the bounds, the previous joint velocity, scratch arrays.

    Args:
        bounds: The bound of each velocity coordinate.
        dt: Sample time [s].
    """

    def __init__(self, bounds: JointSpeedBounds, dt: float) -> None:
        self.v = np.array(bounds.velocity, dtype=float)
        acc = bounds.acceleration
        self.a_dt = None if acc is None else np.array(acc, dtype=float) * dt
        nv = self.v.shape[0]
        self.prev = np.zeros(nv)  # the previous sample's joint velocity (the start: at rest)
        self.c = np.zeros(nv)  # the constraint rows' part of the law's joint velocity
        self.t = np.zeros(nv)

    def apply(self, qdot: np.ndarray, ext: ExtendedTask, r: int, pseudoinverse: bool) -> None:
        """Bring ``qdot`` (nv,) within the bounds in place, (S1)-(S3).

        Args:
            qdot: The law's joint velocity [rad/s or m/s], overwritten.
            ext: The run's extended task (its constraint rows ``m..r``).
            r: Rows of the extended task this sample.
            pseudoinverse: Law (10), whose constraint part is already in :attr:`c`
                (:func:`clik.loop.laws.prioritized`); else it is ``J_c^T K_c e_c``.
        """
        if self.a_dt is None:
            if (np.abs(qdot) <= self.v).all():  # within the limits: the law's own (NaN: not)
                return
        elif self._within(qdot):
            self.prev[:] = qdot
            return
        if not np.isfinite(qdot).all():  # the divergence check stops it: nothing to bound
            return
        c = self.c
        if not pseudoinverse:
            m = ext.m
            c[:] = ext.J[m:r].T.dot(ext.K[m:r] * ext.e[m:r]) if r > m else 0.0
        np.subtract(qdot, c, out=self.t)
        u = self.box_scale(c) * c  # (S1)
        np.add(u, self.fit(u, self.t) * self.t, out=qdot)  # (S2)
        if self.a_dt is not None:  # (S3)
            change = qdot - self.prev
            qdot[:] = self.prev + accel_scale(change, self.a_dt) * change
        np.clip(qdot, -self.v, self.v, out=qdot)  # rounding: a joint at its bound, not 1 ulp past
        if self.a_dt is not None:
            self.prev[:] = qdot

    def apply_parts(self, qdot: np.ndarray, parts: np.ndarray) -> None:
        """(S1)-(S3) with law (10)'s levels: the constraints first, then each level in turn.

        ``parts`` (1 + L, nv): the constraint level's part, then each task level's
        (:func:`clik.loop.levels.prioritized_levels`); ``qdot`` is their sum. (S2) fits
        level 1's part with the room (S1) left, then level 2's with what is left, and so
        on: a lower level never slows a higher one. One level: :meth:`apply`'s steps.
        """
        if self.a_dt is None:
            if (np.abs(qdot) <= self.v).all():
                return
        elif self._within(qdot):
            self.prev[:] = qdot
            return
        if not np.isfinite(qdot).all():
            return
        u = self.box_scale(parts[0]) * parts[0]  # (S1)
        for part in parts[1:]:  # (S2), level by level
            u += self.fit(u, part) * part
        qdot[:] = u
        if self.a_dt is not None:  # (S3)
            change = qdot - self.prev
            qdot[:] = self.prev + accel_scale(change, self.a_dt) * change
        np.clip(qdot, -self.v, self.v, out=qdot)
        if self.a_dt is not None:
            self.prev[:] = qdot

    def _within(self, qdot: np.ndarray) -> bool:
        """Whether ``qdot`` is in the speed box and its change within the acceleration bound."""
        if not bool(np.all(np.abs(qdot) <= self.v)):
            return False
        return bool(np.all(np.abs(qdot - self.prev) <= self.a_dt))

    def box_scale(self, c: np.ndarray) -> float:
        """(S1): ``min(1, min_i v_i / |c_i|)``."""
        a = np.abs(c)
        over = a > self.v
        return float(np.min(self.v[over] / a[over])) if over.any() else 1.0

    def fit(self, u: np.ndarray, t: np.ndarray) -> float:
        """(S2): the largest ``sigma`` in ``[0, 1]`` with ``|u_i + sigma t_i| <= v_i`` for all i.

        ``u`` is in the box; a joint moving toward ``+v_i`` has room ``v_i - u_i``, one
        moving toward ``-v_i`` room ``v_i + u_i``; components of ``t`` below
        :data:`NEGLIGIBLE` of its largest are left out (rounding).
        """
        sigma = 1.0
        moving = np.abs(t) > NEGLIGIBLE * float(np.max(np.abs(t), initial=0.0))
        room = np.where(t > 0.0, self.v - u, self.v + u)[moving]
        step = np.abs(t[moving])
        over = step > room
        if over.any():
            sigma = float(np.min(room[over] / step[over]))
        return max(sigma, 0.0)


def accel_scale(change: np.ndarray, a_dt: np.ndarray) -> float:
    """(S3): ``min(1, min_i a_i dt / |change_i|)``."""
    a = np.abs(change)
    over = a > a_dt
    return float(np.min(a_dt[over] / a[over])) if over.any() else 1.0
