"""Joint kinds and the units of their values.

A *revolute* joint's value is an angle [rad] (degrees only where a scenario says
``unit = "deg"``), a *prismatic* joint's a length [m], always; a *continuous*
joint (unlimited revolute) is stored as (cos, sin). A mobile or floating base
(:mod:`clik.model.base`) is one joint of several values: *planar* ``(x, y, cos, sin)``
[m, m, -, -] or *free-flyer* ``(x, y, z, q_x, q_y, q_z, q_w)`` [m, m, m, unit quaternion].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import pinocchio as pin

from clik.errors import InputError

REVOLUTE = "revolute"
"""Kind of a one-DOF rotation with limits: one value, an angle [rad]."""
CONTINUOUS = "continuous"
"""Kind of an unlimited rotation: two configuration values (cos, sin), one DOF [rad]."""
PRISMATIC = "prismatic"
"""Kind of a one-DOF translation: one value, a length [m] (never converted from degrees)."""
PLANAR = "planar"
"""Kind of a planar joint (a mobile base): ``(x, y, cos, sin)``, nq 4, nv 3 ``(v_x, v_y,
omega)`` [m/s, m/s, rad/s]; its x and y are lengths [m], its (cos, sin) not an angle."""
FREE_FLYER = "free-flyer"
"""Kind of a free-flyer joint (a floating base): ``(x, y, z, q_x, q_y, q_z, q_w)``, nq 7, nv 6
``(v, omega)`` [m/s, rad/s]; its x, y, z are lengths [m], its quaternion not an angle."""
OTHER = "other"
"""Kind of any other joint (spherical, ...): values not converted."""

UNITS = ("rad", "deg")
"""Units of revolute joint values a user may write (prismatic values are always metres)."""


@dataclass(frozen=True)
class JointValues:
    """Joint values as a scenario writes them, with the unit of their angles.

    Which value is an angle is known only with the robot, so the values are
    kept as written: :meth:`Robot.check_configuration` converts them with
    :meth:`Robot.configuration`, turning only the angles (revolute and
    continuous joints) from ``unit`` into radians and keeping prismatic values
    in metres.

    Attributes:
        written: The values as written (revolute in ``unit``, prismatic in metres).
        unit: ``"rad"`` or ``"deg"``.

    Raises:
        InputError: ``unit`` is not ``"rad"`` or ``"deg"``.
    """

    written: tuple[float, ...]
    unit: str = "rad"

    def __post_init__(self) -> None:
        unit_scale(self.unit, "unit")
        object.__setattr__(self, "written", tuple(float(v) for v in self.written))


def unit_scale(unit: str, field: str) -> float:
    """Factor from ``unit`` to radians.

    Raises:
        InputError: ``unit`` is not one of :data:`UNITS`.
    """
    if unit not in UNITS:
        raise InputError(field, "one of 'rad', 'deg'", got=unit)
    return math.pi / 180.0 if unit == "deg" else 1.0


def joint_kind(joint: pin.JointModel) -> str:
    """Kind of a Pinocchio joint model: :data:`REVOLUTE`, :data:`CONTINUOUS`, ...

    Args:
        joint: An entry of ``model.joints``.
    """
    nq, nv, name = joint.nq, joint.nv, joint.shortname()
    if nq == 1 and nv == 1:
        return PRISMATIC if name.startswith("JointModelP") else REVOLUTE  # PX, PY, PZ, Prismatic...
    if nq == 2 and nv == 1:
        return CONTINUOUS
    if name == "JointModelPlanar":
        return PLANAR
    if name == "JointModelFreeFlyer":
        return FREE_FLYER
    return OTHER


LENGTHS = {PRISMATIC: 1, PLANAR: 2, FREE_FLYER: 3}
"""How many of a joint kind's first configuration values are lengths [m]."""


def joint_units(joint: pin.JointModel) -> list[str]:
    """Unit of each of a joint's configuration values.

    ``"rad"`` (revolute), ``"m"`` (prismatic; a base's x, y (and z)), ``""`` (a
    continuous joint's cos and sin, a base's rotation, other joints).
    """
    kind = joint_kind(joint)
    units = [""] * joint.nq
    if kind == REVOLUTE:
        units[0] = "rad"
    for i in range(LENGTHS.get(kind, 0)):
        units[i] = "m"
    return units


def q_slice(model: pin.Model, joint_id: int) -> slice:
    """The configuration values of one joint."""
    joint = model.joints[joint_id]
    return slice(joint.idx_q, joint.idx_q + joint.nq)
