"""What a robot's model was when it was loaded, and the check that it is still so.

Everything clik builds on a :class:`~clik.model.robot.Robot` is sized by its Pinocchio
model: the robot's data, limits and reference configuration, tasks, constraint sets
(their collision scene), the compiled engine's solvers and runs. A model changed
afterwards (``robot.model.addJoint(...)``, a joint replaced) would have them read and
write past their arrays, so every task, set, run and solve checks it first:
:func:`model_signature` (four sizes, about 0.5 us: a solve's check) and
:func:`joint_signature` (every joint, 20 us for the Panda: a run's check).
"""

from __future__ import annotations

import pinocchio as pin

from clik.errors import InputError

Signature = tuple[int, int, int, int]
JointSignature = tuple[tuple[str, int, int, int, int], ...]


def model_signature(model: pin.Model) -> Signature:
    """``(nq, nv, njoints, nframes)``: what a change of the model's size changes."""
    return (model.nq, model.nv, model.njoints, model.nframes)


def joint_signature(model: pin.Model) -> JointSignature:
    """Each joint's kind, configuration index and size, velocity index and size."""
    return tuple((j.shortname(), j.idx_q, j.nq, j.idx_v, j.nv) for j in model.joints)


def check_unchanged(
    model: pin.Model, name: str, signature: Signature, joints: JointSignature, full: bool
) -> None:
    """Refuse ``model`` unless it still has ``signature`` (and, when ``full``, ``joints``).

    Args:
        model: The robot's model now.
        name: The robot's name (in the message).
        signature: :func:`model_signature` when the robot was loaded.
        joints: :func:`joint_signature` when the robot was loaded.
        full: Also compare every joint.

    Raises:
        InputError: ``robot.model`` changed: the message gives the sizes it was loaded
            with and what changed, and says to load a new robot.
    """
    now = model_signature(model)
    if now == signature and (not full or joint_signature(model) == joints):
        return
    if now != signature:
        changed = "a model of " + _sizes(now)
    else:
        new = joint_signature(model)
        j = next(i for i, (a, b) in enumerate(zip(new, joints, strict=True)) if a != b)
        changed = f"joint {j} replaced: {new[j][0]} at idx_q {new[j][1]} (was {joints[j][0]})"
    raise InputError(
        "robot.model",
        f"the model {name!r} was loaded with ({_sizes(signature)}): it changed since, and "
        "everything built on it (its data, limits, tasks, constraint sets, compiled "
        "solvers) is sized by it; load a new Robot for a changed model",
        changed,
    )


def _sizes(signature: Signature) -> str:
    """A model signature in words."""
    nq, nv, njoints, nframes = signature
    return f"nq = {nq}, nv = {nv}, {njoints - 1} joints, {nframes} frames"
