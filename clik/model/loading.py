"""From a checked URDF to Pinocchio's models: kinematics, collision and visual geometry.

Every URDF has gone through :func:`clik.model.urdf_check.check_urdf` before Pinocchio
reads it here. Meshes are bounded once loaded (the formats the cheap checks
cannot read), the reference configuration is the SRDF's posture or neutral,
clipped into the limits, and the visual model is read on first use: meshes for
display are slow to read (about 0.5 s for the Panda) and the kinematics never
needs them.
"""

from __future__ import annotations

import hashlib
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
from lxml import etree

from clik.errors import ClikWarning, RobotLoadError, native_message, user_stacklevel
from clik.model.base import BASE_JOINT, root_joint
from clik.model.joints import PRISMATIC, REVOLUTE, joint_kind
from clik.model.mesh_check import vertex_problem
from clik.model.srdf import group_state_configuration, read_group_states
from clik.model.urdf_check import parse_xml
from clik.model.urdf_numbers import shown
from clik.model.visual_meshes import MissingVisual


class ReferenceClippedWarning(ClikWarning):
    """The robot's own reference configuration lay outside its limits and was clipped.

    Attributes:
        joints: Joint name -> (reference value, lower limit, upper limit) [rad or m].
    """

    def __init__(self, message: str, joints: dict[str, tuple[float, float, float]]) -> None:
        super().__init__(message)
        self.joints = joints


def build_models(
    urdf: Path, package_dirs: list[str], text: str | None, base: str = "fixed"
) -> tuple[pin.Model, pin.GeometryModel]:
    """Pinocchio's model and collision model of the file ``urdf``, or of ``text``.

    Args:
        urdf: The URDF file (named in errors).
        package_dirs: Folders for ``package://`` and relative mesh files.
        text: The URDF expanded from the xacro file ``urdf``, or None to read ``urdf``.
        base: ``"fixed"``, ``"planar"`` or ``"floating"``: the root joint
            (:func:`clik.model.base.root_joint`, named
            :data:`~clik.model.base.BASE_JOINT`) Pinocchio puts between the world and
            the root link; the collision model is built on that model.

    Raises:
        RobotLoadError: Pinocchio refuses the description.
    """
    root = root_joint(base)
    rooted = {} if root is None else {"root_joint": root, "root_joint_name": BASE_JOINT}
    try:
        if text is None:
            model, collision_model = pin.buildModelsFromUrdf(
                str(urdf), package_dirs=package_dirs, geometry_types=[pin.COLLISION], **rooted
            )
        else:
            model = (
                pin.buildModelFromXML(text)
                if root is None
                else pin.buildModelFromXML(text, root, BASE_JOINT)
            )
            collision_model = pin.buildGeomFromUrdfString(
                model, text, pin.COLLISION, package_dirs=package_dirs
            )
    except (ValueError, RuntimeError) as error:
        problem = f"Pinocchio cannot build the model: {native_message(error)}"
        raise RobotLoadError(urdf, problem) from None
    return model, collision_model


def check_mesh_extents(urdf: Path, collision_model: pin.GeometryModel) -> None:
    """Refuse a collision mesh whose scaled vertices leave the accepted range.

    The cheap checks (:func:`clik.model.urdf_check.check_urdf`) bound a binary STL's
    vertices from the file; other formats are bounded here, after loading and
    before any convex hull is built from them.

    Raises:
        RobotLoadError: A mesh's vertices are not finite or beyond
            :data:`~clik.model.mesh_check.MAX_COORDINATE` [m] from its origin.
    """
    for geometry_object in collision_model.geometryObjects:
        vertices = getattr(geometry_object.geometry, "vertices", None)
        if not callable(vertices):
            continue  # a primitive shape: its sizes were checked in the URDF
        problem = vertex_problem(np.asarray(vertices()))
        if problem is not None:
            mesh = geometry_object.meshPath or geometry_object.name
            raise RobotLoadError(
                urdf, f"collision geometry {geometry_object.name!r} ({mesh}): {problem}"
            )


def digest(path: Path) -> str | None:
    """SHA-256 of a file's bytes, or None when it cannot be read."""
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def reference_configuration(model: pin.Model, srdf: Path | None, posture: str | None) -> np.ndarray:
    """The SRDF's reference posture if there is one, else neutral clipped into the limits.

    The posture is the SRDF's group state ``posture``
    (:func:`clik.model.srdf.group_state_configuration`, from Pinocchio's neutral
    configuration): a floating base's ``root_joint`` values are the planar base's x, y
    and yaw, and are skipped by a fixed base.
    """
    if srdf is not None and posture is not None:
        states = read_group_states(srdf)
        if posture in states:  # a fixed base skips the state's root_joint values
            neutral = pin.neutral(model)
            state = states[posture]
            q = group_state_configuration(model, neutral, state, {BASE_JOINT}, "q_reference")
            return clipped_reference(model, q, posture)
    q = pin.neutral(model)
    return np.clip(q, model.lowerPositionLimit, model.upperPositionLimit)


def clipped_reference(model: pin.Model, q: np.ndarray, posture: str) -> np.ndarray:
    """``q`` with every revolute and prismatic joint clipped into its limits (warned).

    Some example-robot-data robots (kinova, simple_humanoid, alex_psyonic_hands) ship a
    reference posture outside their own URDF limits; the nearest configuration inside
    them is the start they can be in.

    Warns:
        ReferenceClippedWarning: Some joints were clipped; it names each one, its value
            and its limits.
    """
    clipped: dict[str, tuple[float, float, float]] = {}
    for name, joint in zip(model.names[1:], model.joints[1:], strict=True):
        if joint_kind(joint) not in (REVOLUTE, PRISMATIC):
            continue
        i = joint.idx_q
        low, high = float(model.lowerPositionLimit[i]), float(model.upperPositionLimit[i])
        value = float(q[i])
        if low <= high and not low <= value <= high:
            q[i] = min(max(value, low), high)
            clipped[str(name)] = (value, low, high)
    if clipped:
        listed = "; ".join(
            f"{n!r} = {v:.6g} clipped into [{lo:.6g}, {hi:.6g}]"
            for n, (v, lo, hi) in clipped.items()
        )
        warnings.warn(
            ReferenceClippedWarning(
                f"the reference configuration {posture!r} lies outside the robot's own joint "
                f"limits; clipped into them: {listed}",
                clipped,
            ),
            stacklevel=user_stacklevel(),
        )
    return q


def read_visual_model(
    path: Path,
    source_digest: str | None,
    urdf_text: str | None,
    full_model: pin.Model,
    package_dirs: list[str],
    reduction: tuple[pin.Model, list[int], np.ndarray] | None,
    missing_visuals: tuple[MissingVisual, ...] = (),
) -> pin.GeometryModel:
    """The visual geometry of the URDF ``path``, reduced like the robot's model.

    Args:
        path: The URDF file (or the xacro file ``urdf_text`` was expanded from).
        source_digest: SHA-256 of the file as checked at loading, or None (not compared).
        urdf_text: The expanded xacro text, read instead of ``path``; or None.
        full_model: The model before any joint was locked.
        package_dirs: Folders for ``package://`` and relative mesh files.
        reduction: ``(full model, locked joint ids, full configuration)`` of a robot
            with locked joints, or None.
        missing_visuals: ``<visual>`` elements whose meshes were missing at loading
            (:func:`~clik.model.visual_meshes.missing_visuals`): left out of the text
            Pinocchio reads.

    Raises:
        RobotLoadError: The URDF was removed or changed since it was checked, or its
            visual meshes cannot be read.
    """
    if source_digest is not None and digest(path) != source_digest:
        raise RobotLoadError(
            path,
            "the file was removed or changed since the robot was loaded "
            "(its visual geometry is read on first use); load the robot again",
        )
    if missing_visuals:  # Pinocchio would throw on them (clik.model.visual_meshes)
        data = urdf_text.encode("utf-8") if urdf_text is not None else _read_checked(path)
        if urdf_text is None and source_digest not in (None, hashlib.sha256(data).hexdigest()):
            raise RobotLoadError(path, "the file changed since the robot was loaded; load it again")
        urdf_text = without_visuals(path, data, missing_visuals)
    try:
        if urdf_text is not None:
            visual = pin.buildGeomFromUrdfString(
                full_model, urdf_text, pin.VISUAL, package_dirs=package_dirs
            )
        else:
            visual = pin.buildGeomFromUrdf(
                full_model, str(path), pin.VISUAL, package_dirs=package_dirs
            )
    except (ValueError, RuntimeError) as error:
        problem = f"Pinocchio cannot read the visual geometry: {native_message(error)}"
        raise RobotLoadError(path, problem) from None
    if reduction is not None:
        reduced_from, joint_ids, q_full = reduction
        _, visual = pin.buildReducedModel(reduced_from, visual, joint_ids, q_full)
    return visual


def _read_checked(path: Path) -> bytes:
    """The bytes of the URDF ``path`` (read again for its visual geometry)."""
    try:
        return path.read_bytes()
    except OSError as error:
        raise RobotLoadError(path, f"cannot be read again ({error.strerror})") from None


def without_visuals(path: Path, data: bytes, missing: tuple[MissingVisual, ...]) -> str:
    """The URDF ``data`` without the ``<visual>`` elements in ``missing``.

    Args:
        path: The URDF file (named in errors).
        data: Its bytes, as they were checked at loading (same elements, same order).
        missing: The elements to leave out (:func:`missing_visuals` of the checked tree).

    Raises:
        RobotLoadError: ``data`` is not a URDF holding those elements (see
            :func:`~clik.model.urdf_check.parse_xml`).
    """
    root = parse_xml(path, data).getroot()
    links = {str(link.get("name")): link for link in root.iterfind("link")}
    left_out = []
    for item in missing:
        link = links.get(item.link)
        visuals = [] if link is None else link.findall("visual")
        if link is None or item.index >= len(visuals):
            raise RobotLoadError(path, f"link {shown(item.link)} lost a <visual> since loading")
        left_out.append((link, visuals[item.index]))
    for link, visual in left_out:  # removed once all are found: indices stay valid
        link.remove(visual)
    return etree.tostring(root, encoding="unicode")
