"""Numbers in a URDF: finite, and each within the physical range of its kind.

Positions and sizes within :data:`~clik.model.mesh_check.MAX_COORDINATE` [m],
angles within :data:`MAX_ANGLE` [rad], masses and inertia entries within
:data:`MAX_MASS` [kg, kg m^2], limits, dynamics values and scale factors within
:data:`MAX_LIMIT` (:data:`RANGES`). A problem is raised through the caller's
``fail(problem, element)`` (:data:`Fail`), which names the file and the
element's line; names and values are shown cut to :data:`SHOWN_NAME`
characters (:func:`shown`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from lxml import etree

from clik import errors
from clik.errors import RobotLoadError
from clik.model.mesh_check import MAX_COORDINATE

Fail = Callable[..., RobotLoadError]
"""Builds the error for a problem found at an element: ``fail(problem, element)``."""

SHOWN_NAME = 60
"""Characters of a long name shown in messages."""

MAX_ANGLE = 4 * math.pi
"""Largest absolute angle in an origin's ``rpy`` [rad] (two turns)."""

MAX_MASS = 1e6
"""Largest mass [kg] and largest inertia entry [kg m^2]."""

MAX_LIMIT = 1e16
"""Largest absolute joint limit (position [rad or m], effort, velocity), dynamics value
(damping, friction) and mesh scale factor: 1e16 is the URDF convention for "no limit"."""

RANGES = {
    "position": MAX_COORDINATE,
    "angle": MAX_ANGLE,
    "mass": MAX_MASS,
    "limit": MAX_LIMIT,
    "scale": math.inf,  # each factor's magnitude in clik.model.mesh_check.SCALE_RANGE
}
"""Largest absolute value of each kind of URDF number."""

_UNITS = {"position": "m", "angle": "rad", "mass": "kg or kg m^2", "limit": "", "scale": ""}


def shown(name: str) -> str:
    """A name as messages show it: quoted, cut to :data:`SHOWN_NAME` characters when long."""
    return errors.shown(name, SHOWN_NAME)


def read_numbers(
    element: etree._Element,
    attribute: str,
    count: int,
    what: str,
    fail: Fail,
    kind: str = "position",
    nonnegative: bool = False,
) -> list[float]:
    """Read ``count`` finite numbers from an attribute, each within ``RANGES[kind]``.

    Each must also be ``>= 0`` when ``nonnegative``.
    """
    text = element.get(attribute)
    try:
        values = [float(word) for word in text.split()] if text is not None else []
    except ValueError:
        values = []
    written = shown(str(text))
    if len(values) != count:
        raise fail(f"{what} {attribute}={written} is not {count} number(s)", element)
    if not all(math.isfinite(value) for value in values):
        raise fail(f"{what} {attribute}={written} is not finite", element)
    if nonnegative and any(value < 0.0 for value in values):
        raise fail(f"{what} {attribute}={written} is negative", element)
    bound = RANGES[kind]
    if any(abs(value) > bound for value in values):
        low = 0 if nonnegative else -bound
        raise fail(
            f"{what} {attribute}={written} is out of range: each value must be within "
            f"[{low:g}, {bound:g}] {_UNITS[kind]}".rstrip(),
            element,
        )
    return values


def check_origin(parent: etree._Element, what: str, fail: Fail) -> None:
    """Check the ``xyz`` [m] and ``rpy`` [rad] of ``parent``'s ``<origin>``, if it has one."""
    origin = parent.find("origin")
    if origin is not None:
        for attribute, kind in (("xyz", "position"), ("rpy", "angle")):
            if origin.get(attribute) is not None:
                read_numbers(origin, attribute, 3, f"{what} origin", fail, kind)
