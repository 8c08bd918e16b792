"""Position servos with velocity feed-forward and gravity compensation: docs/method.md (P1).

Each joint clik moves gets one MuJoCo actuator of force

    tau = kp (q_r - q) + kv (qdot_r - qdot)                                      (P1)

on top of MuJoCo's gravity compensation of every body (``gravcomp = 1``): an affine
actuator of gain ``kp`` and bias ``(0, -kp, -kv)`` driven by the control
``u = q_r + (kv / kp) qdot_r`` (:func:`servo_control`); without feed-forward
``u = q_r`` (``qdot_r = 0``: a position servo damped toward rest). The force is limited
to the joint's effort limit when the model states one (``saturated_joints`` of the
report).
"""

from __future__ import annotations

from typing import Any

import numpy as np

KP = 4000.0
"""Default servo stiffness [N m / rad, or N / m for a prismatic joint]."""
KV = 200.0
"""Default servo damping [N m s / rad, or N s / m]."""
TIMESTEP = 1e-3
"""Default (largest) simulation step [s]; a run recorded more finely sets a finer one."""


def servo_control(
    q_r: np.ndarray, qdot_r: np.ndarray, kp: float, kv: float, feedforward: bool
) -> np.ndarray:
    """The actuators' control ``u`` of eq. (P1): ``q_r + (kv / kp) qdot_r`` [rad or m].

    Args:
        q_r: Joint reference (n,) [rad or m].
        qdot_r: Joint velocity reference (n,) [rad/s or m/s].
        kp: Stiffness (> 0).
        kv: Damping (>= 0).
        feedforward: Whether ``qdot_r`` is fed forward (else ``u = q_r``).
    """
    return q_r + (kv / kp) * qdot_r if feedforward else q_r


def add_servos(
    mujoco: Any, spec: Any, joints: list[str], kp: float, kv: float, effort: np.ndarray
) -> None:
    """One servo of eq. (P1) per joint, and gravity compensation on every body.

    Args:
        mujoco: The imported ``mujoco`` module.
        spec: The robot's ``mujoco.MjSpec`` (changed in place).
        joints: The joints to drive, by name (the actuators' order).
        kp: Stiffness.
        kv: Damping.
        effort: Each joint's force limit [N m or N]; 0 or infinite: unlimited.
    """
    for body in spec.bodies:
        body.gravcomp = 1.0
    for name, limit in zip(joints, effort, strict=True):
        actuator = spec.add_actuator(name=f"clik_servo_{name}", target=name)
        actuator.trntype = mujoco.mjtTrn.mjTRN_JOINT
        actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        gain = np.zeros(len(actuator.gainprm))
        gain[0] = kp
        actuator.gainprm = gain
        bias = np.zeros(len(actuator.biasprm))
        bias[:3] = (0.0, -kp, -kv)
        actuator.biasprm = bias
        if np.isfinite(limit) and limit > 0.0:
            actuator.forcelimited = True
            actuator.forcerange = [-float(limit), float(limit)]
