"""Transitional: the robot model moved to :mod:`clik.model` (removed with the package rooms).

The modules still importing ``clik.robot`` are rewritten by the package
reorganisation, which deletes this file.
"""

from clik.model.joints import (
    CONTINUOUS,
    OTHER,
    PRISMATIC,
    REVOLUTE,
    UNITS,
    JointValues,
    joint_kind,
)
from clik.model.loading import ReferenceClippedWarning
from clik.model.mimic import MAX_MIMIC, Mimic, MimicJointWarning
from clik.model.robot import PANDA_FINGERS, Robot

__all__ = [
    "CONTINUOUS",
    "MAX_MIMIC",
    "OTHER",
    "PANDA_FINGERS",
    "PRISMATIC",
    "REVOLUTE",
    "UNITS",
    "JointValues",
    "Mimic",
    "MimicJointWarning",
    "ReferenceClippedWarning",
    "Robot",
    "joint_kind",
]
