"""Mimic joints (URDF ``<mimic>``): read, and locked at the value their leader implies.

Mimic joints are not driven by their leader: clik moves every joint
independently, and Pinocchio 4.1's ``mimic=True`` refuses several of the
robots clik offers (a follower parsed before its leader: romeo, talos_full,
talos_full_box; a leader that does not exist: alex_psyonic_hands), cannot lock
a leader alone, and gives a follower no velocity of its own (nv = 0), which
clik's motion bounds for obstacle certificates do not cover. So
:meth:`Robot.load <clik.model.robot.Robot.load>` locks each follower at the
value its leader implies (``multiplier * leader + offset``, the leader at its
reference, or at its ``lock`` value) and warns with :class:`MimicJointWarning`
when the leader stays free (then the follower no longer follows it).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
from lxml import etree

from clik.errors import ClikWarning, RobotLoadError, user_stacklevel
from clik.model.joints import CONTINUOUS, PRISMATIC, joint_kind

MAX_MIMIC = 1000.0
"""Largest magnitude of a ``<mimic>`` multiplier and offset [rad or m] (a follower's value
then stays finite along any chain of mimics within the joint-count budget)."""


class MimicJointWarning(ClikWarning):
    """Mimic joints were locked while their leader stays free (the follower does not follow).

    Attributes:
        joints: Follower name -> (leader name, value it is locked at [rad or m]).
    """

    def __init__(self, message: str, joints: dict[str, tuple[str, float]]) -> None:
        super().__init__(message)
        self.joints = joints


@dataclass(frozen=True)
class Mimic:
    """A URDF ``<mimic>``: ``follower = multiplier * leader + offset`` [rad or m].

    Attributes:
        leader: Name of the joint followed.
        multiplier: Factor on the leader's value.
        offset: Added to the product [rad or m].
    """

    leader: str
    multiplier: float = 1.0
    offset: float = 0.0


def mimic_joints(root: etree._Element, urdf: Path) -> dict[str, Mimic]:
    """The URDF's ``<joint><mimic joint=... multiplier=... offset=.../></joint>`` entries.

    Raises:
        RobotLoadError: A ``<mimic>`` without a joint name, or with a multiplier or
            offset that is not a finite number.
    """
    mimics: dict[str, Mimic] = {}
    for joint in root.findall("joint"):
        element = joint.find("mimic")
        if element is None:
            continue
        name = joint.get("name")
        leader = element.get("joint")
        if not leader:
            raise RobotLoadError(
                urdf, f"joint {name!r} has a <mimic> without joint=...", line=element.sourceline
            )
        numbers: dict[str, float] = {}
        for attribute, default in (("multiplier", 1.0), ("offset", 0.0)):
            text = element.get(attribute)
            try:
                value = default if text is None else float(text)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise RobotLoadError(
                    urdf,
                    f"joint {name!r} has a <mimic> {attribute} {text!r}, expected a finite number",
                    line=element.sourceline,
                )
            if abs(value) > MAX_MIMIC:
                raise RobotLoadError(
                    urdf,
                    f"joint {name!r} has a <mimic> {attribute} {text!r}, expected a number of "
                    f"magnitude at most {MAX_MIMIC:g}",
                    line=element.sourceline,
                )
            numbers[attribute] = value
        mimics[name] = Mimic(leader, numbers["multiplier"], numbers["offset"])
    return mimics


def mimic_values(
    model: pin.Model,
    q_reference: np.ndarray,
    mimics: Mapping[str, Mimic],
    values: Mapping[str, float],
    source: Path | str,
) -> dict[str, tuple[str, float]]:
    """Follower -> (leader, value) for the mimic followers to lock.

    Followers in ``values`` (locked by the user) and those whose leader is not
    a movable joint are left out. A leader that is itself a follower is
    resolved first. Values [rad or m] are clipped into the follower's limits.

    Args:
        model: The robot's model, before locking.
        q_reference: Its reference configuration, where free leaders are taken.
        mimics: The URDF's mimic joints.
        values: The joints locked by the user, with their values [rad or m].
        source: The robot's file (or name), named in errors.

    Raises:
        RobotLoadError: Mimic joints follow each other in a cycle.
    """
    names = set(model.names[1:])
    todo = {f: m for f, m in mimics.items() if f in names and m.leader in names}
    todo = {f: m for f, m in todo.items() if f not in values}
    out: dict[str, tuple[str, float]] = {}

    def leader_value(name: str, chain: tuple[str, ...]) -> float:
        if name in values:
            return float(values[name])
        if name in todo:
            return resolve(name, chain)
        joint = model.joints[model.getJointId(name)]
        q = q_reference[joint.idx_q : joint.idx_q + joint.nq]
        return math.atan2(q[1], q[0]) if joint_kind(joint) == CONTINUOUS else float(q[0])

    def resolve(follower: str, chain: tuple[str, ...] = ()) -> float:
        if follower in out:
            return out[follower][1]
        if follower in chain:
            cycle = " -> ".join(repr(n) for n in (*chain, follower))
            raise RobotLoadError(source, f"mimic joints follow each other: {cycle}")
        mimic = todo[follower]
        value = mimic.multiplier * leader_value(mimic.leader, (*chain, follower)) + mimic.offset
        joint = model.joints[model.getJointId(follower)]
        if joint_kind(joint) != CONTINUOUS:
            low = float(model.lowerPositionLimit[joint.idx_q])
            high = float(model.upperPositionLimit[joint.idx_q])
            value = min(max(value, low), high)
        out[follower] = (mimic.leader, value)
        return value

    for follower in todo:
        resolve(follower)
    return out


def warn_free_leaders(
    model: pin.Model, robot_name: str, free_leaders: Mapping[str, tuple[str, float]]
) -> None:
    """Warn that these mimic followers were locked while their leader stays free.

    Args:
        model: The robot's model, before locking.
        robot_name: The robot's name, first in the message.
        free_leaders: Follower name -> (leader name, value it is locked at).

    Warns:
        MimicJointWarning: Always (called by ``Robot.load``, hence its stack level).
    """
    kinds = {str(n): joint_kind(j) for n, j in zip(model.names[1:], model.joints[1:], strict=True)}
    listing = "; ".join(
        f"{f!r} = {v:.6g} {'m' if kinds.get(f) == PRISMATIC else 'rad'} (mimics {lead!r})"
        for f, (lead, v) in free_leaders.items()
    )
    warnings.warn(
        MimicJointWarning(
            f"{robot_name}: mimic joint(s) locked at the value their leader's reference "
            f"implies, the leader left free (clik moves every joint independently, so "
            f"the follower does not follow): {listing}; lock the leader too to keep "
            "them consistent",
            dict(free_leaders),
        ),
        stacklevel=user_stacklevel(),
    )
