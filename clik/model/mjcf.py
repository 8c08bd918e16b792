"""From a checked MJCF (MuJoCo) model to Pinocchio's models, through MuJoCo's compiler.

:func:`clik.model.mjcf_check.check_mjcf` checks the model and every file it reads and
returns one self-contained document; MuJoCo's compiler (``mujoco.MjModel``) compiles
it exactly as MuJoCo does (default classes, w-first quaternions, ``eulerseq``,
``fromto``, mesh scales, joint ``ref``, ``<compiler>`` settings), and clik builds its
models from the compiled numbers, never from its own reading of the XML:

- **Kinematics** (:mod:`clik.model.mjcf_compiled`): hinge joints are revolute, slide
  joints prismatic, clik's joint value is MuJoCo's ``qpos``; a body with several joints
  is a chain of one-degree-of-freedom joints; ranges as MuJoCo compiled them (radians,
  metres). MJCF gives no joint velocity limits: runs use
  ``joint_speed.default_velocity`` (warned) unless ``joint_speed.velocity`` gives them.
  A ball joint is refused, naming its body.
- **Collision geometry** (:mod:`clik.model.mjcf_geometry`): a geom is collision
  geometry unless it has both ``contype="0"`` and ``conaffinity="0"``; the visual
  geometry is the geoms of ``group`` 0 to 2. Each sits at MuJoCo's compiled pose with
  MuJoCo's sizes, a mesh as MuJoCo compiled it (scaled, centred). Planes (a scene's
  floor) are dropped: the environment is given as obstacles. Mesh geoms become convex
  hulls in the collision scene (as MuJoCo collides them); an ellipsoid is skipped there
  with a warning (no convex shape for it).
- **Reference configuration**: the ``<key name="home">`` of ``<keyframe>`` if
  there is one (clipped into the limits, warned), else MuJoCo's ``qpos0`` (each
  joint's ``ref``, zero by default) clipped into the limits.
- **Base** (``Robot.load(..., base=...)``, :mod:`clik.model.base`): the root body's
  free joint (``<freejoint/>``) is removed from the document, and so is its pose;
  clik places the root body itself (:func:`root_offset`):

  - ``"fixed"``: welded at the pose the file gives the root body (MuJoCo's ``qpos0``),
    the free joint warned (:class:`~clik.model.mjcf_root.FreeJointWeldedWarning`),
    the keys' free-joint values dropped;
  - ``"floating"``: Pinocchio's free-flyer root joint (named ``root_joint``) *is* the
    root body's pose in the world, as MuJoCo's free joint: its reference is the
    ``home`` key's 7 values (MuJoCo's ``x y z qw qx qy qz`` turned into Pinocchio's
    ``x y z qx qy qz qw``), else the file's pose of the root body;
  - ``"planar"``: a planar root joint carrying that pose's ``x``, ``y`` and yaw; its
    height, roll and pitch stay fixed between the root joint and the root body.

  Forward kinematics at the reference then equals MuJoCo's at the ``home`` key (or
  ``qpos0``): ``tests/model/test_mjcf_bases.py``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pinocchio as pin

from clik.errors import InputError, RobotLoadError
from clik.model.base import (
    FIXED,
    FLOATING,
    PLANAR,
    planar_from_free_flyer,
)
from clik.model.loading import check_mesh_extents, clipped_reference
from clik.model.mjcf_check import check_mjcf
from clik.model.mjcf_compiled import build_model, compile_text, se3
from clik.model.mjcf_geometry import build_geometry
from clik.model.mjcf_root import FREE_JOINT_VALUES, HOME_KEY, MjcfDocument


def load_mjcf(
    path: Path, refused: Mapping[str, object] | None = None, base: str = FIXED
) -> tuple[pin.Model, pin.GeometryModel, np.ndarray, MjcfDocument]:
    """Check an MJCF model, then build its kinematic and collision models.

    ``Robot.load(path, lock=...)`` applies (the models are then reduced); its
    ``package_dirs`` is not used (files are relative to the model's folder).

    Args:
        path: The main model file.
        refused: ``Robot.load``'s options an MJCF model does not take, by name
            (``xacro_args``, ``srdf``): each must be empty or false.
        base: ``"fixed"``, ``"planar"`` or ``"floating"`` (see the module's docstring).

    Returns:
        The model (its root joint first, for a planar or floating base), its collision
        geometry, the reference configuration and the checked document (kept by the
        robot to read its visual geometry).

    Raises:
        InputError: An option in ``refused`` was given.
        RobotLoadError: The model or a file it reads is refused
            (:func:`~clik.model.mjcf_check.check_mjcf`), MuJoCo's compiler refuses it
            (its message, at the file and line of the element), it has a ball joint, or
            its ``home`` key does not hold one value per joint.

    Warns:
        FreeJointWeldedWarning: With a fixed base, the root body's free joint was removed.
        ReferenceClippedWarning: The ``home`` key lies outside the joint ranges.
    """
    for option, value in (refused or {}).items():
        if value:
            raise InputError(option, f"no {option} for an MJCF model ({path})", value)
    document = check_mjcf(path, base)
    model, collision_model = _read(document, pin.COLLISION)
    _check_joints(model, document)
    check_mesh_extents(path, collision_model)
    return model, collision_model, reference_configuration(model, document), document


def mjcf_visual_model(
    document: MjcfDocument,
    full_model: pin.Model,
    reduction: tuple[pin.Model, list[int], np.ndarray] | None = None,
) -> pin.GeometryModel:
    """The visual geometry of a checked document, reduced like the robot's model.

    Args:
        document: The checked document (:attr:`Robot.mjcf <clik.model.robot.Robot.mjcf>`).
        full_model: The model before any joint was locked.
        reduction: ``(full model, locked joint ids, full configuration)`` of a robot
            with locked joints, or None.

    Raises:
        RobotLoadError: MuJoCo's compiler cannot read it (a mesh removed since loading, ...).
    """
    visual = _read(document, pin.VISUAL, full_model)[1]
    if reduction is not None:
        reduced_from, joint_ids, q_full = reduction
        _, visual = pin.buildReducedModel(reduced_from, visual, joint_ids, q_full)
    return visual


def reference_configuration(model: pin.Model, document: MjcfDocument) -> np.ndarray:
    """The ``home`` key if the model has one, else MuJoCo's ``qpos0``; clipped into the limits.

    A planar or floating base starts at :func:`base_pose` (the ``home`` key's free joint,
    else the file's pose of the root body): floating, Pinocchio's ``x, y, z, q_x, q_y,
    q_z, q_w``; planar, ``x, y, cos, sin`` of its yaw.

    Raises:
        RobotLoadError: The ``home`` key does not give one value per joint.
    """
    if document.base == FIXED:
        if HOME_KEY in model.referenceConfigurations:
            q = np.array(model.referenceConfigurations[HOME_KEY], dtype=float)
            return clipped_reference(model, q, HOME_KEY)
        return np.clip(_qpos0(model, document), model.lowerPositionLimit, model.upperPositionLimit)
    n_base = model.joints[1].nq
    pose = np.asarray(pin.SE3ToXYZQUAT(base_pose(document)), dtype=float)
    q = pin.neutral(model)
    q[:n_base] = planar_from_free_flyer(pose) if document.base == PLANAR else pose
    if document.home_joints is None:
        low, high = model.lowerPositionLimit[n_base:], model.upperPositionLimit[n_base:]
        q[n_base:] = np.clip(_qpos0(model, document)[n_base:], low, high)
        return q
    if len(document.home_joints) != model.nq - n_base:
        after = f" after the free joint's {FREE_JOINT_VALUES}" if document.welded else ""
        raise RobotLoadError(
            document.path,
            f"the key {HOME_KEY!r} has {len(document.home_joints)} qpos values for the joints"
            f"{after}: expected {model.nq - n_base}, one per joint",
        )
    q[n_base:] = document.home_joints
    return clipped_reference(model, q, HOME_KEY)


def _qpos0(model: pin.Model, document: MjcfDocument) -> np.ndarray:
    """MuJoCo's ``qpos0`` of the joints (their ``ref``) after the base's values (neutral)."""
    q = pin.neutral(model)
    if document.qpos0 is not None:
        q[model.nq - len(document.qpos0) :] = document.qpos0
    return q


def root_placement(document: MjcfDocument) -> pin.SE3:
    """The pose the file gives its root body in the world (identity when it gives none).

    Compiled by MuJoCo from :attr:`MjcfDocument.root_probe
    <clik.model.mjcf_root.MjcfDocument.root_probe>` (a body with the root body's pose
    attributes), so every orientation form (``quat``, ``euler`` with the file's
    ``eulerseq``, ``axisangle``, ``xyaxes``, ``zaxis``) and the file's angle unit are read
    as MuJoCo reads them.

    Raises:
        RobotLoadError: MuJoCo's compiler refuses it.
    """
    if document.root_probe is None:
        return pin.SE3.Identity()
    probe = compile_text(document.root_probe, document.path)
    placement = se3(probe.body_pos[1], probe.body_quat[1])
    if not all(math.isfinite(v) for v in np.ravel(placement.homogeneous)):
        raise RobotLoadError(document.path, "the root body's pose is not finite")
    return placement


def base_pose(document: MjcfDocument) -> pin.SE3:
    """The root body's pose in the world at the reference configuration.

    The ``home`` key's free-joint values when there are some (MuJoCo's ``x y z qw qx qy
    qz``, the quaternion normalised as MuJoCo does), else :func:`root_placement` (MuJoCo's
    ``qpos0`` of a free joint is the body's pose in the file).

    Raises:
        RobotLoadError: The key's quaternion is zero.
    """
    if document.home_base is None:
        return root_placement(document)
    x, y, z, w, qx, qy, qz = document.home_base
    norm = math.sqrt(w * w + qx * qx + qy * qy + qz * qz)
    if not norm > 0.0:
        raise RobotLoadError(
            document.path, f"the key {HOME_KEY!r} gives the free joint a zero quaternion"
        )
    rotation = pin.Quaternion(w / norm, qx / norm, qy / norm, qz / norm).matrix()
    return pin.SE3(rotation, np.array([x, y, z], dtype=float))


def root_offset(document: MjcfDocument) -> pin.SE3:
    """Where the root body goes after the base's root joint (the world for a fixed base).

    Fixed: :func:`root_placement`. Floating: the identity (the free-flyer's configuration
    is the root body's pose). Planar: the part of :func:`base_pose` the planar joint does
    not carry, its height, roll and pitch: ``planar(x, y, yaw)^-1 pose``.
    """
    if document.base == FIXED:
        return root_placement(document)
    if document.base == FLOATING:
        return pin.SE3.Identity()
    pose = base_pose(document)
    x, y, cos, sin = planar_from_free_flyer(np.asarray(pin.SE3ToXYZQUAT(pose)))
    yaw = np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]])
    return pin.SE3(yaw, np.array([x, y, 0.0])).actInv(pose)


def _read(
    document: MjcfDocument, kind: pin.GeometryType, model: pin.Model | None = None
) -> tuple[pin.Model, pin.GeometryModel]:
    """The model built from MuJoCo's compiled one (unless given) and its geometry of ``kind``."""
    compiled = compile_text(document.text, document.path, document.lines)
    if model is None:
        model = build_model(compiled, document, root_offset(document))
        document.qpos0 = [float(v) for v in compiled.qpos0]
    return model, build_geometry(compiled, model, kind)


def _check_joints(model: pin.Model, document: MjcfDocument) -> None:
    """Finite joint placements (MuJoCo's compiler checked the rest: ranges, axes)."""
    for name, placement in zip(model.names, model.jointPlacements, strict=True):
        if not all(math.isfinite(v) for v in np.ravel(placement.homogeneous)):
            raise RobotLoadError(document.path, f"joint {str(name)!r} has a non-finite placement")
