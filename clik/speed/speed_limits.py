r"""Joint speed limits a run must respect: the settings and the per-sample ratio.

A run with :class:`SpeedLimits` must keep every joint's speed within ``scale``
times its URDF limit (``<limit velocity=...>``, ``model.velocityLimit``) and,
where one is given, its acceleration within ``amax_i``. Per sample ``k``, the
ratio of docs/method.md ("Joint speed limits: time scaling of the reference") is

.. math::

    r_k = \max\Big( \max_i \frac{|\dot q_{i,k}|}{s\, v_{\max,i}},\;
                    \max_i \sqrt{\frac{|\ddot q_{i,k}|}{a_{\max,i}}} \Big)

(the square root because slowing the reference by :math:`\sigma` scales the
velocities by :math:`\sigma` and the accelerations by :math:`\sigma^2`). The
limits are respected when :math:`\max_k r_k \le 1`. A velocity coordinate whose
URDF limit is missing, zero or infinite has no velocity bound (as in
:mod:`clik.outputs.velocity_report`); one without an acceleration limit has no
acceleration bound.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import InputError, JointNotFound
from clik.outputs.velocity_report import velocity_names

if TYPE_CHECKING:
    from clik.model.robot import Robot

MAX_SCALE = 10.0
"""Largest ``scale`` accepted: a fraction of the URDF limit up to ten times it."""

MAX_PASSES = 20
"""Largest ``max_passes`` accepted."""


def _positive(value: object, field: str, unit: str, upper: float = math.inf) -> float:
    """A finite number in ``(0, upper]``."""
    bound = f" and <= {upper:g}" if math.isfinite(upper) else ""
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating):
        raise InputError(field, f"a number > 0{bound} {unit}".rstrip(), value)
    number = float(value)
    if not (math.isfinite(number) and 0.0 < number <= upper):
        raise InputError(field, f"a number > 0{bound} {unit}".rstrip(), value)
    return number


@dataclass(frozen=True)
class SpeedLimits:
    r"""Respect the joint velocity (and acceleration) limits by time scaling of the reference.

    Attributes:
        scale: Fraction of the URDF velocity limit allowed, ``0 < scale <= 10``
            (above 1 allows speeds past the URDF's own limit).
        acceleration: Acceleration limit [rad/s^2 or m/s^2]: one number for every
            joint, a mapping joint name -> limit (joints not named have none), or
            None (no acceleration limit; standard URDF has none).
        margin: Relative margin of the slowdown: :math:`\sigma = 1 / \max(1, r (1 +
            margin))`, ``0 <= margin <= 1``.
        max_passes: Re-timing passes at most (runs after the first), 1..20.
        window: Half-width of the running maximum of the ratio [s] of the run's time:
            the slowdown starts this much before a peak and ends this much after it.
    """

    scale: float = 1.0
    acceleration: float | Mapping[str, float] | None = None
    margin: float = 0.05
    max_passes: int = 6
    window: float = 0.05

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "scale", _positive(self.scale, "velocity_limits.scale", "", MAX_SCALE))
        set_(self, "window", _positive(self.window, "velocity_limits.window", "[s]"))
        margin = self.margin
        if isinstance(margin, bool) or not isinstance(margin, int | float) or not 0 <= margin <= 1:
            raise InputError("velocity_limits.margin", "a number in [0, 1]", margin)
        set_(self, "margin", float(margin))
        passes = self.max_passes
        if isinstance(passes, bool) or not isinstance(passes, int) or not 1 <= passes <= MAX_PASSES:
            raise InputError("velocity_limits.max_passes", f"an integer in 1..{MAX_PASSES}", passes)
        acc = self.acceleration
        field = "velocity_limits.acceleration"
        if isinstance(acc, Mapping):
            checked = {
                str(k): _positive(v, f"{field}.{k}", "[rad/s^2 or m/s^2]") for k, v in acc.items()
            }
            set_(self, "acceleration", checked)
        elif acc is not None:
            set_(self, "acceleration", _positive(acc, field, "[rad/s^2 or m/s^2]"))

    def bounds(self, robot: Robot) -> SpeedBounds:
        """The bound of every velocity coordinate of ``robot``.

        Raises:
            JointNotFound: An acceleration limit for a joint the model does not have.
            InputError: No joint has a velocity limit and no acceleration limit is given.
        """
        model = robot.model
        names = velocity_names(model)
        vmax = np.array(model.velocityLimit, dtype=float)
        vmax = np.where(np.isfinite(vmax) & (vmax > 0.0), self.scale * vmax, np.inf)
        amax = np.full(model.nv, np.inf)
        if isinstance(self.acceleration, Mapping):
            joints = list(model.names)[1:]
            for name, limit in self.acceleration.items():
                if name not in joints:
                    raise JointNotFound(name, joints)
                joint = model.joints[model.getJointId(name)]
                amax[joint.idx_v : joint.idx_v + joint.nv] = limit
        elif self.acceleration is not None:
            amax[:] = self.acceleration
        if not (np.isfinite(vmax).any() or np.isfinite(amax).any()):
            raise InputError(
                "velocity_limits.enabled",
                f"a robot with joint velocity limits (URDF <limit velocity=...>): {robot.name!r} "
                "has none, so there is nothing to respect; give velocity_limits.acceleration or "
                "turn velocity_limits off",
            )
        return SpeedBounds(names, vmax, amax)

    def as_dict(self) -> dict[str, Any]:
        """The settings, JSON-ready."""
        acc = self.acceleration
        return {
            "scale": self.scale,
            "acceleration": dict(acc) if isinstance(acc, Mapping) else acc,
            "margin": self.margin,
            "max_passes": self.max_passes,
            "window_s": self.window,
        }


@dataclass(frozen=True)
class Excess:
    r"""The worst sample of a run against its bounds.

    Attributes:
        ratio: :math:`\max_k r_k` (0 when nothing is bounded).
        joint: The velocity coordinate where it occurs.
        kind: ``"velocity"`` or ``"acceleration"``.
        value: ``|qdot|`` [rad/s or m/s] or ``|qddot|`` [rad/s^2 or m/s^2] there.
        limit: Its bound, ``scale vmax`` or ``amax``, in the same unit.
        t: Time of the sample [s].
    """

    ratio: float
    joint: str
    kind: str
    value: float
    limit: float
    t: float

    def describe(self) -> str:
        """The excess in words, with its numbers."""
        unit = "rad/s or m/s" if self.kind == "velocity" else "rad/s^2 or m/s^2"
        symbol = "|qdot|" if self.kind == "velocity" else "|qddot|"
        return (
            f"joint {self.joint!r} at {self.value / self.limit:.3g} x its {self.kind} limit at t = "
            f"{self.t:.6g} s ({symbol} = {self.value:.4g} > {self.limit:.4g} {unit})"
        )


@dataclass(frozen=True)
class SpeedBounds:
    """The bound of each velocity coordinate (``inf``: none).

    Attributes:
        names: Name of each velocity coordinate (nv,).
        velocity: ``scale vmax_i`` (nv,) [rad/s or m/s].
        acceleration: ``amax_i`` (nv,) [rad/s^2 or m/s^2].
    """

    names: list[str]
    velocity: np.ndarray
    acceleration: np.ndarray

    def ratios(self, qdot: np.ndarray, qddot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per-sample, per-coordinate ratios (N, nv): velocity and (square-rooted) acceleration.

        Non-finite values (a diverged run's last samples) count as 0.
        """
        speed = np.nan_to_num(np.abs(np.asarray(qdot, dtype=float)), nan=0.0, posinf=0.0)
        accel = np.nan_to_num(np.abs(np.asarray(qddot, dtype=float)), nan=0.0, posinf=0.0)
        return speed / self.velocity, np.sqrt(accel / self.acceleration)

    def ratio(self, qdot: np.ndarray, qddot: np.ndarray) -> np.ndarray:
        """The ratio :math:`r_k` of each sample (N,)."""
        vel, acc = self.ratios(qdot, qddot)
        if vel.shape[1] == 0:
            return np.zeros(vel.shape[0])
        return np.maximum(vel.max(axis=1), acc.max(axis=1))

    def worst(self, t: np.ndarray, qdot: np.ndarray, qddot: np.ndarray) -> Excess:
        """Where the ratio is largest: joint, kind, value, bound and time."""
        vel, acc = self.ratios(qdot, qddot)
        if vel.size == 0:
            return Excess(0.0, "", "velocity", 0.0, math.inf, 0.0)
        use_acc = acc.max() > vel.max()
        table = acc if use_acc else vel
        k, i = np.unravel_index(int(np.argmax(table)), table.shape)
        if use_acc:
            value, limit = abs(float(qddot[k, i])), float(self.acceleration[i])
        else:
            value, limit = abs(float(qdot[k, i])), float(self.velocity[i])
        kind = "acceleration" if use_acc else "velocity"
        return Excess(float(table[k, i]), self.names[i], kind, value, limit, float(t[k]))
