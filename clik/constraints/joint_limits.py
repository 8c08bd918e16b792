"""Joint-range constraints, eqs. (16)-(19) of METHOD.md.

For ``q_imin <= q_i <= q_imax`` and a threshold ``d_q``, the distance to the
nearer limit is ``d = q_i - q_imin`` (lower) or ``d = q_imax - q_i`` (upper).
The error is ``e_q = d_q - d`` (17), positive inside the threshold band; the
row is ``u_q = +-(0 ... 1 ... 0)`` (19), ``+`` for the lower limit and ``-``
for the upper one, so that ``edot_q = -u_q qdot`` (feed-forward 0 for a
constant threshold).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from clik.errors import InputError, JointNotFound


class JointLimits:
    """The joint-range rows of one robot, evaluated for all joints at once.

    Args:
        robot: The robot (its URDF limits are the defaults).
        threshold: ``d_q`` [rad or m], scalar or per joint.
        override: Joint name -> ``{"lower": value, "upper": value}`` replacing URDF limits
            (e.g. the case study's ``q3 <= -80 deg``) [rad].

    Attributes:
        lower, upper: Limits used (nq,), ``-inf``/``inf`` where a joint has none.
        threshold: ``d_q`` per joint (nq,).
        names: Constraint name of each of the ``2 nq`` candidate rows
            (``joint:<name>:lower``, then ``joint:<name>:upper``).
    """

    def __init__(
        self,
        robot: object,
        threshold: float | np.ndarray = math.pi / 90.0,
        override: Mapping[str, Mapping[str, float]] | None = None,
    ) -> None:
        names = list(robot.joint_names)  # type: ignore[attr-defined]
        if robot.nq != robot.nv:  # type: ignore[attr-defined]
            raise InputError(
                "constraints.joint_limits",
                "a robot with nq == nv (no continuous or spherical joints) for joint-range rows",
            )
        lower = np.array(robot.lower, dtype=float)  # type: ignore[attr-defined]
        upper = np.array(robot.upper, dtype=float)  # type: ignore[attr-defined]
        for joint, lim in (override or {}).items():
            if joint not in names:
                raise JointNotFound(joint, names)
            i = names.index(joint)
            for side, value in lim.items():
                if side not in ("lower", "upper") or not np.isfinite(value):
                    raise InputError(
                        f"constraints.joint_limits.override.{joint}.{side}",
                        "'lower' or 'upper' with a finite value",
                        value,
                    )
                (lower if side == "lower" else upper)[i] = value
        if np.any(lower > upper):
            bad = [names[i] for i in np.flatnonzero(lower > upper)]
            raise InputError("constraints.joint_limits", "lower <= upper for every joint", bad)
        thr = np.broadcast_to(np.asarray(threshold, dtype=float), lower.shape).copy()
        if not np.all(np.isfinite(thr)) or np.any(thr <= 0):
            raise InputError("constraints.joint_limits.threshold", "positive values", threshold)
        self.lower, self.upper, self.threshold = lower, upper, thr
        self.joint_names = names
        self.names = [f"joint:{n}:lower" for n in names] + [f"joint:{n}:upper" for n in names]
        self.n = len(names)
        self._bound = np.concatenate([lower, -upper])
        self._thr = np.concatenate([thr, thr])
        self.sign = np.concatenate([np.ones(self.n), -np.ones(self.n)])
        self.errors = np.zeros(2 * self.n)
        self._tmp = np.zeros(2 * self.n)

    def evaluate(self, q: np.ndarray) -> np.ndarray:
        """Errors ``e_q = d_q - d`` (17) of all ``2 nq`` rows (lower rows, then upper rows)."""
        e, n = self.errors, self.n
        # d = q - lower  (lower rows),  d = upper - q  (upper rows)
        np.subtract(q, self._bound[:n], out=e[:n])
        np.add(q, self._bound[n:], out=e[n:])
        e[n:] *= -1.0
        np.subtract(self._thr, e, out=e)
        return e

    def slack(self, q: np.ndarray) -> float:
        """How far [rad or m] the nearest joint is from entering its threshold band.

        Negative or zero when some row's error is >= 0 (``-max e_q`` of eq. (17)).
        """
        return -float(self.evaluate(q).max())

    def row(self, i: int, out: np.ndarray) -> None:
        """Row ``u_q`` (19) of candidate ``i`` into ``out`` (nv,)."""
        out[:] = 0.0
        out[i % self.n] = self.sign[i]
