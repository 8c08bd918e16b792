"""A URDF's joints: known types, ends that name existing links, one parent per link, numbers.

:func:`joint_ends` gives the tree's edges (child link -> parent link) once
every joint has a known type (:data:`JOINT_TYPES`), parent and child links that
exist, and numbers in range: origin, a non-zero axis for a movable joint,
dynamics, and limits with ``lower <= upper`` for revolute and prismatic joints
(effort and velocity never negative).
"""

from __future__ import annotations

from lxml import etree

from clik.model.urdf_numbers import Fail, check_origin, read_numbers, shown

MOVABLE_TYPES = ("revolute", "continuous", "prismatic")
"""Joint types that add a degree of freedom to a fixed-base arm."""

JOINT_TYPES = (*MOVABLE_TYPES, "fixed", "floating", "planar")


def joint_ends(
    links: dict[str, etree._Element], joints: dict[str, etree._Element], fail: Fail
) -> dict[str, str]:
    """Child link -> parent link, checking each joint's type, ends and numbers."""
    parent_of: dict[str, str] = {}  # child link -> parent link
    joint_of: dict[str, str] = {}  # child link -> joint name
    for name, joint in joints.items():
        kind = joint.get("type")
        if kind not in JOINT_TYPES:
            raise fail(
                f"joint {shown(name)} has type {shown(str(kind))}; "
                f"known types: {', '.join(JOINT_TYPES)}",
                joint,
            )
        ends = {}
        for end in ("parent", "child"):
            element = joint.find(end)
            link = None if element is None else element.get("link")
            if link is None:
                raise fail(f"joint {shown(name)} has no <{end} link=...>", joint)
            if link not in links:
                raise fail(
                    f"joint {shown(name)} names {end} link {shown(link)} that does not exist",
                    element,
                )
            ends[end] = link
        child = ends["child"]
        if child in joint_of:
            raise fail(
                f"link {shown(child)} is the child of two joints ({shown(joint_of[child])} and "
                f"{shown(name)}): the joints do not form a tree",
                joint,
            )
        parent_of[child], joint_of[child] = ends["parent"], name
        _check_joint_numbers(name, joint, fail)
    return parent_of


def _check_joint_numbers(name: str, joint: etree._Element, fail: Fail) -> None:
    """A joint's origin, axis (not zero when movable), dynamics and limits, in range."""
    what = f"joint {shown(name)}"
    check_origin(joint, what, fail)
    kind = joint.get("type")
    axis = joint.find("axis")
    if axis is not None and axis.get("xyz") is not None:
        direction = read_numbers(axis, "xyz", 3, f"{what} axis", fail)
        if kind in MOVABLE_TYPES and not any(direction):
            raise fail(f"{what} has a zero axis", axis)
    dynamics = joint.find("dynamics")
    for attribute in ("damping", "friction"):
        if dynamics is not None and dynamics.get(attribute) is not None:
            read_numbers(dynamics, attribute, 1, f"{what} dynamics", fail, "limit")
    limit = joint.find("limit")
    if limit is None:
        if kind in ("revolute", "prismatic"):
            raise fail(f"{what} is {kind} but has no <limit>", joint)
        return
    values = {  # effort and velocity are bounds on magnitudes: never negative
        attribute: read_numbers(
            limit, attribute, 1, f"{what} limit", fail, "limit", attribute in _MAGNITUDES
        )[0]
        for attribute in ("lower", "upper", *_MAGNITUDES)
        if limit.get(attribute) is not None
    }
    lower, upper = values.get("lower", 0.0), values.get("upper", 0.0)
    if kind in ("revolute", "prismatic") and lower > upper:
        raise fail(f"{what} has lower limit {lower:g} above its upper limit {upper:g}", limit)


_MAGNITUDES = ("effort", "velocity")
