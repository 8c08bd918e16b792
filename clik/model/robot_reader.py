"""How :meth:`Robot.load <clik.model.robot.Robot.load>` reads a robot, and locks joints.

A URDF or xacro source goes, in order: xacro expansion (:mod:`clik.model.xacro_expand`,
packages found by :class:`~clik.model.packages.PackageDirs`), the strict checks
(:func:`clik.model.urdf_check.check_urdf`: visual meshes may be missing, with a
warning), the URDF text Pinocchio reads (:func:`clik.model.urdf_uris.pinocchio_urdf`:
every mesh the file checked), Pinocchio's models with the base's root joint
(:mod:`clik.model.loading`, :mod:`clik.model.base`), the reference configuration,
then the SRDF (:mod:`clik.model.srdf`; a xacro SRDF expanded like the URDF, with the same
``xacro_args`` and packages) and the locked joints. An MJCF model has its own
path (:func:`clik.model.mjcf.load_mjcf`).

Mimic joints (URDF ``<mimic>``, e.g. the Panda's ``panda_finger_joint2``) are always
locked, at ``multiplier * leader + offset`` (clipped into the follower's limits), the
leader taken at its ``lock`` value or else at its reference; a follower named in
``lock`` takes that value instead. When a locked follower's leader stays free,
:class:`~clik.model.mimic.MimicJointWarning` names them. A ``<mimic>`` whose leader is
not a movable joint is ignored (the follower stays free, as Pinocchio reads it).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from clik.errors import InputError
from clik.model import srdf as srdf_files
from clik.model.base import check_base_options, set_base_speed
from clik.model.loading import build_models, check_mesh_extents, digest, reference_configuration
from clik.model.locking import lock_values, reduced, set_locked
from clik.model.mimic import Mimic, mimic_joints, mimic_values, warn_free_leaders
from clik.model.mjcf import load_mjcf
from clik.model.mjcf_check import is_mjcf
from clik.model.packages import PackageDirs
from clik.model.sources import SourceFiles, source_files
from clik.model.urdf_check import check_urdf
from clik.model.urdf_uris import pinocchio_urdf
from clik.model.visual_meshes import missing_visuals, visual_links
from clik.model.xacro_expand import check_xacro_args, expand_xacro, is_xacro

Robot = Any
"""A :class:`clik.model.robot.Robot` (not imported: ``robot`` imports this module)."""


def read_robot(
    cls: Any,
    source: str | Path,
    package_dirs: Sequence[str | Path] | None,
    lock: Mapping[str, float] | None,
    xacro_args: Mapping[str, str] | None,
    base: str,
    base_speed: Sequence[float] | None,
    srdf: str | Path | bool | None,
) -> Robot:
    """The robot :meth:`Robot.load <clik.model.robot.Robot.load>` describes (same arguments)."""
    speed = check_base_options(base, base_speed, lock)
    files = source_files(source)
    if is_mjcf(files.urdf):
        return _read_mjcf(cls, files, lock, xacro_args, base, speed, srdf)
    srdf_path = srdf_files.srdf_file(srdf, files.srdf)  # InputError for a bad srdf=
    urdf = files.urdf
    if isinstance(package_dirs, str | Path):
        expected = "a list of folders, e.g. ['ws/src'] (not one string)"
        raise InputError("package_dirs", expected, str(package_dirs))
    dirs = [str(d) for d in (files.package_dirs if package_dirs is None else package_dirs)]
    args = check_xacro_args(xacro_args)
    if args and not is_xacro(urdf) and not (srdf_path and is_xacro(srdf_path)):
        expected = "a xacro source or SRDF (a file ending in .xacro)"
        raise InputError("xacro_args", expected, str(source))
    packages = PackageDirs(dirs)  # workspaces searched once for this load
    text = expand_xacro(urdf, args, packages) if is_xacro(urdf) else None

    root = check_urdf(urdf, packages, text)
    mimics = mimic_joints(root, urdf)
    source_digest = digest(urdf) if text is None else None  # xacro: the text is kept
    model_text = pinocchio_urdf(root, urdf, packages)  # meshes: the files checked
    model, collision_model = build_models(urdf, dirs, model_text, base)
    set_base_speed(model, speed)
    check_mesh_extents(urdf, collision_model)
    q_reference = reference_configuration(model, files.srdf, files.posture)
    robot = cls(files.name, urdf.resolve(), dirs, model, collision_model, q_reference)
    robot._source_digest = source_digest
    robot.mimics = mimics
    robot.xacro_args, robot.urdf_text, robot._model_text = args, text, model_text
    robot.visual_links, robot.missing_visuals = visual_links(root), missing_visuals(root)
    _set_srdf(robot, srdf_path, packages, extra_args=is_xacro(urdf))
    names = robot.joint_names
    followers = [f for f, m in mimics.items() if f in names and m.leader in names]
    return locked_robot(robot, dict(lock or {}), mimics) if lock or followers else robot


def _read_mjcf(
    cls: Any,
    files: SourceFiles,
    lock: Mapping[str, float] | None,
    xacro_args: Mapping[str, str] | None,
    base: str,
    speed: tuple[float, float],
    srdf: str | Path | bool | None,
) -> Robot:
    """An MJCF robot with its base (:mod:`clik.model.mjcf`); options it cannot take refused."""
    refused = {"xacro_args": xacro_args, "srdf": srdf}
    model, collision_model, q_reference, document = load_mjcf(files.urdf, refused, base)
    set_base_speed(model, speed)
    robot = cls(files.name, files.urdf.resolve(), [], model, collision_model, q_reference)
    robot.mjcf = document
    return locked_robot(robot, dict(lock)) if lock else robot


def _set_srdf(robot: Robot, path: Path | None, packages: PackageDirs, extra_args: bool) -> None:
    """Read the SRDF file ``path`` (None: none) and keep what the robot uses of it.

    A xacro SRDF is expanded with the robot's ``xacro_args`` and ``packages``; with
    ``extra_args`` (the URDF is xacro too, and took them) it need not use them all.
    """
    if path is not None:
        srdf = srdf_files.read_srdf(
            path,
            robot.link_names,
            robot.joint_names,
            robot.xacro_args,
            packages,
            extra_args=extra_args,
        )
        robot.srdf_path, robot.group_states = srdf.path.resolve(), srdf.group_states
        robot.disabled_collision_pairs = srdf.disabled_pairs


def locked_robot(
    robot: Robot, lock: Mapping[str, float], mimics: Mapping[str, Mimic] | None = None
) -> Robot:
    """A new robot with the joints in ``lock`` fixed at the given values.

    Mimic followers (``mimics``) not in ``lock`` are locked too, at the value
    their leader implies (see the module's docstring).
    """
    q_full = robot.q_reference
    values = lock_values(robot.model, lock)
    source = robot.source_path or robot.name
    implied = mimic_values(robot.model, q_full, mimics or {}, values, source)
    values.update({follower: value for follower, (_, value) in implied.items()})
    free_leaders = {f: lv for f, lv in implied.items() if lv[0] not in values}
    joint_ids = set_locked(robot.model, q_full, values, lock)
    if free_leaders:
        warn_free_leaders(robot.model, robot.name, free_leaders)
    model, collision_model, q_reference = reduced(
        robot.model, robot.collision_model, joint_ids, q_full
    )
    new = type(robot)(
        robot.name, robot.source_path, robot.package_dirs, model, collision_model, q_reference
    )
    new._reduction = (robot.model, joint_ids, q_full)
    new._source_digest = robot._source_digest
    new.mimics = dict(robot.mimics)
    new.xacro_args, new.urdf_text = dict(robot.xacro_args), robot.urdf_text
    new._model_text = robot._model_text
    new.visual_links, new.missing_visuals = robot.visual_links, robot.missing_visuals
    new.srdf_path = robot.srdf_path
    new.disabled_collision_pairs = robot.disabled_collision_pairs
    new.group_states = robot.group_states
    new.mjcf = robot.mjcf
    new.locked = values
    return new
