"""A robot: Pinocchio's kinematic and geometry models, loaded safely.

:meth:`Robot.load` takes a URDF path, a xacro path (``arm.urdf.xacro``, expanded
by :func:`clik.model.xacro_expand.expand_xacro`), the name of one of clik's robots
(``planar4r``) or an example-robot-data name (``panda``, ``ur5``, ...)
(:mod:`clik.model.sources`). Every URDF goes through
:func:`clik.model.urdf_check.check_urdf` before Pinocchio reads it
(:mod:`clik.model.loading`). An MJCF (MuJoCo) model, a file whose root element is
``<mujoco>`` (``arm3``, ``scene.xml``), is checked and read by :mod:`clik.model.mjcf`.
The visual model is built on first use.

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
from clik.model import srdf as srdf_files
from clik.model.base import base_kind
from clik.model.configuration import float_array, shown
from clik.model.fingers import open_fingers
from clik.model.joints import JointValues, joint_kind, joint_units
from clik.model.loading import (
    read_visual_model,
)
from clik.model.mimic import Mimic
from clik.model.mjcf import mjcf_visual_model
from clik.model.mjcf_root import MjcfDocument
from clik.model.model_signature import check_unchanged, joint_signature, model_signature
from clik.model.robot_reader import read_robot
from clik.model.sources import available_robots
from clik.model.visual_meshes import MissingVisual

PANDA_FINGERS = {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}
"""``lock`` for the Panda's fingers, closed: ``Robot.load("panda", lock=PANDA_FINGERS)``
has the 7 arm joints."""


class Robot:
    """A robot model with its data: fixed to the world, or on a planar or floating base.

    Configurations are Pinocchio's: ``nq`` values, one per revolute or prismatic
    joint [rad or m], two (cos, sin) per continuous joint (then ``nv < nq``).

    Attributes:
        name: The robot's name (ours or example-robot-data's, else the file stem).
        source_path: The URDF file (or the xacro file it was expanded from).
        package_dirs: Folders searched for ``package://`` meshes.
        xacro_args: The xacro arguments given to :meth:`load` (empty for a URDF).
        urdf_text: The URDF expanded from the xacro file ``source_path``, or None
            for a URDF file (whatever reads the robot's URDF again uses this text).
        model: Pinocchio model; with a planar or floating base (:meth:`load`'s ``base``)
            its first joint is the base (:mod:`clik.model.base`).
        data: Pinocchio data for ``model``.
        collision_model: Collision geometry (coal shapes).
        collision_data: Geometry data for ``collision_model``.
        mimics: The URDF's mimic joints: follower name -> :class:`Mimic`.
        locked: Joints removed from the model, with their value [rad or m]: the
            ``lock`` given to :meth:`load` and the mimic followers it locked.
        signature: ``(nq, nv, njoints, nframes)`` of ``model`` when the robot was made
            (:meth:`check_model`).
        mjcf: An MJCF model's checked document (:class:`~clik.model.mjcf_root.MjcfDocument`,
            what Pinocchio read; its visual geometry is read from it), or None.
        srdf_path: The SRDF file read (:mod:`clik.model.srdf`), or None.
        disabled_collision_pairs: The SRDF's ``<disable_collisions>`` link pairs, each
            sorted by name: self-collision rows skip them.
        group_states: The SRDF's group states by name (:meth:`group_state`).
        visual_links: Links with ``<visual>`` elements in the URDF (meshes missing or
            not), known without reading the visual model; None for a robot not made
            by :meth:`load`.
        missing_visuals: The ``<visual>`` elements whose meshes were missing at loading
            (:class:`~clik.model.visual_meshes.MissingVisual`): left out of
            :attr:`visual_model`; the 3-D view draws those links' collision geometry.

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
        self._q_reference = open_fingers(
            model, self.check_configuration(q_reference, "q_reference")
        )
        self._visual_model = visual_model
        self._reduction: tuple[pin.Model, list[int], np.ndarray] | None = None
        self._source_digest: str | None = None  # of the file as checked, see visual_model
        self.mimics: dict[str, Mimic] = {}
        self.locked: dict[str, float] = {}
        self.xacro_args: dict[str, str] = {}
        self.urdf_text: str | None = None
        self._model_text: str | None = None  # what Pinocchio read (clik.model.urdf_uris)
        self.visual_links: frozenset[str] | None = None
        self.missing_visuals: tuple[MissingVisual, ...] = ()
        self.srdf_path: Path | None = None
        self.disabled_collision_pairs: frozenset[tuple[str, str]] = frozenset()
        self.group_states: Mapping[str, srdf_files.GroupState] = {}
        self.mjcf: MjcfDocument | None = None  # an MJCF model's checked document

    # ------------------------------------------------------------------ loading

    @classmethod
    def load(
        cls,
        source: str | Path,
        package_dirs: Sequence[str | Path] | None = None,
        lock: Mapping[str, float] | None = None,
        xacro_args: Mapping[str, str] | None = None,
        base: str = "fixed",
        base_speed: Sequence[float] | None = None,
        srdf: str | Path | bool | None = None,
    ) -> Robot:
        """Load a robot from a URDF or xacro file, or by name.

        ``source`` is tried, in order, as an existing file, one of our robot
        names (:meth:`available`), then an example-robot-data name. The
        reference configuration is the SRDF's reference posture where
        example-robot-data names one (the Panda's "default" ready pose), else
        Pinocchio's neutral configuration clipped into the joint limits, with a
        gripper's fingers in the middle of their range (the Panda's 0.001 m becomes
        0.02 m, outside any joint-range threshold: :func:`~clik.model.fingers.open_fingers`).
        A file whose root is ``<mujoco>`` is an MJCF model (:func:`clik.model.mjcf.load_mjcf`,
        its ``home`` key as reference).

        Args:
            source: A URDF path (relative to the working folder), a xacro path
                (name ending ``.xacro``) or a robot name.
            package_dirs: Folders holding the packages of ``package://`` meshes
                and of xacro's ``$(find pkg)``, found by the name in their
                ``package.xml`` anywhere below (a ROS workspace's ``src``), or as a
                folder ``pkg`` directly in one (:mod:`clik.model.packages`; then
                ``ROS_PACKAGE_PATH`` and ``AMENT_PREFIX_PATH`` when set); default:
                the file's folder and its two parents, never the filesystem root
                (example-robot-data robots: the loader's own folder).
            lock: Joints to lock, with their value [rad or m], e.g.
                ``{"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}``;
                the models are reduced to the other joints.
            xacro_args: Arguments of a xacro file, name -> value (strings), e.g.
                ``{"n_links": "5"}``; only for a xacro ``source`` or SRDF (which
                need not use them all when the source is xacro too).
            srdf: An SRDF file (:mod:`clik.model.srdf`: disabled collision pairs, group
                states); default the robot's own (example-robot-data's), False: none.
                One with xacro markup is expanded like a xacro source, with
                ``xacro_args`` (:mod:`clik.model.srdf_xacro`).
            base: ``"fixed"`` (welded to the world), ``"planar"`` (a mobile base:
                x, y, yaw) or ``"floating"`` (a free-flyer: position and
                orientation); a planar or floating base is the model's first joint,
                named ``"root_joint"`` (:mod:`clik.model.base`), unlimited in position.
            base_speed: ``[linear m/s, angular rad/s]``, the base's speed limits
                (default ``[1.0, 1.0]``, :data:`~clik.model.base.DEFAULT_LINEAR_SPEED`);
                only with a planar or floating base.

        Mimic joints are always locked (:mod:`clik.model.robot_reader`).

        Returns:
            The robot.

        Raises:
            UnknownRobotError: ``source`` is neither a file nor a known name.
            RobotLoadError: The file is missing or invalid (including a ``<mimic>``
                with a non-numeric multiplier or offset, or mimic joints that
                follow each other in a cycle), or xacro cannot expand it (see
                :func:`~clik.model.xacro_expand.expand_xacro`), or the SRDF is invalid
                or xacro cannot expand it (names the SRDF file).
            JointNotFound: A joint in ``lock`` does not exist.
            InputError: A lock value is not finite or outside the joint's limits; an
                unknown ``base``, a bad ``base_speed`` or one for a fixed base; the base
                joint in ``lock``;
                ``xacro_args`` for a source and an SRDF that are not xacro files, or
                not strings, or missing an argument a file needs; a ``$(find pkg)``
                with no package ``pkg`` in ``package_dirs``; two packages of one name
                under one package folder (:mod:`clik.model.packages`).

        Warns:
            MimicJointWarning: Mimic followers were locked while their leader is free.
            SrdfWarning: Some SRDF pairs name links the robot does not have (counted).
            SrdfMismatchWarning: The SRDF names none of the robot's links and joints.
        """
        return read_robot(cls, source, package_dirs, lock, xacro_args, base, base_speed, srdf)

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
        reads its :attr:`urdf_text` instead. The ``<visual>`` elements whose meshes
        were missing at loading (:attr:`missing_visuals`) are left out.

        Raises:
            RobotLoadError: The URDF was removed or changed since the robot was
                loaded, or its visual meshes cannot be read.
        """
        if self._visual_model is None and self.mjcf is not None:
            self._visual_model = mjcf_visual_model(self.mjcf, self._full_model, self._reduction)
        if self._visual_model is None:
            path = self.source_path
            self._visual_model = (
                pin.GeometryModel()
                if path is None
                else read_visual_model(
                    path,
                    self._source_digest,
                    self.urdf_text if self._model_text is None else self._model_text,
                    self._full_model,
                    self.package_dirs,
                    self._reduction,
                    self.missing_visuals,
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
    def base(self) -> str:
        """``"fixed"``, ``"planar"`` or ``"floating"`` (:meth:`load`'s ``base``)."""
        return base_kind(self.model)

    @property
    def joint_names(self) -> list[str]:
        """Names of the movable joints in configuration order ("universe" excluded)."""
        return list(self.model.names[1:])

    @property
    def joint_kinds(self) -> dict[str, str]:
        """Kind of each movable joint, by name.

        One of ``"revolute"``, ``"prismatic"``, ``"continuous"``, ``"planar"`` and
        ``"free-flyer"`` (a base), or ``"other"`` (see
        :data:`~clik.model.joints.REVOLUTE`...).
        """
        return {
            name: joint_kind(joint)
            for name, joint in zip(self.joint_names, self.model.joints[1:], strict=True)
        }

    @property
    def q_units(self) -> list[str]:
        """Unit of each configuration value, shape (nq,).

        ``"rad"`` (revolute), ``"m"`` (prismatic, a base's x, y and z) or ``""`` (a
        continuous joint's cos and sin, a base's rotation, other joints).
        """
        units = [""] * self.nq
        for joint in self.model.joints[1:]:
            units[joint.idx_q : joint.idx_q + joint.nq] = joint_units(joint)
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
    def link_names(self) -> list[str]:
        """Names of the robot's links (the URDF's ``<link>`` elements: body frames)."""
        return [f.name for f in self.model.frames if f.type == pin.FrameType.BODY]

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

    def group_state(self, name: str, field: str = "group_state") -> np.ndarray:
        """The configuration of the SRDF group state ``name`` (e.g. the Panda's ``"default"``).

        Joints the state does not list keep their reference values, locked joints their
        lock values (:func:`clik.model.srdf.state_configuration`); the limits are not
        checked here (:meth:`check_within_limits`).

        Raises:
            InputError: No state ``name`` (the message lists the SRDF's states), or a
                joint's value count does not fit the joint.
        """
        return srdf_files.state_configuration(self, name, field)

    def check_configuration(self, q: object, field: str = "q0") -> np.ndarray:
        """Convert a configuration to a float array and check it.

        A :class:`~clik.model.joints.JointValues` (a scenario's ``initial.q``) is
        converted with :meth:`configuration`, in its unit; a string ``"srdf:NAME"``
        is the SRDF group state ``NAME`` (:meth:`group_state`).

        Args:
            q: Joint values [rad or m], ``nq`` of them, or ``"srdf:NAME"``.
            field: Name of the input, used in the error message.

        Returns:
            A new float array of shape (nq,).

        Raises:
            InputError: Not ``nq`` finite numbers, or an unknown group state.
        """
        if isinstance(q, str) and q.startswith(srdf_files.SRDF_PREFIX):
            q = self.group_state(q[len(srdf_files.SRDF_PREFIX) :], field)
        if isinstance(q, JointValues):
            return self.configuration(q.written, q.unit, field)
        expected = f"an array of {self.nq} finite joint values [rad or m] for {self.name}"
        array = float_array(q, field, expected)
        if array.shape != (self.nq,):
            raise InputError(field, expected, got=shown(array))
        return configurations.unit_rotations(self.model, array, field)

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
