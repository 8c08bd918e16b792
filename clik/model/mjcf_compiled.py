"""Pinocchio's kinematic model from MuJoCo's compiled model (``mujoco.MjModel``).

MuJoCo's compiler reads the checked document (:func:`clik.model.mjcf_check.check_mjcf`)
exactly as MuJoCo does: default classes, w-first quaternions, ``eulerseq``, ``fromto``,
mesh scales, joint ``ref``, the ``<compiler>`` settings. clik then builds its Pinocchio
model from the compiled numbers, body by body (docs/robots/mjcf.md, "How clik reads
MJCF"):

- a body's frame in its parent's is ``(body_pos, body_quat)``;
- each of its joints, in order, moves the body about (hinge) or along (slide) the
  joint's unit axis ``a`` through its anchor ``p`` (both in the body's frame) by
  ``q - q_ref`` (MuJoCo's ``qpos - qpos0``). In Pinocchio that is a one-degree-of-freedom
  joint placed at ``T(p) R(a, -q_ref)`` (a slide: ``T(p - a q_ref)``) after the frame
  reached so far, the body's frame ``T(-p)`` after it. A body with several joints
  becomes a chain of one-degree-of-freedom joints (MuJoCo applies them in that order);
  a body without joint is welded to its parent's joint;
- clik's joint value is MuJoCo's ``qpos``: ranges, keys and the reference are read
  as MuJoCo writes them;
- a site is a frame (``OP_FRAME``) on its body's joint, a body a ``BODY`` frame, a
  welded body also a ``FIXED_JOINT`` frame ``<body>_fixed`` (as Pinocchio's readers);
- the inertia of each body is MuJoCo's (mass, centre of mass, principal inertia).

Joint velocity limits: MJCF has none (runs use ``joint_speed``); effort limits are the
joints' ``actuatorfrcrange`` when limited.
"""

from __future__ import annotations

import re
import warnings
from typing import Any

import numpy as np
import pinocchio as pin

from clik.errors import RobotLoadError, user_stacklevel
from clik.model.base import BASE_JOINT, root_joint
from clik.model.mjcf_root import EqualityIgnoredWarning, MjcfDocument

FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3
"""MuJoCo's joint types (``mjtJoint``)."""

_AXES: dict[tuple[float, ...], str] = {
    (1.0, 0.0, 0.0): "X",
    (0.0, 1.0, 0.0): "Y",
    (0.0, 0.0, 1.0): "Z",
}


def compile_text(text: str, path: Any, lines: dict[int, tuple[str, int]] | None = None) -> Any:
    """MuJoCo's compiled model (``mujoco.MjModel``) of a checked document.

    The document's mesh files are absolute paths (checked); MuJoCo reads nothing else.

    Args:
        text: The document.
        path: The model's file (named in errors).
        lines: The file and line of each line of ``text``
            (:attr:`~clik.model.mjcf_root.MjcfDocument.lines`).

    Raises:
        RobotLoadError: MuJoCo's compiler refuses it: its message, with the file and line
            of the element it names.
    """
    import mujoco  # a dependency; imported when an MJCF model is loaded

    try:
        return mujoco.MjModel.from_xml_string(text)
    except (ValueError, RuntimeError) as error:
        message = " ".join(str(error).split())
        found = re.search(r"line (\d+)", message)
        source, line = (
            (lines or {}).get(int(found.group(1)), (path, None)) if found else (path, None)
        )
        if found and line is not None:
            message = message[: found.start()].rstrip(", ")
        problem = f"MuJoCo's compiler refuses the model: {message.removeprefix('Error: ')}"
        raise RobotLoadError(source, problem, line=line) from None


def body_name(mj: Any, body: int) -> str:
    """A body's name, ``body<i>`` when it has none."""
    return str(mj.body(body).name) or f"body{body}"


def element_name(mj: Any, kind: str, index: int) -> str:
    """A joint's or a geom's name; when it has none, its body's name and its rank there.

    ``<body>_joint<k>`` for a joint, ``<body>Geom_<k>`` for a geom (as Pinocchio's
    reader names geoms).
    """
    element = mj.joint(index) if kind == "joint" else mj.geom(index)
    if str(element.name):
        return str(element.name)
    ids, first, word = (
        (mj.jnt_bodyid, mj.body_jntadr, "_joint")
        if kind == "joint"
        else (mj.geom_bodyid, mj.body_geomadr, "Geom_")
    )
    body = int(ids[index])
    return f"{body_name(mj, body)}{word}{index - int(first[body])}"


def se3(position: np.ndarray, quaternion_wxyz: np.ndarray) -> pin.SE3:
    """A pose from MuJoCo's position and w-first quaternion."""
    w, x, y, z = (float(v) for v in quaternion_wxyz)
    rotation = pin.Quaternion(w, x, y, z).normalized().matrix()
    return pin.SE3(rotation, np.array(position, dtype=float))


def build_model(mj: Any, document: MjcfDocument, root_pose: pin.SE3) -> pin.Model:
    """Pinocchio's model of a compiled MJCF robot (see the module's docstring).

    The base's root joint (``root_joint``: a planar or free-flyer joint) comes first
    when ``document.base`` is not fixed; the root body hangs on it (other bodies of the
    world, which hold no joint and no geom, are frames welded to the world). The root
    body is placed at ``root_pose`` after the base's root joint (or the world): for a
    fixed base the pose the file gives it (removed from the document:
    :attr:`~clik.model.mjcf_root.MjcfDocument.root_probe`), for a planar base what the
    planar joint does not carry, for a floating base the identity
    (:func:`clik.model.mjcf.root_offset`).

    Raises:
        RobotLoadError: A ball or free joint below the root (naming the body and joint).
    """
    model = pin.Model()
    model.name = str(document.path.stem)
    root = root_joint(document.base)
    # per body: (Pinocchio joint it hangs on, its BODY frame, its placement in that joint)
    hang: dict[int, tuple[int, int, pin.SE3]] = {0: (0, 0, pin.SE3.Identity())}
    on_world = [b for b in range(1, mj.nbody) if int(mj.body_parentid[b]) == 0]
    root_body = on_world[document.root_index]
    for body in range(1, mj.nbody):
        parent_joint, parent_frame, parent_pose = hang[int(mj.body_parentid[body])]
        if body == root_body:
            if root is not None:
                parent_joint = model.addJoint(0, root, pin.SE3.Identity(), BASE_JOINT)
                parent_frame = model.addJointFrame(parent_joint, 0)
            parent_pose = root_pose
        pose = parent_pose * se3(mj.body_pos[body], mj.body_quat[body])
        hang[body] = _add_body(model, mj, document, body, (parent_joint, parent_frame, pose))
    _add_sites(model, mj, hang)
    _unique_frame_names(model)
    _add_keys(model, mj, document)
    _warn_equalities(mj, document)
    return model


EQUALITY_KINDS = ("connect", "weld", "joint", "tendon", "flex", "flexvert", "flexstrain")
"""MuJoCo's equality types (``mjtEq``) by number, as the file writes them."""


def _warn_equalities(mj: Any, document: MjcfDocument) -> None:
    """Warn once, with their kinds and counts, when the model has equality constraints."""
    if mj.neq == 0:
        return
    kinds: dict[str, int] = {}
    for eq in range(mj.neq):
        kind = int(mj.eq_type[eq])
        name = EQUALITY_KINDS[kind] if kind < len(EQUALITY_KINDS) else f"type {kind}"
        kinds[name] = kinds.get(name, 0) + 1
    counted = ", ".join(f"{n} {k}" for k, n in kinds.items())
    warnings.warn(
        EqualityIgnoredWarning(
            f"{document.path}: the model's {mj.neq} <equality> constraint(s) ({counted}) are "
            "not applied: clik moves its joints independently (MuJoCo holds them by forces "
            "in simulation); lock coupled joints (lock=...) when it matters"
        ),
        stacklevel=user_stacklevel(),
    )


def _add_body(
    model: pin.Model, mj: Any, document: MjcfDocument, body: int, at: tuple[int, int, pin.SE3]
) -> tuple[int, int, pin.SE3]:
    """One body's joints (a chain), frames and inertia; where its children hang."""
    joint, frame, pose = at
    name = body_name(mj, body)
    first = int(mj.body_jntadr[body])
    for j in range(first, first + int(mj.body_jntnum[body])):
        joint, frame, pose = _add_joint(model, mj, document, j, (joint, frame, pose))
    if int(mj.body_jntnum[body]) == 0 and int(mj.body_parentid[body]) != 0:
        frame = model.addFrame(pin.Frame(f"{name}_fixed", joint, frame, pose, pin.FIXED_JOINT))
    frame = model.addFrame(pin.Frame(name, joint, frame, pose, pin.BODY))
    inertia = _inertia(mj, body)
    if inertia.mass > 0.0:
        model.appendBodyToJoint(joint, inertia, pose)
    return joint, frame, pose


def _add_joint(
    model: pin.Model, mj: Any, document: MjcfDocument, j: int, at: tuple[int, int, pin.SE3]
) -> tuple[int, int, pin.SE3]:
    """One hinge or slide joint after ``at``; the body's frame after it."""
    parent, frame, pose = at
    kind = int(mj.jnt_type[j])
    name = element_name(mj, "joint", j)
    body = body_name(mj, int(mj.jnt_bodyid[j]))
    if kind not in (HINGE, SLIDE):
        what = "a ball joint" if kind == BALL else "a free joint below the root body"
        raise RobotLoadError(
            document.path,
            f"body {body!r} has {what} ({name!r}): clik's joints have one degree of freedom "
            "(hinge or slide); a ball joint can be written as three hinges",
        )
    axis = np.array(mj.jnt_axis[j], dtype=float)
    anchor = np.array(mj.jnt_pos[j], dtype=float)
    ref = float(mj.qpos0[mj.jnt_qposadr[j]])
    if kind == HINGE:
        offset = pin.SE3(pin.AngleAxis(-ref, axis).matrix(), anchor)
    else:
        offset = pin.SE3(np.eye(3), anchor - ref * axis)
    lower, upper = (
        (float(mj.jnt_range[j][0]), float(mj.jnt_range[j][1]))
        if mj.jnt_limited[j]
        else (-np.inf, np.inf)
    )
    effort = float(np.max(np.abs(mj.jnt_actfrcrange[j]))) if mj.jnt_actfrclimited[j] else np.inf
    joint = model.addJoint(
        parent,
        _joint_model(kind, axis),
        pose * offset,
        name,
        np.array([effort]),
        np.array([np.inf]),
        np.array([lower]),
        np.array([upper]),
    )
    frame = model.addJointFrame(joint, frame)
    return joint, frame, pin.SE3(np.eye(3), -anchor)


def _joint_model(kind: int, axis: np.ndarray) -> pin.JointModel:
    """Pinocchio's joint about (or along) a unit axis: an aligned type when it is one."""
    letter = _AXES.get(tuple(float(v) for v in axis))
    revolute = kind == HINGE
    if letter is not None:
        return getattr(pin, f"JointModel{'R' if revolute else 'P'}{letter}")()
    if revolute:
        return pin.JointModelRevoluteUnaligned(axis)
    return pin.JointModelPrismaticUnaligned(axis)


def _inertia(mj: Any, body: int) -> pin.Inertia:
    """A body's spatial inertia in its frame (MuJoCo's principal axes at ``body_iquat``)."""
    frame = se3(mj.body_ipos[body], mj.body_iquat[body])
    principal = np.diag(np.array(mj.body_inertia[body], dtype=float))
    rotational = frame.rotation @ principal @ frame.rotation.T
    return pin.Inertia(float(mj.body_mass[body]), frame.translation, rotational)


def _add_sites(model: pin.Model, mj: Any, hang: dict[int, tuple[int, int, pin.SE3]]) -> None:
    """Each site, a frame on its body's joint (``site<i>`` when it has no name)."""
    for site in range(mj.nsite):
        joint, frame, pose = hang[int(mj.site_bodyid[site])]
        if int(mj.site_bodyid[site]) == 0:
            continue  # a site of the world: not part of the robot
        name = str(mj.site(site).name) or f"site{site}"
        placement = pose * se3(mj.site_pos[site], mj.site_quat[site])
        model.addFrame(pin.Frame(name, joint, frame, placement, pin.OP_FRAME))


_FRAME_RANK = {pin.BODY: 0, pin.OP_FRAME: 1, pin.FIXED_JOINT: 2, pin.JOINT: 3}
_FRAME_SUFFIX = {pin.OP_FRAME: "_site", pin.FIXED_JOINT: "_fixed", pin.JOINT: "_joint"}


def _unique_frame_names(model: pin.Model) -> None:
    """One frame per name: MuJoCo lets a body, a site and a joint share one.

    The body keeps the name, then a site, a welded body's ``FIXED_JOINT`` frame, a
    joint's frame; the others get ``_site``, ``_fixed`` or ``_joint`` appended (joint
    names, in ``model.names``, do not change).
    """
    by_name: dict[str, list[pin.Frame]] = {}
    for frame in model.frames:
        by_name.setdefault(str(frame.name), []).append(frame)
    taken = set(by_name)
    for name, frames in by_name.items():
        for frame in sorted(frames, key=lambda f: _FRAME_RANK.get(f.type, 4))[1:]:
            new = f"{name}{_FRAME_SUFFIX.get(frame.type, '_frame')}"
            while new in taken:
                new += "_"
            frame.name = new
            taken.add(new)


def _add_keys(model: pin.Model, mj: Any, document: MjcfDocument) -> None:
    """The keys (``<keyframe>``) as reference configurations, on a fixed base only.

    A planar or floating base reads its ``home`` key from the document
    (:attr:`~clik.model.mjcf_root.MjcfDocument.home_joints`).
    """
    if model.nq != mj.nq:
        return
    for key in range(mj.nkey):
        name = str(mj.key(key).name)
        if name:
            model.referenceConfigurations[name] = np.array(mj.key_qpos[key], dtype=float)
