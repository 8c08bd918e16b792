"""A fixed-base robot's joints one value each, by name: what drivers and simulators use.

clik's configuration ``q`` holds an unbounded revolute joint as a (cos, sin) pair
(Pinocchio's ``JointModelRUBZ`` and kin); a robot driver, MuJoCo and ROS's
``JointState`` hold one angle per joint. :class:`JointOrder` maps between the two, in
clik's velocity order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clik.errors import InputError
from clik.model.robot import Robot


@dataclass(frozen=True)
class JointOrder:
    """clik's joints of one degree of freedom each, in velocity order.

    Attributes:
        names: The joints' names (n).
        idx_q: Each joint's first entry in ``q``.
        idx_v: Each joint's entry in ``qdot``.
        angle_pairs: Whether each joint is held in ``q`` as a (cos, sin) pair.
    """

    names: list[str]
    idx_q: np.ndarray
    idx_v: np.ndarray
    angle_pairs: np.ndarray

    @classmethod
    def of(cls, robot: Robot, who: str) -> JointOrder:
        """The robot's joints, one value each.

        A planar or floating base, or a joint of several degrees of freedom, is refused
        (``who`` says what needs one value per joint).

        Raises:
            InputError: A base, or a joint of several degrees of freedom, named.
        """
        if robot.base != "fixed":
            raise InputError("robot.base", f"a fixed-base robot ({who})", robot.base)
        model = robot.model
        names, iq, iv, pairs = [], [], [], []
        for j in range(1, model.njoints):
            joint = model.joints[j]
            if joint.nv == 0:
                continue
            if joint.nv != 1 or joint.nq not in (1, 2):
                raise InputError(
                    f"robot.joints.{model.names[j]}",
                    f"one degree of freedom (revolute, continuous or prismatic; {who})",
                    joint.shortname(),
                )
            names.append(str(model.names[j]))
            iq.append(joint.idx_q)
            iv.append(joint.idx_v)
            pairs.append(joint.nq == 2)
        return cls(
            names, np.array(iq, dtype=int), np.array(iv, dtype=int), np.array(pairs, dtype=bool)
        )

    def angles(self, q: np.ndarray) -> np.ndarray:
        """Joint values [rad or m] (N, n) of configurations (N, nq), unwrapped in time."""
        q = np.atleast_2d(q)
        out = q[:, self.idx_q].copy()
        for j in np.flatnonzero(self.angle_pairs):
            i = self.idx_q[j]
            out[:, j] = np.unwrap(np.arctan2(q[:, i + 1], q[:, i]))
        return out

    def configuration(self, q_base: np.ndarray, values: np.ndarray) -> np.ndarray:
        """A configuration (nq,): ``q_base`` with the joints set to ``values`` (n,)."""
        q = np.array(q_base, dtype=float, copy=True)
        for j, i in enumerate(self.idx_q):
            if self.angle_pairs[j]:
                q[i], q[i + 1] = np.cos(values[j]), np.sin(values[j])
            else:
                q[i] = values[j]
        return q
