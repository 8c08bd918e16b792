r"""Joint speed limits kept by the law itself, every sample: the settings and their bounds.

docs/method.md, "Joint speed limits in the law". :class:`JointSpeed` says what each
joint may do; :meth:`JointSpeed.bounds` turns it into one bound per velocity
coordinate of a robot (:class:`JointSpeedBounds`), which the loop's speed step
(:mod:`clik.loop.speed_step`) applies to the law's joint velocity:

.. math::

    |\dot q_i| \le v_i = s\, v_{\max,i}, \qquad |\dot q_{i,k} - \dot q_{i,k-1}| \le a_i\, dt

with ``s`` = ``scale``, ``v_max`` the URDF's ``<limit velocity=...>`` (or a per-joint
override; ``default_velocity`` for a joint whose URDF gives none or 0, with a
:class:`SpeedLimitWarning` naming it) and ``a`` the optional acceleration limits.
It is on by default; ``JointSpeed(enabled=False)`` (or ``joint_speed=None``) turns
it off, e.g. for the paper's case study as printed.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import ClikWarning, InputError, JointNotFound
from clik.outputs.velocity_report import file_sources, velocity_names

if TYPE_CHECKING:
    from clik.model.robot import Robot

DEFAULT_VELOCITY = 2.0
"""Speed bound [rad/s or m/s] of a joint whose URDF gives no velocity limit (or 0)."""

MAX_SCALE = 10.0
"""Largest ``scale``: up to ten times the URDF's limit."""

MAX_SPEED_BOUND = 1e4
"""Largest velocity or acceleration bound accepted [rad/s, m/s, rad/s^2 or m/s^2]."""


class SpeedLimitWarning(ClikWarning):
    """A joint has no velocity limit in its URDF: the law keeps it within ``default_velocity``."""


def _bound(value: object, field: str, unit: str, upper: float = MAX_SPEED_BOUND) -> float:
    """A finite number in ``(0, upper]``, else :class:`InputError` naming ``field``."""
    expected = f"a number > 0 and <= {upper:g} {unit}".rstrip()
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise InputError(field, expected, value)
    number = float(value)
    if not (math.isfinite(number) and 0.0 < number <= upper):
        raise InputError(field, expected, value)
    return number


def _per_joint(value: object, field: str, unit: str) -> dict[str, float]:
    """A mapping joint name -> bound, each checked."""
    if not isinstance(value, Mapping):
        raise InputError(field, f"a mapping joint name -> number {unit}", value)
    return {str(k): _bound(v, f"{field}.{k}", unit) for k, v in value.items()}


@dataclass(frozen=True)
class JointSpeed:
    """Joint speed (and acceleration) limits the law keeps at every sample.

    Attributes:
        enabled: Whether the law keeps them (default True).
        scale: Fraction of each joint's velocity limit allowed, ``0 < scale <= 10``.
        velocity: Per-joint velocity limits [rad/s or m/s] that replace the URDF's (the
            ``scale`` applies to them too), or None.
        default_velocity: Velocity limit [rad/s or m/s] of a joint whose URDF gives none
            (or 0); the run warns, naming those joints.
        acceleration: Acceleration limit [rad/s^2 or m/s^2]: one number for every joint,
            a mapping joint name -> limit (joints not named have none), or None.
    """

    enabled: bool = True
    scale: float = 1.0
    velocity: Mapping[str, float] | None = None
    default_velocity: float = DEFAULT_VELOCITY
    acceleration: float | Mapping[str, float] | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        if not isinstance(self.enabled, bool):
            raise InputError("joint_speed.enabled", "true or false", self.enabled)
        set_(self, "scale", _bound(self.scale, "joint_speed.scale", "", MAX_SCALE))
        unit = "[rad/s or m/s]"
        set_(
            self,
            "default_velocity",
            _bound(self.default_velocity, "joint_speed.default_velocity", unit),
        )
        if self.velocity is not None:
            set_(self, "velocity", _per_joint(self.velocity, "joint_speed.velocity", unit))
        acc, field, accel_unit = self.acceleration, "joint_speed.acceleration", "[rad/s^2 or m/s^2]"
        if isinstance(acc, Mapping):
            set_(self, "acceleration", _per_joint(acc, field, accel_unit))
        elif acc is not None:
            set_(self, "acceleration", _bound(acc, field, accel_unit))

    def bounds(self, robot: Robot, warn: bool = True) -> JointSpeedBounds | None:
        """The bound of every velocity coordinate of ``robot`` (None when not enabled).

        Args:
            robot: The robot.
            warn: Warn (:class:`SpeedLimitWarning`) naming the joints without a URDF limit.

        Raises:
            JointNotFound: A per-joint limit for a joint the model does not have.
        """
        if not self.enabled:
            return None
        model = robot.model
        names = velocity_names(model)
        urdf = np.array(model.velocityLimit, dtype=float)
        given = np.isfinite(urdf) & (urdf > 0.0)
        vmax = np.where(given, urdf, self.default_velocity)
        source = file_sources(model, given, "default")
        for name, limit in (self.velocity or {}).items():
            span = _span(model, name)
            vmax[span] = limit
            given[span] = True
            source[span] = ["setting"] * len(source[span])
        unlimited = sorted({names[i].split("[")[0] for i in np.flatnonzero(~given)})
        amax: np.ndarray | None = None
        if isinstance(self.acceleration, Mapping):
            amax = np.full(model.nv, np.inf)
            for name, limit in self.acceleration.items():
                amax[_span(model, name)] = limit
        elif self.acceleration is not None:
            amax = np.full(model.nv, float(self.acceleration))
        if unlimited and warn:
            where = (
                "the MJCF model (MJCF gives no joint velocity limits)"
                if getattr(robot, "mjcf", None) is not None
                else "the URDF (<limit velocity=...> missing or 0)"
            )
            warnings.warn(
                f"joint_speed: joint(s) {', '.join(unlimited)} of {robot.name!r} have no velocity "
                f"limit in {where}: the law keeps them "
                f"within default_velocity = {self.default_velocity:g} rad/s or m/s (times scale "
                f"{self.scale:g}); set joint_speed.velocity to give theirs",
                SpeedLimitWarning,
                stacklevel=3,
            )
        return JointSpeedBounds(names, self.scale * vmax, amax, unlimited, self, vmax, source)


def _span(model: Any, name: str) -> slice:
    """The velocity coordinates of joint ``name``."""
    joints = list(model.names)[1:]
    if name not in joints:
        raise JointNotFound(name, joints)
    joint = model.joints[model.getJointId(name)]
    return slice(joint.idx_v, joint.idx_v + joint.nv)


@dataclass(frozen=True)
class JointSpeedBounds:
    """The bound of each velocity coordinate, as the law applies it.

    Attributes:
        names: Name of each velocity coordinate (nv,).
        velocity: ``v_i = scale vmax_i`` (nv,) [rad/s or m/s], finite and > 0.
        acceleration: ``a_i`` (nv,) [rad/s^2 or m/s^2], ``inf`` where none; None: no
            acceleration limit at all.
        unlimited: Joints whose URDF gives no velocity limit (``default_velocity`` used).
        settings: The settings they come from.
        limit: ``vmax_i`` (nv,) [rad/s or m/s], before the scale.
        source: Where each ``vmax_i`` comes from (nv,): ``"urdf"``, ``"setting"``,
            ``"default"`` or ``"base_speed"`` (:mod:`clik.outputs.velocity_report`).
    """

    names: list[str]
    velocity: np.ndarray
    acceleration: np.ndarray | None
    unlimited: list[str]
    settings: JointSpeed
    limit: np.ndarray
    source: list[str]

    def as_info(self) -> dict[str, Any]:
        """``result.info["joint_speed"]``: the settings and the bounds, JSON-ready."""
        acc = self.acceleration
        return {
            "scale": self.settings.scale,
            "velocity": [float(v) for v in self.velocity],
            "acceleration": None
            if acc is None
            else [float(a) if math.isfinite(a) else None for a in acc],
            "default_velocity": self.settings.default_velocity,
            "unlimited": list(self.unlimited),
            "limit": [float(v) for v in self.limit],
            "source": list(self.source),
        }
