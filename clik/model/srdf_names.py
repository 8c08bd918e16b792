"""Whether an SRDF is about the robot at all: the robot's links and joints it names.

An SRDF read with the wrong robot, or a xacro SRDF expanded with other arguments
than its URDF (another ``prefix``), names none of the robot's links or joints: all
its pairs are left out and its group states set nothing. :func:`warn_mismatch`
says so once, with the counts, instead of a warning per unknown name.
"""

from __future__ import annotations

import warnings
from collections.abc import Collection

from lxml import etree

from clik.errors import ClikWarning, user_stacklevel

LINK_ATTRIBUTES: dict[str, tuple[str, ...]] = {
    "disable_collisions": ("link1", "link2"),
    "enable_collisions": ("link1", "link2"),
    "link": ("name",),
    "chain": ("base_link", "tip_link"),
    "end_effector": ("parent_link",),
    "virtual_joint": ("child_link",),
    "link_sphere_approximation": ("link",),
}
"""SRDF elements naming links, with the attributes that do (a group's ``<link>``, ...)."""

JOINT_ATTRIBUTES: dict[str, tuple[str, ...]] = {
    "joint": ("name",),
    "passive_joint": ("name",),
    "joint_property": ("joint_name",),
}
"""SRDF elements naming joints (a group's or a group state's ``<joint>``, ...)."""

_LISTED = 10
"""Names quoted in the warning before the rest is counted."""


class SrdfMismatchWarning(ClikWarning):
    """The SRDF names no link and no joint of the robot: none of it applies.

    Attributes:
        link_count: The robot's links.
        joint_count: The robot's joints.
        names: The link and joint names the SRDF gives instead (none of the robot's).
    """

    def __init__(self, message: str, link_count: int, joint_count: int, names: list[str]):
        super().__init__(message)
        self.link_count, self.joint_count, self.names = link_count, joint_count, names


def named(root: etree._Element, attributes: dict[str, tuple[str, ...]]) -> list[str]:
    """The names given by ``attributes`` (element tag -> attributes) under ``root``, once each."""
    found: dict[str, None] = {}
    for element in root.iter(*attributes):
        for key in attributes[str(element.tag)]:
            value = element.get(key)
            if value:
                found[value] = None
    return list(found)


def warn_mismatch(
    path: object, root: etree._Element, link_names: Collection[str], joint_names: Collection[str]
) -> bool:
    """Warn when the SRDF ``root`` names none of the robot's links and joints.

    Returns:
        Whether it warned (the caller then says nothing more about unknown names).

    Warns:
        SrdfMismatchWarning: The SRDF names 0 of the robot's links and 0 of its joints.
    """
    links, joints = named(root, LINK_ATTRIBUTES), named(root, JOINT_ATTRIBUTES)
    if set(links) & set(link_names) or set(joints) & set(joint_names):
        return False
    others = list(dict.fromkeys(links + joints))
    listed = ", ".join(repr(n) for n in others[:_LISTED])
    more = f" and {len(others) - _LISTED} more" if len(others) > _LISTED else ""
    given = f"it names {len(others)} others ({listed}{more})" if others else "it names none"
    pairs, states = len(root.findall("disable_collisions")), len(root.findall("group_state"))
    warnings.warn(
        SrdfMismatchWarning(
            f"{path} names 0 of the robot's {len(link_names)} links and 0 of its "
            f"{len(joint_names)} joints ({given}): it was written for another robot, or "
            f"its xacro markup wants other xacro_args (a prefix?); its {pairs} "
            f"<disable_collisions> pairs are left out and its {states} group states set "
            "no joint of the robot",
            len(link_names),
            len(joint_names),
            others,
        ),
        stacklevel=user_stacklevel(),
    )
    return True
