"""Checks of joint-range thresholds ``d_q``: degrees read as radians, and the range cap.

A scenario's ``[constraints.joint_limits] threshold`` is in radians unless the table says
``unit = "deg"``; ``threshold = 5.0`` meant as 5 deg is 286 deg. One above a full turn
(:data:`MAX_ANGLE_THRESHOLD`) is refused; any threshold is capped at a quarter of its
joint's range (:data:`~clik.constraints.joint_limits.RANGE_FRACTION`), and a cap is said
(:class:`ThresholdCapWarning`), with a hint to write ``unit = "deg"`` when the number
looks like degrees (:data:`LOOKS_LIKE_DEGREES`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np

from clik.errors import ClikWarning, InputError, user_stacklevel
from clik.model.joints import PRISMATIC, REVOLUTE

MAX_ANGLE_THRESHOLD = 2.0 * math.pi
"""Largest revolute threshold [rad]: one above a full turn is refused (degrees read as rad)."""
LOOKS_LIKE_DEGREES = 1.0
"""A revolute threshold from this value [rad] (57 deg) on is probably written in degrees."""


class ThresholdCapWarning(ClikWarning):
    """A joint-range threshold was capped at a quarter of its joint's range."""


def degrees_hint(threshold: float) -> str:
    """A hint to write ``unit = "deg"`` for a revolute threshold [rad] that looks like degrees."""
    if threshold >= LOOKS_LIKE_DEGREES:
        return (
            f'; {threshold:g} looks like degrees: write unit = "deg" in the scenario '
            "(Python: math.radians)"
        )
    return ""


def check_angles(thr: np.ndarray, kinds: Sequence[str]) -> None:
    """Refuse a revolute threshold above :data:`MAX_ANGLE_THRESHOLD`.

    Args:
        thr: The threshold of each limited joint [rad or m].
        kinds: ``"revolute"`` or ``"prismatic"`` per limited joint.

    Raises:
        InputError: ``constraints.joint_limits.threshold``, with the degrees hint.
    """
    revolute = np.array([k == REVOLUTE for k in kinds], dtype=bool)
    if revolute.any() and thr[revolute].max() > MAX_ANGLE_THRESHOLD:
        asked = float(thr[revolute].max())
        raise InputError(
            "constraints.joint_limits.threshold",
            f"an angle [rad] of at most 2 pi{degrees_hint(asked)}",
            asked,
        )


def warn_capped(
    names: Sequence[str],
    kinds: Sequence[str],
    asked: np.ndarray,
    applied: np.ndarray,
    prismatic: bool,
) -> None:
    """Say which joints' thresholds were capped (asked -> applied), one warning per kind.

    Args:
        names: The limited joints.
        kinds: ``"revolute"`` or ``"prismatic"`` per limited joint.
        asked: The thresholds asked for [rad or m].
        applied: The thresholds after the cap [rad or m].
        prismatic: Whether a ``prismatic_threshold`` was given (else the prismatic
            joints' threshold is the revolute one read as metres, capped by design).

    Warns:
        ThresholdCapWarning: Names the key, each capped joint, asked and applied values.
    """
    for kind, key, unit in (
        (REVOLUTE, "threshold", "rad"),
        (PRISMATIC, "prismatic_threshold", "m"),
    ):
        if kind == PRISMATIC and not prismatic:
            continue
        capped = [
            k for k in range(len(names)) if kinds[k] == kind and applied[k] < asked[k] * (1 - 1e-12)
        ]
        if not capped:
            continue
        joints = ", ".join(f"{names[k]} {asked[k]:.4g} -> {applied[k]:.4g} {unit}" for k in capped)
        hint = degrees_hint(float(asked[capped].max())) if kind == REVOLUTE else ""
        warnings.warn(
            f"constraints.joint_limits.{key}: capped at a quarter of the joint's range "
            f"({joints}){hint}",
            ThresholdCapWarning,
            stacklevel=user_stacklevel(),
        )
