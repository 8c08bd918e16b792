"""SRDF files (MoveIt's semantic robot description): disabled collision pairs, group states.

An SRDF names, beside a URDF, the link pairs a self-collision check may skip
(``<disable_collisions link1="a" link2="b" reason="Never"/>``: adjacent links, links
that can never touch, links always touching) and named joint configurations
(``<group_state name="ready" group="arm">`` with ``<joint name="j1" value="0.5"/>``).
Every example-robot-data robot ships one.

:func:`read_srdf` reads one strictly, with the URDF's rules
(:func:`clik.model.urdf_check.parse_xml`: no entities, no external DTD, no XInclude,
the same size and element budgets), and checks its names and numbers. An SRDF with
xacro markup (``arm.srdf.xacro``) is expanded first, with the URDF's ``xacro_args`` and
packages (:mod:`clik.model.srdf_xacro`). Links the robot does not have are left out
with a :class:`SrdfWarning` counting the pairs and naming the links (a MoveIt setup
assistant's file often keeps names of links renamed since); an SRDF naming no link and
no joint of the robot, written for another robot or expanded with other arguments, is a
:class:`~clik.model.srdf_names.SrdfMismatchWarning` instead. A group state's joints are
checked when the state is used (:func:`group_state_configuration`): joints the model does
not have are then skipped with a warning.

:meth:`Robot.load <clik.model.robot.Robot.load>` reads the SRDF (``srdf=``), the
self-collision rows skip its pairs
(:class:`~clik.constraints.collision_scene.CollisionScene`), and a start may be a group
state (``robot.group_state("ready")``, ``q0="srdf:ready"``, a scenario's
``[initial] q = "srdf:ready"``).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Protocol

import numpy as np
import pinocchio as pin
from lxml import etree

from clik.errors import ClikWarning, InputError, RobotLoadError, shown, user_stacklevel
from clik.model.base import planar_from_free_flyer
from clik.model.joints import CONTINUOUS, PLANAR, joint_kind
from clik.model.srdf_names import warn_mismatch
from clik.model.srdf_xacro import expansion_lines, srdf_root
from clik.model.urdf_check import MAX_NAME_LENGTH

SRDF_PREFIX = "srdf:"
"""A start written ``"srdf:NAME"`` is the SRDF group state ``NAME``."""

MAX_JOINT_VALUES = 16
"""Most numbers in one group-state ``<joint value="...">`` (a free-flyer joint has 7)."""

MAX_GROUP_STATE_VALUE = 1000.0
"""Largest magnitude of a group-state joint value [rad or m] (``MAX_JOINT_VALUE`` of a
scenario's ``initial.q``)."""

_LISTED = 20
"""Names listed in a warning before the rest is counted."""


class SrdfWarning(ClikWarning):
    """Names in an SRDF that the robot does not have: what they name is left out.

    Attributes:
        names: The unknown link or joint names.
    """

    def __init__(self, message: str, names: list[str]) -> None:
        super().__init__(message)
        self.names = names


@dataclass(frozen=True)
class GroupState:
    """A named configuration of an SRDF (``<group_state>``), its joint values as written.

    Attributes:
        name: The state's name (e.g. ``"ready"``).
        groups: The groups it was written for (an SRDF may give one name to states of
            several groups: their joints are merged).
        values: Joint name -> its values [rad or m]: one for a revolute or prismatic
            joint, one angle for a continuous joint, ``nq`` for another joint (a
            free-flyer: ``x y z qx qy qz qw``).
    """

    name: str
    groups: tuple[str, ...]
    values: Mapping[str, tuple[float, ...]]


@dataclass(frozen=True)
class Srdf:
    """What clik uses of an SRDF file.

    Attributes:
        path: The file.
        disabled_pairs: Link pairs whose collisions are not checked, each pair sorted
            (``("panda_link1", "panda_link3")``), only links the robot has.
        group_states: Group state name -> :class:`GroupState`.
        unknown_links: Links named in ``<disable_collisions>`` that the robot does not
            have (their pairs are left out, :class:`SrdfWarning`).
    """

    path: Path
    disabled_pairs: frozenset[tuple[str, str]]
    group_states: Mapping[str, GroupState] = field(default_factory=dict)
    unknown_links: tuple[str, ...] = ()


def read_srdf(
    path: str | Path,
    link_names: Collection[str],
    joint_names: Collection[str] = (),
    xacro_args: Mapping[str, str] | None = None,
    package_dirs: Sequence[str | Path] = (),
    *,
    extra_args: bool = False,
) -> Srdf:
    """Read an SRDF file's disabled collision pairs and group states.

    An SRDF with xacro markup (``arm.srdf.xacro``, ``${prefix}`` names, macros) is
    expanded first, with ``xacro_args`` and ``package_dirs``
    (:func:`clik.model.srdf_xacro.srdf_root`).

    Args:
        path: The SRDF file.
        link_names: The robot's link names (its URDF's ``<link>`` elements).
        joint_names: The robot's joint names (its movable joints).
        xacro_args: Arguments of the SRDF's xacro markup (the URDF's).
        package_dirs: Folders holding the packages its ``$(find pkg)`` name.
        extra_args: Whether ``xacro_args`` may hold arguments the SRDF does not use.

    Returns:
        The file's pairs (among ``link_names``) and group states.

    Raises:
        RobotLoadError: The file is missing, not strict XML within the budgets (see
            :func:`~clik.model.urdf_check.parse_xml`), xacro cannot expand it, its
            root is not ``<robot>``, a ``<disable_collisions>`` lacks ``link1`` or
            ``link2``, a ``<group_state>`` lacks its ``name``, a joint value is not
            one to :data:`MAX_JOINT_VALUES` finite numbers of magnitude at most
            :data:`MAX_GROUP_STATE_VALUE`, a name is longer than
            :data:`~clik.model.urdf_check.MAX_NAME_LENGTH`, or two states of one name
            give one joint different values. Each names the file and the line (of
            the expansion, for a xacro SRDF).
        InputError: ``xacro_args`` or ``package_dirs`` do not fit its xacro markup.

    Warns:
        SrdfMismatchWarning: The SRDF names no link and no joint of the robot (then
            the warning below is not given).
        SrdfWarning: Some ``<disable_collisions>`` name links the robot does not
            have (one line: how many pairs, which links).
    """
    path = Path(path)
    root, expanded = srdf_root(path, xacro_args, package_dirs, extra_args)
    with expansion_lines(path, expanded):
        return srdf_of(path, root, link_names, joint_names)


def srdf_of(
    path: Path, root: etree._Element, link_names: Collection[str], joint_names: Collection[str]
) -> Srdf:
    """What :func:`read_srdf` reads of the SRDF ``<robot>`` element ``root`` (as it is)."""
    links = set(link_names)
    pairs: set[tuple[str, str]] = set()
    unknown: dict[str, None] = {}
    elements = list(root.iterchildren("disable_collisions"))
    left_out = 0
    for element in elements:
        first, second = (_name(path, element, key) for key in ("link1", "link2"))
        missing = [n for n in (first, second) if n not in links]
        unknown.update(dict.fromkeys(missing))
        left_out += bool(missing)
        if not missing and first != second:
            pairs.add((first, second) if first < second else (second, first))
    states = _group_states(path, root)
    if not warn_mismatch(path, root, link_names, joint_names) and unknown:
        _warn_unknown_links(path, list(unknown), left_out, len(elements))
    return Srdf(path, frozenset(pairs), states, tuple(unknown))


def _warn_unknown_links(path: Path, names: list[str], left_out: int, total: int) -> None:
    """One :class:`SrdfWarning`: how many pairs name unknown links, and which links."""
    listed = ", ".join(repr(n) for n in names[:_LISTED])
    more = f" and {len(names) - _LISTED} more" if len(names) > _LISTED else ""
    warnings.warn(
        SrdfWarning(
            f"{path}: {left_out} of its {total} <disable_collisions> pairs name links the "
            f"robot does not have ({len(names)}: {listed}{more}); those pairs are left out",
            names,
        ),
        stacklevel=user_stacklevel(),
    )


def read_group_states(
    path: str | Path,
    xacro_args: Mapping[str, str] | None = None,
    package_dirs: Sequence[str | Path] = (),
) -> Mapping[str, GroupState]:
    """The group states of the SRDF file ``path`` (its pairs not read: no robot needed).

    A xacro SRDF is expanded first, as by :func:`read_srdf`.

    Raises:
        RobotLoadError: As :func:`read_srdf`.
    """
    path = Path(path)
    root, expanded = srdf_root(path, xacro_args, package_dirs)
    with expansion_lines(path, expanded):
        return _group_states(path, root)


def _group_states(path: Path, root: etree._Element) -> Mapping[str, GroupState]:
    """The ``<group_state>`` elements, states of one name merged."""
    values: dict[str, dict[str, tuple[float, ...]]] = {}
    groups: dict[str, list[str]] = {}
    for element in root.iterchildren("group_state"):
        name = _name(path, element, "name")
        group = element.get("group", "")
        state = values.setdefault(name, {})
        groups.setdefault(name, []).append(group)
        for joint in element.iterchildren("joint"):
            joint_name = _name(path, joint, "name")
            numbers = _numbers(path, joint, joint_name)
            if state.get(joint_name, numbers) != numbers:
                raise RobotLoadError(
                    path,
                    f"group state {name!r} gives joint {joint_name!r} two values "
                    f"({state[joint_name]} and {numbers}) in its groups {groups[name]}",
                    line=joint.sourceline,
                )
            state[joint_name] = numbers
    return MappingProxyType(
        {
            name: GroupState(name, tuple(groups[name]), MappingProxyType(joints))
            for name, joints in values.items()
        }
    )


def _name(path: Path, element: etree._Element, key: str) -> str:
    """The attribute ``key`` of ``element``: a name, present and within the budget."""
    value = element.get(key)
    if not value:
        raise RobotLoadError(
            path, f"<{element.tag}> needs a {key!r} attribute", line=element.sourceline
        )
    if len(value) > MAX_NAME_LENGTH:
        raise RobotLoadError(
            path,
            f"<{element.tag}> {key} of {len(value)} characters, above the budget of "
            f"{MAX_NAME_LENGTH} (clik.model.urdf_check.MAX_NAME_LENGTH)",
            line=element.sourceline,
        )
    return value


def _numbers(path: Path, joint: etree._Element, name: str) -> tuple[float, ...]:
    """A group-state joint's ``value``: 1 to :data:`MAX_JOINT_VALUES` finite numbers."""
    text = joint.get("value", "")
    words = text.split(None, MAX_JOINT_VALUES)
    expected = (
        f"joint {name!r}: expected a value of 1 to {MAX_JOINT_VALUES} finite numbers of "
        f"magnitude at most {MAX_GROUP_STATE_VALUE:g} [rad or m], got {shown(text, 80)}"
    )
    if not 1 <= len(words) <= MAX_JOINT_VALUES:
        raise RobotLoadError(path, expected, line=joint.sourceline)
    try:
        numbers = tuple(float(word) for word in words)
    except ValueError:
        raise RobotLoadError(path, expected, line=joint.sourceline) from None
    if not all(math.isfinite(v) and abs(v) <= MAX_GROUP_STATE_VALUE for v in numbers):
        raise RobotLoadError(path, expected, line=joint.sourceline)
    return numbers


class WithSrdf(Protocol):
    """What :func:`state_configuration` reads of a robot (:class:`~clik.model.robot.Robot`)."""

    @property
    def name(self) -> str:
        """The robot's name."""

    @property
    def model(self) -> pin.Model:
        """Its Pinocchio model."""

    @property
    def q_reference(self) -> np.ndarray:
        """Its reference configuration, shape (nq,)."""

    @property
    def locked(self) -> Mapping[str, float]:
        """Joints locked out of the model, with their values [rad or m]."""

    @property
    def srdf_path(self) -> Path | None:
        """Its SRDF file, or None."""

    @property
    def group_states(self) -> Mapping[str, GroupState]:
        """Its SRDF's group states by name."""


def state_configuration(robot: WithSrdf, name: str, field: str) -> np.ndarray:
    """The configuration of the robot's SRDF group state ``name`` (``robot.group_state``).

    Args:
        robot: The robot (its ``group_states``, ``q_reference`` and ``locked`` joints).
        name: The state's name.
        field: Name of the input, used in error messages.

    Raises:
        InputError: The robot's SRDF has no state ``name`` (the message lists its
            states, or says the robot has no SRDF); see :func:`group_state_configuration`.
    """
    state = robot.group_states.get(name) if isinstance(name, str) else None
    if state is None:
        names = ", ".join(repr(n) for n in robot.group_states)
        expected = (
            f"the name of a group state of {robot.srdf_path} ({names})"
            if robot.group_states
            else f"a group state name, but {robot.name} has "
            + ("no SRDF (srdf=PATH)" if robot.srdf_path is None else "none in its SRDF")
        )
        raise InputError(field, expected, name)
    return group_state_configuration(robot.model, robot.q_reference, state, robot.locked, field)


def group_state_configuration(
    model: pin.Model,
    q_reference: np.ndarray,
    state: GroupState,
    locked: Collection[str],
    field: str,
) -> np.ndarray:
    """The configuration of a group state: ``q_reference`` with the state's joints set.

    Joints the state does not list keep their reference values. A joint the model
    lacks is skipped: silently when it is locked (``locked``: its lock value holds),
    else with a :class:`SrdfWarning`. A continuous joint's value is its angle [rad]
    (stored as cos, sin); a joint of several values (planar, free-flyer) takes
    Pinocchio's ``nq`` values, then normalised.

    Args:
        model: The robot's model.
        q_reference: Its reference configuration, shape (nq,).
        state: The group state.
        locked: Joints locked out of the model.
        field: Name of the input, used in error messages.

    Returns:
        A new configuration, shape (nq,) [rad or m] (not checked against the limits).

    Raises:
        InputError: A joint's value count does not fit the joint (names the joint).

    Warns:
        SrdfWarning: The state names joints the model does not have (nor locked ones).
    """
    q = np.array(q_reference, dtype=float)
    absent: list[str] = []
    several = False
    for name, values in state.values.items():
        if not model.existJointName(name) or model.getJointId(name) == 0:
            if name not in locked:
                absent.append(name)
            continue
        joint = model.joints[model.getJointId(name)]
        i, nq = joint.idx_q, joint.nq
        if joint_kind(joint) == CONTINUOUS and len(values) == 1:
            q[i : i + 2] = (math.cos(values[0]), math.sin(values[0]))
        elif joint_kind(joint) == PLANAR and len(values) == 7:  # (x, y, z, quaternion)
            q[i : i + nq] = planar_from_free_flyer(np.array(values))  # a floating base's state
        elif len(values) == nq:
            q[i : i + nq] = values
            several = several or nq > 1
        else:
            count = "1 value (its angle) or 2" if joint_kind(joint) == CONTINUOUS else str(nq)
            raise InputError(
                field,
                f"group state {state.name!r}: {count} values for joint {name!r}",
                list(values),
            )
    if absent:
        warnings.warn(
            SrdfWarning(
                f"group state {state.name!r} names joints the robot does not have "
                f"({', '.join(repr(n) for n in absent[:_LISTED])}); their values are ignored",
                absent,
            ),
            stacklevel=user_stacklevel(),
        )
    return np.asarray(pin.normalize(model, q)) if several else q


def srdf_file(srdf: object, own: Path | None) -> Path | None:
    """The SRDF file :meth:`Robot.load <clik.model.robot.Robot.load>` reads.

    Args:
        srdf: ``srdf=`` as given: None (the robot's own SRDF: example-robot-data's,
            none for a file), False (none), or a path.
        own: The robot's own SRDF, or None.

    Raises:
        InputError: ``srdf`` is none of these (True among them).
    """
    if srdf is None:
        return own
    if srdf is False:
        return None
    if isinstance(srdf, str | Path) and str(srdf):
        return Path(srdf)
    raise InputError(
        "srdf",
        "an SRDF file path, None (the robot's own: example-robot-data's) or False (none)",
        srdf,
    )
