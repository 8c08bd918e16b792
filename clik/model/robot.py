"""A fixed-base robot: Pinocchio's kinematic and geometry models, loaded safely.

:meth:`Robot.load` takes a URDF path, a xacro path (``arm.urdf.xacro``, expanded
by :func:`clik.model.xacro_expand.expand_xacro`), the name of one of clik's robots
(``planar4r``) or an example-robot-data name (``panda``, ``ur5``, ...)
(:mod:`clik.model.sources`). Every URDF goes through
:func:`clik.model.urdf_check.check_urdf` before Pinocchio reads it
(:mod:`clik.model.loading`). The visual model is built on first use.

Joint kinds and units are in :mod:`clik.model.joints`, locked joints in
:mod:`clik.model.locking`, mimic joints (always locked) in
:mod:`clik.model.mimic`, configuration checks in :mod:`clik.model.configuration`.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from clik.errors import FrameNotFound, InputError, JointNotFound
from clik.model import configuration as configurations
from clik.model.configuration import float_array, shown
from clik.model.joints import PRISMATIC, REVOLUTE, JointValues, joint_kind
from clik.model.loading import (
    build_models,
    check_mesh_extents,
    digest,
    read_visual_model,
    reference_configuration,
)
from clik.model.locking import lock_values, reduced, set_locked
from clik.model.mimic import Mimic, mimic_joints, mimic_values, warn_free_leaders
from clik.model.model_signature import check_unchanged, joint_signature, model_signature
from clik.model.sources import available_robots, source_files
from clik.model.urdf_check import check_urdf
from clik.model.xacro_expand import check_xacro_args, expand_xacro, is_xacro

PANDA_FINGERS = {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}
"""``lock`` for the Panda's fingers, closed: ``Robot.load("panda", lock=PANDA_FINGERS)``
has the 7 arm joints."""


class Robot:
    """A fixed-base robot model with its data.

    Configurations are Pinocchio's: ``nq`` values, one per revolute or prismatic
    joint [rad or m], two (cos, sin) per continuous joint (then ``nv < nq``).

    Attributes:
        name: The robot's name (ours or example-robot-data's, else the file stem).
        source_path: The URDF file (or the xacro file it was expanded from).
        package_dirs: Folders searched for ``package://`` meshes.
        xacro_args: The xacro arguments given to :meth:`load` (empty for a URDF).
        urdf_text: The URDF expanded from the xacro file ``source_path``, or None
            for a URDF file (whatever reads the robot's URDF again uses this text).
        model: Pinocchio model (fixed base).
        data: Pinocchio data for ``model``.
        collision_model: Collision geometry (coal shapes).
        collision_data: Geometry data for ``collision_model``.
        mimics: The URDF's mimic joints: follower name -> :class:`Mimic`.
        locked: Joints removed from the model, with their value [rad or m]: the
            ``lock`` given to :meth:`load` and the mimic followers it locked.
        signature: ``(nq, nv, njoints, nframes)`` of ``model`` when the robot was made
            (:meth:`check_model`).

    The model is the robot's for good: everything derived from it (``data``, limits,
    names, ``q_reference``, tasks, constraint sets, compiled solvers) is sized by it, so
    a model changed afterwards (``robot.model.addJoint(...)``) is refused by every run
    and solve (:meth:`check_model`); load a new robot instead. ``data`` is a
    convenience for the caller's own Pinocchio calls in the thread that made the robot:
    runs and solves never use it (each has its own), and clik's conveniences use
    :meth:`thread_data` (``data`` in that thread, another data in any other), so robots,
    tasks and constraint sets may be shared by threads.
    """

    def __init__(
        self,
        name: str,
        source_path: Path | None,
        package_dirs: list[str],
        model: pin.Model,
        collision_model: pin.GeometryModel,
        q_reference: np.ndarray,
        visual_model: pin.GeometryModel | None = None,
    ) -> None:
        self.name = name
        self.source_path = source_path
        self.package_dirs = package_dirs
        self.model = model
        self.data = model.createData()
        self.signature = model_signature(model)
        self._joints = joint_signature(model)
        self._threads = threading.local()  # each thread's own data (thread_data)
        self._threads.data = self.data  # this thread's: the robot's own, as before threads
        self.collision_model = collision_model
        self.collision_data = collision_model.createData()
        self._q_reference = self.check_configuration(q_reference, "q_reference")
        self._visual_model = visual_model
        self._reduction: tuple[pin.Model, list[int], np.ndarray] | None = None
        self._source_digest: str | None = None  # of the file as checked, see visual_model
        self.mimics: dict[str, Mimic] = {}
        self.locked: dict[str, float] = {}
        self.xacro_args: dict[str, str] = {}
        self.urdf_text: str | None = None

    # ------------------------------------------------------------------ loading

    @classmethod
    def load(
        cls,
        source: str | Path,
        package_dirs: Sequence[str | Path] | None = None,
        lock: Mapping[str, float] | None = None,
        xacro_args: Mapping[str, str] | None = None,
    ) -> Robot:
        """Load a robot from a URDF or xacro file, or by name.

        ``source`` is tried, in order, as an existing file, one of our robot
        names (:meth:`available`), then an example-robot-data name. The
        reference configuration is the SRDF's reference posture where
        example-robot-data names one (the Panda's "default" ready pose), else
        Pinocchio's neutral configuration clipped into the joint limits.

        Args:
            source: A URDF path (relative to the working folder), a xacro path
                (name ending ``.xacro``) or a robot name.
            package_dirs: Folders holding the packages of ``package://`` meshes
                and of xacro's ``$(find pkg)``; default: the file's folder and its
                two parents, never the filesystem root (example-robot-data
                robots: the loader's own folder).
            lock: Joints to lock, with their value [rad or m], e.g.
                ``{"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}``;
                the models are reduced to the other joints.
            xacro_args: Arguments of a xacro file, name -> value (strings), e.g.
                ``{"n_links": "5"}``; only for a xacro ``source``.

        Mimic joints (URDF ``<mimic>``, e.g. the Panda's ``panda_finger_joint2``)
        are always locked, at ``multiplier * leader + offset`` (clipped into the
        follower's limits), the leader taken at its ``lock`` value or else at its
        reference; a follower named in ``lock`` takes that value instead. When a
        locked follower's leader stays free, :class:`MimicJointWarning` names
        them. A ``<mimic>`` whose leader is not a movable joint is ignored (the
        follower stays free, as Pinocchio reads it).

        Returns:
            The robot.

        Raises:
            UnknownRobotError: ``source`` is neither a file nor a known name.
            RobotLoadError: The file is missing or invalid (including a ``<mimic>``
                with a non-numeric multiplier or offset, or mimic joints that
                follow each other in a cycle), or xacro cannot expand it (see
                :func:`~clik.model.xacro_expand.expand_xacro`).
            JointNotFound: A joint in ``lock`` does not exist.
            InputError: A lock value is not finite or outside the joint's limits;
                ``xacro_args`` for a source that is not a xacro file, or not
                strings, or missing an argument the file needs; a ``$(find pkg)``
                with no folder ``pkg`` in ``package_dirs``.

        Warns:
            MimicJointWarning: Mimic followers were locked while their leader is free.
        """
        files = source_files(source)
        urdf = files.urdf
        dirs = [str(d) for d in (files.package_dirs if package_dirs is None else package_dirs)]
        args = check_xacro_args(xacro_args)
        if args and not is_xacro(urdf):
            raise InputError("xacro_args", "a xacro source (a file ending in .xacro)", str(source))
        text = expand_xacro(urdf, args, dirs) if is_xacro(urdf) else None

        root = check_urdf(urdf, dirs, text)
        mimics = mimic_joints(root, urdf)
        source_digest = digest(urdf) if text is None else None  # xacro: the text is kept
        model, collision_model = build_models(urdf, dirs, text)
        check_mesh_extents(urdf, collision_model)
        q_reference = reference_configuration(model, files.srdf, files.posture)
        robot = cls(files.name, urdf.resolve(), dirs, model, collision_model, q_reference)
        robot._source_digest = source_digest
        robot.mimics = mimics
        robot.xacro_args, robot.urdf_text = args, text
        names = robot.joint_names
        followers = [f for f, m in mimics.items() if f in names and m.leader in names]
        return robot._locked(dict(lock or {}), mimics) if lock or followers else robot

    def _locked(
        self, lock: Mapping[str, float], mimics: Mapping[str, Mimic] | None = None
    ) -> Robot:
        """A new robot with the joints in ``lock`` fixed at the given values.

        Mimic followers (``mimics``) not in ``lock`` are locked too, at the value
        their leader implies (see :meth:`load`).
        """
        q_full = self.q_reference
        values = lock_values(self.model, lock)
        source = self.source_path or self.name
        implied = mimic_values(self.model, self._q_reference, mimics or {}, values, source)
        values.update({follower: value for follower, (_, value) in implied.items()})
        free_leaders = {f: lv for f, lv in implied.items() if lv[0] not in values}
        joint_ids = set_locked(self.model, q_full, values, lock)
        if free_leaders:
            warn_free_leaders(self.model, self.name, free_leaders)
        model, collision_model, q_reference = reduced(
            self.model, self.collision_model, joint_ids, q_full
        )
        robot = Robot(
            self.name, self.source_path, self.package_dirs, model, collision_model, q_reference
        )
        robot._reduction = (self.model, joint_ids, q_full)
        robot._source_digest = self._source_digest
        robot.mimics = dict(self.mimics)
        robot.xacro_args, robot.urdf_text = dict(self.xacro_args), self.urdf_text
        robot.locked = values
        return robot

    @staticmethod
    def available() -> dict[str, str]:
        """Names :meth:`load` accepts, with where each model comes from."""
        return available_robots()

    # ------------------------------------------------------------------ models

    def thread_data(self) -> pin.Data:
        """The calling thread's ``pin.Data`` of the model.

        :attr:`data` in the thread that made the robot, one of its own (made at its first
        call) in any other thread. What clik's conveniences compute with
        (``Task.placement``, ``Task.jacobian``, a result's manipulability), so that they
        fill :attr:`data` as before in a single-threaded program while threads never
        share one.
        """
        data: pin.Data | None = getattr(self._threads, "data", None)
        if data is None:
            data = self._threads.data = self.model.createData()
        return data

    def check_model(self, full: bool = True) -> None:
        """Refuse a model changed since the robot was made (its sizes, or its joints).

        Args:
            full: Also compare every joint (kind, configuration and velocity indices);
                False compares only :attr:`signature` (about 0.5 us, a solve's check).

        Raises:
            InputError: ``robot.model`` changed after loading (names the old and new
                sizes): load a new :class:`Robot`.
        """
        check_unchanged(self.model, self.name, self.signature, self._joints, full)

    @property
    def visual_model(self) -> pin.GeometryModel:
        """Visual geometry, read from the URDF on first use (slow for meshes).

        Empty when the robot has no source file. The file is read again only if
        it is still the one checked by :meth:`load`; a robot expanded from xacro
        reads its :attr:`urdf_text` instead.

        Raises:
            RobotLoadError: The URDF was removed or changed since the robot was
                loaded, or its visual meshes cannot be read.
        """
        if self._visual_model is None:
            path = self.source_path
            self._visual_model = (
                pin.GeometryModel()
                if path is None
                else read_visual_model(
                    path,
                    self._source_digest,
                    self.urdf_text,
                    self._full_model,
                    self.package_dirs,
                    self._reduction,
                )
            )
        return self._visual_model

    @property
    def _full_model(self) -> pin.Model:
        return self.model if self._reduction is None else self._reduction[0]

    @property
    def nq(self) -> int:
        """Size of a configuration."""
        return self.model.nq

    @property
    def nv(self) -> int:
        """Number of degrees of freedom (size of a joint velocity)."""
        return self.model.nv

    @property
    def joint_names(self) -> list[str]:
        """Names of the movable joints in configuration order ("universe" excluded)."""
        return list(self.model.names[1:])

    @property
    def joint_kinds(self) -> dict[str, str]:
        """Kind of each movable joint, by name.

        One of ``"revolute"``, ``"prismatic"``, ``"continuous"`` or ``"other"``
        (see :data:`~clik.model.joints.REVOLUTE`...).
        """
        return {
            name: joint_kind(joint)
            for name, joint in zip(self.joint_names, self.model.joints[1:], strict=True)
        }

    @property
    def q_units(self) -> list[str]:
        """Unit of each configuration value, shape (nq,).

        ``"rad"`` (revolute), ``"m"`` (prismatic) or ``""`` (a continuous joint's
        cos and sin, other joints).
        """
        units = [""] * self.nq
        for joint in self.model.joints[1:]:
            kind = joint_kind(joint)
            if kind in (REVOLUTE, PRISMATIC):
                units[joint.idx_q] = "rad" if kind == REVOLUTE else "m"
        return units

    @property
    def q_joint_names(self) -> list[str]:
        """Name of the joint of each configuration value, shape (nq,)."""
        names = [""] * self.nq
        for name, joint in zip(self.joint_names, self.model.joints[1:], strict=True):
            names[joint.idx_q : joint.idx_q + joint.nq] = [name] * joint.nq
        return names

    @property
    def frame_names(self) -> list[str]:
        """Names of all the model's frames (links, joints, fixed joints)."""
        return [frame.name for frame in self.model.frames]

    @property
    def lower(self) -> np.ndarray:
        """Lower position limits, shape (nq,) [rad or m].

        Pinocchio's values: for a continuous joint the two (cos, sin) entries are
        bounded by -1.01, not by an angle.
        """
        return self.model.lowerPositionLimit.copy()

    @property
    def upper(self) -> np.ndarray:
        """Upper position limits, shape (nq,) [rad or m]; see :attr:`lower`."""
        return self.model.upperPositionLimit.copy()

    @property
    def q_reference(self) -> np.ndarray:
        """Reference configuration, shape (nq,) (a fresh copy each time)."""
        return self._q_reference.copy()

    def frame_id(self, name: str) -> int:
        """Index of a frame.

        Raises:
            FrameNotFound: The model has no frame of that name.
        """
        if not self.model.existFrame(name):
            raise FrameNotFound(name, self.frame_names)
        return self.model.getFrameId(name)

    def joint_id(self, name: str) -> int:
        """Index of a movable joint in ``model.joints``.

        Raises:
            JointNotFound: The model has no movable joint of that name.
        """
        if name not in self.joint_names:
            raise JointNotFound(name, self.joint_names)
        return self.model.getJointId(name)

    # ------------------------------------------------------------ configurations

    def random_configuration(self, rng: np.random.Generator, margin: float = 0.0) -> np.ndarray:
        """A configuration drawn uniformly within the joint limits.

        One-DOF joints with finite limits are drawn in
        ``[lower + margin, upper - margin]``; continuous joints get an angle
        uniform in ``[-pi, pi)``; other joints stay at Pinocchio's neutral.

        Args:
            rng: The random generator.
            margin: Distance kept from each limit [rad or m].

        Returns:
            A configuration, shape (nq,).

        Raises:
            InputError: ``margin`` is negative or wider than half a joint's range.
        """
        return configurations.random_configuration(self.model, rng, margin)

    def check_configuration(self, q: object, field: str = "q0") -> np.ndarray:
        """Convert a configuration to a float array and check it.

        A :class:`~clik.model.joints.JointValues` (a scenario's ``initial.q``) is
        converted with :meth:`configuration`, in its unit.

        Args:
            q: Joint values [rad or m], ``nq`` of them.
            field: Name of the input, used in the error message.

        Returns:
            A new float array of shape (nq,).

        Raises:
            InputError: Not ``nq`` finite numbers.
        """
        if isinstance(q, JointValues):
            return self.configuration(q.written, q.unit, field)
        expected = f"an array of {self.nq} finite joint values [rad or m] for {self.name}"
        array = float_array(q, field, expected)
        if array.shape != (self.nq,):
            raise InputError(field, expected, got=shown(array))
        return array

    def configuration(self, values: object, unit: str = "rad", field: str = "q0") -> np.ndarray:
        """A configuration from joint values as a user writes them.

        Only angles are converted from degrees: revolute joints' values and
        continuous joints' angles. Prismatic joints' values are metres whatever
        ``unit`` says; a continuous joint's (cos, sin) pair is not an angle and
        is kept as it is.

        Args:
            values: ``nq`` values (Pinocchio's configuration, a continuous joint as
                its (cos, sin)) or, for a robot whose only multi-value joints are
                continuous (``nq > nv``), ``nv`` values, a continuous joint as its
                angle [``unit``].
            unit: ``"rad"`` or ``"deg"``, the unit of revolute (and continuous) angles.
            field: Name of the input, used in the error message.

        Returns:
            A new float array of shape (nq,) [rad or m].

        Raises:
            InputError: A bad unit, or not ``nq`` (or ``nv``) finite numbers.
        """
        return configurations.configuration(self.model, self.name, values, unit, field)

    def check_within_limits(
        self, q: np.ndarray, field: str = "q0", tolerance: float = 1e-9
    ) -> None:
        """Check that a configuration lies inside the model's joint limits.

        A start outside the robot's own (URDF) limits is a configuration the
        robot cannot be in: clik refuses it rather than guess a recovery.
        Continuous joints (no limits) and joints with infinite limits are not
        checked. Stricter limits given to a joint-range constraint are not the
        model's: a start beyond them (but inside the model's) is driven back by
        the constraint's row, active from the first sample.

        Args:
            q: A configuration, shape (nq,), as returned by :meth:`check_configuration`.
            field: Name of the input, used in the error message.
            tolerance: Accepted excess beyond a limit [rad or m] (rounding, e.g.
                of a limit given in degrees).

        Raises:
            InfeasibleError: A joint is beyond one of its limits by more than
                ``tolerance``; the message names every such joint, its value and
                its limits.
        """
        configurations.check_within_limits(self.model, self.name, q, field, tolerance)

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, nq={self.nq}, nv={self.nv})"
