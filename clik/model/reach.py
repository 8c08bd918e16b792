r"""How far a frame can reach: a bound checked before a run starts.

For a fixed-base chain, every point of the frame stays within

.. math::

    \rho = \sum_j |{}^{j-1}p_j| + |{}^{j}p_f|
         + \sum_{j\ \text{prismatic}} \max(|q^{min}_j|, |q^{max}_j|)

of the chain's first moving joint (offsets between successive joint origins, the frame's
offset on its joint, and the travel of prismatic joints), whatever the configuration. A
position reference farther than that from the first joint is out of reach: the run is
refused before it starts, with the distance and the reach in the message, rather than
ending in a deadlock that a gain or a trajectory parameter gets the blame for.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from clik.model.robot import Robot


def reach_bound(robot: Robot, frame_id: int) -> tuple[np.ndarray, float, str]:
    """The chain's first moving joint origin [m], the reach bound [m], that joint's name.

    Infinite when the chain has an unbounded prismatic or a free-floating joint.
    """
    model = robot.model
    frame = model.frames[frame_id]
    chain = []
    j = frame.parentJoint
    while j > 0:
        chain.append(j)
        j = model.parents[j]
    if not chain:  # the frame is fixed to the world
        data = model.createData()
        pin.framesForwardKinematics(model, data, robot.q_reference)
        return data.oMf[frame_id].translation.copy(), 0.0, "universe"
    first = chain[-1]
    reach = float(np.linalg.norm(frame.placement.translation))
    for j in chain:
        joint = model.joints[j]
        if j != first:
            reach += float(np.linalg.norm(model.jointPlacements[j].translation))
        if joint.nv > 1 or joint.nq > 2:
            return np.zeros(3), math.inf, model.names[first]
        if joint.shortname().startswith("JointModelP"):
            low = model.lowerPositionLimit[joint.idx_q]
            high = model.upperPositionLimit[joint.idx_q]
            travel = max(abs(float(low)), abs(float(high)))
            if not math.isfinite(travel):
                return np.zeros(3), math.inf, model.names[first]
            reach += travel
    return model.jointPlacements[first].translation.copy(), reach, model.names[first]
