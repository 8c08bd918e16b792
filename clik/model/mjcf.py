"""From a checked MJCF (MuJoCo) model to Pinocchio's models.

:func:`clik.model.mjcf_check.check_mjcf` checks the model and every file it reads and
returns one self-contained document; Pinocchio's MJCF reader reads that document
(written to a private temporary file, its mesh files as checked absolute paths), never
the user's files directly. What clik takes from it:

- **Kinematics**: hinge joints are revolute, slide joints prismatic; ranges in the
  file's angle unit (``<compiler angle>``, degrees by default, as MuJoCo). Pinocchio
  4.1 converts a slide joint's range as if it were an angle in a degree model; the
  range is set back to metres here. MJCF gives no joint velocity limits: runs use
  ``joint_speed.default_velocity`` (warned) unless ``joint_speed.velocity`` gives them.
- **Collision geometry**: a geom is collision geometry unless it has both
  ``contype="0"`` and ``conaffinity="0"`` (those are visual only); a geom of
  ``group`` 3 or more is collision only (Pinocchio's reading). Planes (a scene's
  floor) are dropped: the environment is given as obstacles. Mesh files become
  convex hulls in the collision scene, like a URDF's; an ellipsoid is skipped there
  with a warning (no convex shape for it).
- **Reference configuration**: the ``<key name="home">`` of ``<keyframe>`` if
  there is one (clipped into the limits, warned), else Pinocchio's neutral
  configuration (all zeros) clipped into the limits.
- **Base**: fixed; a root free joint is removed (see
  :class:`~clik.model.mjcf_check.FreeJointWeldedWarning`).
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pinocchio as pin

from clik.errors import InputError, RobotLoadError, native_message
from clik.model.joints import PRISMATIC, joint_kind
from clik.model.loading import check_mesh_extents, clipped_reference
from clik.model.mjcf_check import MjcfDocument, check_mjcf

HOME_KEY = "home"
"""Name of the ``<key>`` used as the reference configuration when the model has one."""


def load_mjcf(
    path: Path, refused: Mapping[str, object] | None = None
) -> tuple[pin.Model, pin.GeometryModel, np.ndarray, MjcfDocument]:
    """Check an MJCF model, then build its kinematic and collision models.

    ``Robot.load(path, lock=...)`` applies (the models are then reduced); its
    ``package_dirs`` is not used (files are relative to the model's folder).

    Args:
        path: The main model file.
        refused: ``Robot.load``'s options an MJCF model does not take, by name
            (``xacro_args``, ``srdf``, a planar or floating ``base``): each must be
            empty or false.

    Returns:
        The model (fixed base), its collision geometry, the reference configuration and
        the checked document (kept by the robot to read its visual geometry).

    Raises:
        InputError: An option in ``refused`` was given.
        RobotLoadError: The model or a file it reads is refused
            (:func:`~clik.model.mjcf_check.check_mjcf`), Pinocchio cannot read it, or it
            has a joint of more than one degree of freedom.

    Warns:
        FreeJointWeldedWarning: The root body's free joint was removed.
        ReferenceClippedWarning: The ``home`` key lies outside the joint ranges.
    """
    for option, value in (refused or {}).items():
        if value:
            raise InputError(option, f"no {option} for an MJCF model ({path})", value)
    document = check_mjcf(path)
    model, collision_model = _read(document, pin.COLLISION)
    _check_joints(model, document)
    check_mesh_extents(path, collision_model)
    return model, collision_model, reference_configuration(model), document


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
        RobotLoadError: Pinocchio cannot read it (a mesh removed since loading, ...).
    """
    visual = _read(document, pin.VISUAL, full_model)[1]
    if reduction is not None:
        reduced_from, joint_ids, q_full = reduction
        _, visual = pin.buildReducedModel(reduced_from, visual, joint_ids, q_full)
    return visual


def reference_configuration(model: pin.Model) -> np.ndarray:
    """The ``home`` key if the model has one, else neutral; clipped into the limits."""
    if HOME_KEY in model.referenceConfigurations:
        q = np.array(model.referenceConfigurations[HOME_KEY], dtype=float)
        return clipped_reference(model, q, HOME_KEY)
    return np.clip(pin.neutral(model), model.lowerPositionLimit, model.upperPositionLimit)


def _read(
    document: MjcfDocument, kind: pin.GeometryType, model: pin.Model | None = None
) -> tuple[pin.Model, pin.GeometryModel]:
    """Pinocchio's model (unless given) and geometry of ``kind``, planes dropped."""
    what = "model" if model is None else "visual geometry"
    with tempfile.TemporaryDirectory(prefix="clik-mjcf-") as folder:
        file = Path(folder, "model.xml")
        file.write_text(document.text, encoding="utf-8")
        try:
            if model is None:
                model = pin.buildModelFromMJCF(str(file))
                _metres(model, document)
            geometry = pin.buildGeomFromMJCF(model, str(file), kind)
        except (ValueError, RuntimeError, KeyError, IndexError) as error:
            problem = f"Pinocchio cannot read the {what}: {native_message(error)}"
            raise RobotLoadError(document.path, problem) from None
    return model, _without_planes(geometry)


def _metres(model: pin.Model, document: MjcfDocument) -> None:
    """Undo Pinocchio 4.1's degree conversion of slide joint ranges (they are metres)."""
    if not document.degrees:
        return
    lower, upper = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    for joint in model.joints[1:]:
        if joint_kind(joint) == PRISMATIC:
            i = joint.idx_q
            lower[i], upper[i] = np.degrees(lower[i]), np.degrees(upper[i])
    model.lowerPositionLimit, model.upperPositionLimit = lower, upper


def _without_planes(geometry: pin.GeometryModel) -> pin.GeometryModel:
    """The geometry without its planes (coal half-spaces: a floor, not part of the robot)."""
    kept = pin.GeometryModel()
    for go in geometry.geometryObjects:
        if type(go.geometry).__name__ not in ("Halfspace", "Plane"):
            kept.addGeometryObject(go)
    return kept


def _check_joints(model: pin.Model, document: MjcfDocument) -> None:
    """Every joint one degree of freedom, finite placements, ``lower <= upper``."""
    for name, joint in zip(model.names[1:], model.joints[1:], strict=True):
        if joint.nq != 1 or joint.nv != 1:
            raise RobotLoadError(
                document.path,
                f"joint {str(name)!r} has {joint.nv} degrees of freedom "
                f"({joint.shortname()}): clik loads hinge and slide joints",
            )
        low = float(model.lowerPositionLimit[joint.idx_q])
        high = float(model.upperPositionLimit[joint.idx_q])
        if low > high:
            raise RobotLoadError(
                document.path, f"joint {str(name)!r} has range [{low:g}, {high:g}]: lower > upper"
            )
    for name, placement in zip(model.names, model.jointPlacements, strict=True):
        if not all(math.isfinite(v) for v in np.ravel(placement.homogeneous)):
            raise RobotLoadError(document.path, f"joint {str(name)!r} has a non-finite placement")
