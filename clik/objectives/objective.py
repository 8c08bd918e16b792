"""A null-space objective of eq. (5): its kind, gain and the level it acts below."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from clik.errors import InputError
from clik.model.joints import PRISMATIC, REVOLUTE

if TYPE_CHECKING:
    from clik.model.robot import Robot

ObjectiveKind = Literal["joint_centering", "manipulability", "posture"]
OBJECTIVE_KINDS: tuple[str, ...] = ("joint_centering", "manipulability", "posture")
JOINT_CENTERING, MANIPULABILITY, POSTURE = OBJECTIVE_KINDS


class Objective:
    """A criterion whose gradient moves the arm in the null space of the tasks, eq. (5).

    Args:
        kind: ``"joint_centering"`` (away from the joint limits, the paper's reference
            [3]), ``"manipulability"`` (of the primary task, (D1)) or ``"posture"``
            (toward ``posture``); see :mod:`clik.objectives.gradients`.
        gain: ``k`` > 0: [rad^2/s] for joint centring, [1/s] for a posture, [rad/s per
            unit of w] for manipulability.
        priority: The level below which it acts (it moves in the null space of the
            constraints and of every level of priority up to this one); None: below
            the lowest level.
        posture: The posture (nq,) of a ``"posture"`` objective; None: the run's start.

    Raises:
        InputError: A bad field (named).

    Objectives need law (10) (``"pseudoinverse"``): the others have no null space.
    """

    def __init__(
        self,
        kind: ObjectiveKind,
        gain: float = 1.0,
        priority: int | None = None,
        posture: np.ndarray | None = None,
    ) -> None:
        if kind not in OBJECTIVE_KINDS:
            raise InputError("objectives.kind", " or ".join(repr(k) for k in OBJECTIVE_KINDS), kind)
        try:
            k = float(gain)
        except (TypeError, ValueError):
            raise InputError("objectives.gain", "a positive number", gain) from None
        if not math.isfinite(k) or k <= 0.0:
            raise InputError("objectives.gain", "a positive finite number", gain)
        if priority is not None and (
            isinstance(priority, bool) or not isinstance(priority, int | np.integer) or priority < 1
        ):
            raise InputError(
                "objectives.priority", "an integer >= 1, or None (the lowest)", priority
            )
        if posture is not None and kind != POSTURE:
            raise InputError("objectives.posture", "a posture only for kind 'posture'", kind)
        self.kind: ObjectiveKind = kind
        self.gain = k
        self.priority = None if priority is None else int(priority)
        self.posture = None if posture is None else np.array(posture, dtype=float)

    def __repr__(self) -> str:
        return f"Objective({self.kind!r}, gain={self.gain:g}, priority={self.priority})"

    def level(self, priorities: list[int]) -> int:
        """The level index (1-based) it acts below, among the run's ``priorities``."""
        if self.priority is None:
            return len(priorities)
        below = [i + 1 for i, p in enumerate(priorities) if p <= self.priority]
        return below[-1] if below else 1

    def setup(self, robot: Robot, q0: np.ndarray) -> dict[str, Any]:
        """What its gradient reads, for a run from ``q0`` (checked against the robot).

        Raises:
            InputError: A posture of the wrong size or outside the limits, or no joint
                with finite limits to centre.
        """
        if self.kind == JOINT_CENTERING:
            return centering_setup(robot)
        if self.kind == POSTURE:
            q_ref = (
                q0
                if self.posture is None
                else robot.check_configuration(self.posture, "objectives.posture")
            )
            return {"q_ref": np.array(q_ref, dtype=float)}
        return {}


def centering_setup(robot: Robot) -> dict[str, Any]:
    """Joints with finite limits: indices, middles ``a`` and half ranges ``h`` [rad or m]."""
    idx_q, idx_v, lo, hi = [], [], [], []
    kinds = robot.joint_kinds
    for name, joint in zip(robot.joint_names, robot.model.joints[1:], strict=True):
        if kinds[name] not in (REVOLUTE, PRISMATIC):
            continue
        a, b = (
            robot.model.lowerPositionLimit[joint.idx_q],
            robot.model.upperPositionLimit[joint.idx_q],
        )
        if math.isfinite(a) and math.isfinite(b) and b > a:
            idx_q.append(joint.idx_q)
            idx_v.append(joint.idx_v)
            lo.append(a)
            hi.append(b)
    if not idx_q:
        raise InputError("objectives.kind", "a robot with joint limits for 'joint_centering'")
    low, high = np.array(lo), np.array(hi)
    return {
        "idx_q": np.array(idx_q, dtype=np.intp), "idx_v": np.array(idx_v, dtype=np.intp),
        "center": 0.5 * (low + high), "half_range": 0.5 * (high - low),
    }  # fmt: skip
