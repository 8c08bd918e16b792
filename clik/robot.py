"""A fixed-base robot: Pinocchio's kinematic and geometry models, loaded safely.

:meth:`Robot.load` takes a URDF path, a xacro path (``arm.urdf.xacro``, expanded
by :func:`clik.xacro_expand.expand_xacro`), the name of one of clik's robots
(``planar4r``) or an example-robot-data name (``panda``, ``ur5``, ...). Every
URDF goes through :func:`clik.urdf_check.check_urdf` before Pinocchio reads it.
The visual model is built on first use: meshes for display are slow to read
(about 0.5 s for the Panda) and the kinematics never needs them.

Joint kinds: a *revolute* joint's value is an angle [rad] (degrees only where a
scenario says ``unit = "deg"``), a *prismatic* joint's a length [m], always; a
*continuous* joint (unlimited revolute) is stored as (cos, sin).

Mimic joints (URDF ``<mimic>``) are not driven by their leader: clik moves every
joint independently, and Pinocchio 4.1's ``mimic=True`` refuses several of the
robots clik offers (a follower parsed before its leader: romeo, talos_full,
talos_full_box; a leader that does not exist: alex_psyonic_hands), cannot lock
a leader alone, and gives a follower no velocity of its own (nv = 0), which
clik's motion bounds for obstacle certificates do not cover. So
:meth:`Robot.load` locks each follower at the value its leader implies
(``multiplier * leader + offset``, the leader at its reference, or at its
``lock`` value) and warns with :class:`MimicJointWarning` when the leader
stays free (then the follower no longer follows it).
"""

from __future__ import annotations

import hashlib
import importlib.resources
import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from os.path import join
from pathlib import Path
from typing import Protocol

import numpy as np
import pinocchio as pin
from lxml import etree

from clik.errors import (
    FrameNotFound,
    InfeasibleError,
    InputError,
    JointNotFound,
    RobotLoadError,
    UnknownRobotError,
    native_message,
)
from clik.mesh_check import vertex_problem
from clik.urdf_check import check_urdf, parse_xml
from clik.xacro_expand import check_xacro_args, expand_xacro, is_xacro

PANDA_FINGERS = {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}
"""``lock`` for the Panda's fingers, closed: ``Robot.load("panda", lock=PANDA_FINGERS)``
has the 7 arm joints."""

REVOLUTE = "revolute"
"""Kind of a one-DOF rotation with limits: one value, an angle [rad]."""
CONTINUOUS = "continuous"
"""Kind of an unlimited rotation: two configuration values (cos, sin), one DOF [rad]."""
PRISMATIC = "prismatic"
"""Kind of a one-DOF translation: one value, a length [m] (never converted from degrees)."""
OTHER = "other"
"""Kind of any other joint (planar, spherical, free-flyer): values not converted."""

UNITS = ("rad", "deg")
"""Units of revolute joint values a user may write (prismatic values are always metres)."""


MAX_MIMIC = 1000.0
"""Largest magnitude of a ``<mimic>`` multiplier and offset [rad or m] (a follower's value
then stays finite along any chain of mimics within the joint-count budget)."""


class ReferenceClippedWarning(UserWarning):
    """The robot's own reference configuration lay outside its limits and was clipped.

    Attributes:
        joints: Joint name -> (reference value, lower limit, upper limit) [rad or m].
    """

    def __init__(self, message: str, joints: dict[str, tuple[float, float, float]]) -> None:
        super().__init__(message)
        self.joints = joints


class MimicJointWarning(UserWarning):
    """Mimic joints were locked while their leader stays free (the follower does not follow).

    Attributes:
        joints: Follower name -> (leader name, value it is locked at [rad or m]).
    """

    def __init__(self, message: str, joints: dict[str, tuple[str, float]]) -> None:
        super().__init__(message)
        self.joints = joints


@dataclass(frozen=True)
class Mimic:
    """A URDF ``<mimic>``: ``follower = multiplier * leader + offset`` [rad or m].

    Attributes:
        leader: Name of the joint followed.
        multiplier: Factor on the leader's value.
        offset: Added to the product [rad or m].
    """

    leader: str
    multiplier: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class JointValues:
    """Joint values as a scenario writes them, with the unit of their angles.

    Which value is an angle is known only with the robot, so the values are
    kept as written: :meth:`Robot.check_configuration` converts them with
    :meth:`Robot.configuration`, turning only the angles (revolute and
    continuous joints) from ``unit`` into radians and keeping prismatic values
    in metres.

    Attributes:
        written: The values as written (revolute in ``unit``, prismatic in metres).
        unit: ``"rad"`` or ``"deg"``.

    Raises:
        InputError: ``unit`` is not ``"rad"`` or ``"deg"``.
    """

    written: tuple[float, ...]
    unit: str = "rad"

    def __post_init__(self) -> None:
        _unit_scale(self.unit, "unit")
        object.__setattr__(self, "written", tuple(float(v) for v in self.written))


def _unit_scale(unit: str, field: str) -> float:
    """Factor from ``unit`` to radians."""
    if unit not in UNITS:
        raise InputError(field, "one of 'rad', 'deg'", got=unit)
    return math.pi / 180.0 if unit == "deg" else 1.0


def joint_kind(joint: pin.JointModel) -> str:
    """Kind of a Pinocchio joint model: :data:`REVOLUTE`, :data:`CONTINUOUS`, ...

    Args:
        joint: An entry of ``model.joints``.
    """
    nq, nv, name = joint.nq, joint.nv, joint.shortname()
    if nq == 1 and nv == 1:
        return PRISMATIC if name.startswith("JointModelP") else REVOLUTE  # PX, PY, PZ, Prismatic...
    if nq == 2 and nv == 1:
        return CONTINUOUS
    return OTHER


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
                :func:`~clik.xacro_expand.expand_xacro`).
            JointNotFound: A joint in ``lock`` does not exist.
            InputError: A lock value is not finite or outside the joint's limits;
                ``xacro_args`` for a source that is not a xacro file, or not
                strings, or missing an argument the file needs; a ``$(find pkg)``
                with no folder ``pkg`` in ``package_dirs``.

        Warns:
            MimicJointWarning: Mimic followers were locked while their leader is free.
        """
        files = _source_files(source)
        urdf = files.urdf
        dirs = [str(d) for d in (files.package_dirs if package_dirs is None else package_dirs)]
        args = check_xacro_args(xacro_args)
        if args and not is_xacro(urdf):
            raise InputError("xacro_args", "a xacro source (a file ending in .xacro)", str(source))
        text = expand_xacro(urdf, args, dirs) if is_xacro(urdf) else None

        root = check_urdf(urdf, dirs, text)
        mimics = _mimic_joints(root, urdf)
        digest = _digest(urdf) if text is None else None  # xacro: the text is kept
        model, collision_model = _build_models(urdf, dirs, text)
        _check_mesh_extents(urdf, collision_model)
        q_reference = _reference_configuration(model, files.srdf, files.posture)
        robot = cls(files.name, urdf.resolve(), dirs, model, collision_model, q_reference)
        robot._source_digest = digest
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
        values = self._lock_values(lock)
        implied = self._mimic_values(mimics or {}, values)
        values.update({follower: value for follower, (_, value) in implied.items()})
        free_leaders = {f: lv for f, lv in implied.items() if lv[0] not in values}
        joint_ids: list[int] = []
        for joint_name, value in values.items():
            joint_id = self.model.getJointId(joint_name)
            continuous = joint_kind(self.model.joints[joint_id]) == CONTINUOUS
            q_full[_q_slice(self.model, joint_id)] = (
                (math.cos(value), math.sin(value)) if continuous else value
            )
            joint_ids.append(joint_id)
        if len(joint_ids) == self.model.njoints - 1:
            raise InputError("lock", "at least one joint left free", got=list(lock))
        if free_leaders:
            self._warn_free_leaders(free_leaders)
        model, (collision_model,) = pin.buildReducedModel(
            self.model, [self.collision_model], sorted(joint_ids), q_full
        )
        q_reference = np.concatenate(
            [q_full[_q_slice(self.model, self.model.getJointId(n))] for n in model.names[1:]]
        )
        robot = Robot(
            self.name, self.source_path, self.package_dirs, model, collision_model, q_reference
        )
        robot._reduction = (self.model, sorted(joint_ids), q_full)
        robot._source_digest = self._source_digest
        robot.mimics = dict(self.mimics)
        robot.xacro_args, robot.urdf_text = dict(self.xacro_args), self.urdf_text
        robot.locked = values
        return robot

    def _lock_values(self, lock: Mapping[str, float]) -> dict[str, float]:
        """The values of ``lock`` as floats, each checked against its joint.

        Raises:
            JointNotFound: A joint in ``lock`` does not exist.
            InputError: A joint is not one-DOF, or its value is not finite or
                outside the joint's limits (continuous joints have none).
        """
        values: dict[str, float] = {}
        for joint_name, given in lock.items():
            joint = self.model.joints[self.joint_id(joint_name)]
            low, high = self.lower[joint.idx_q], self.upper[joint.idx_q]
            continuous = joint_kind(joint) == CONTINUOUS
            try:
                value = float(given)
            except (TypeError, ValueError):
                value = math.nan
            if joint.nv != 1 or not (math.isfinite(value) and (continuous or low <= value <= high)):
                expected = f"a value within the joint's limits [{low:g}, {high:g}]"
                raise InputError(f"lock[{joint_name!r}]", expected, got=value)
            values[joint_name] = value
        return values

    def _warn_free_leaders(self, free_leaders: Mapping[str, tuple[str, float]]) -> None:
        """Warn that these mimic followers were locked while their leader stays free.

        Args:
            free_leaders: Follower name -> (leader name, value it is locked at).
        """
        listing = "; ".join(
            f"{f!r} = {v:.6g} {self._unit_of(f)} (mimics {lead!r})"
            for f, (lead, v) in free_leaders.items()
        )
        warnings.warn(
            MimicJointWarning(
                f"{self.name}: mimic joint(s) locked at the value their leader's reference "
                f"implies, the leader left free (clik moves every joint independently, so "
                f"the follower does not follow): {listing}; lock the leader too to keep "
                "them consistent",
                dict(free_leaders),
            ),
            stacklevel=4,
        )

    def _mimic_values(
        self, mimics: Mapping[str, Mimic], values: Mapping[str, float]
    ) -> dict[str, tuple[str, float]]:
        """Follower -> (leader, value) for the mimic followers to lock.

        Followers in ``values`` (locked by the user) and those whose leader is not
        a movable joint are left out. A leader that is itself a follower is
        resolved first. Values [rad or m] are clipped into the follower's limits.
        """
        names = set(self.joint_names)
        todo = {f: m for f, m in mimics.items() if f in names and m.leader in names}
        todo = {f: m for f, m in todo.items() if f not in values}
        out: dict[str, tuple[str, float]] = {}

        def leader_value(name: str, chain: tuple[str, ...]) -> float:
            if name in values:
                return float(values[name])
            if name in todo:
                return resolve(name, chain)
            joint = self.model.joints[self.model.getJointId(name)]
            q = self._q_reference[joint.idx_q : joint.idx_q + joint.nq]
            return math.atan2(q[1], q[0]) if joint_kind(joint) == CONTINUOUS else float(q[0])

        def resolve(follower: str, chain: tuple[str, ...] = ()) -> float:
            if follower in out:
                return out[follower][1]
            if follower in chain:
                cycle = " -> ".join(repr(n) for n in (*chain, follower))
                raise RobotLoadError(
                    self.source_path or self.name, f"mimic joints follow each other: {cycle}"
                )
            mimic = todo[follower]
            value = mimic.multiplier * leader_value(mimic.leader, (*chain, follower)) + mimic.offset
            joint = self.model.joints[self.model.getJointId(follower)]
            if joint_kind(joint) != CONTINUOUS:
                low = float(self.model.lowerPositionLimit[joint.idx_q])
                high = float(self.model.upperPositionLimit[joint.idx_q])
                value = min(max(value, low), high)
            out[follower] = (mimic.leader, value)
            return value

        for follower in todo:
            resolve(follower)
        return out

    @staticmethod
    def available() -> dict[str, str]:
        """Names :meth:`load` accepts, with where each model comes from."""
        names = {name: f"clik: {path.name}" for name, path in _our_robots().items()}
        for name, loader in _erd_robots().items():
            names.setdefault(name, f"example-robot-data: {loader.path}/{loader.urdf_filename}")
        return names

    # ------------------------------------------------------------------ models

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
                pin.GeometryModel() if path is None else self._read_visual_model(path)
            )
        return self._visual_model

    def _read_visual_model(self, path: Path) -> pin.GeometryModel:
        """The visual geometry of the URDF ``path``, reduced like :attr:`model`."""
        if self._source_digest is not None and _digest(path) != self._source_digest:
            raise RobotLoadError(
                path,
                "the file was removed or changed since the robot was loaded "
                "(its visual geometry is read on first use); load the robot again",
            )
        try:
            if self.urdf_text is not None:
                visual = pin.buildGeomFromUrdfString(
                    self._full_model, self.urdf_text, pin.VISUAL, package_dirs=self.package_dirs
                )
            else:
                visual = pin.buildGeomFromUrdf(
                    self._full_model, str(path), pin.VISUAL, package_dirs=self.package_dirs
                )
        except (ValueError, RuntimeError) as error:
            problem = f"Pinocchio cannot read the visual geometry: {native_message(error)}"
            raise RobotLoadError(path, problem) from None
        if self._reduction is not None:
            full_model, joint_ids, q_full = self._reduction
            _, visual = pin.buildReducedModel(full_model, visual, joint_ids, q_full)
        return visual

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
        (see :data:`REVOLUTE`...).
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

    def _unit_of(self, name: str) -> str:
        """``"m"`` for a prismatic joint, else ``"rad"``."""
        return "m" if self.joint_kinds.get(name) == PRISMATIC else "rad"

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
        q = pin.neutral(self.model)
        for joint in self.model.joints[1:]:
            i = joint.idx_q
            low, high = self.model.lowerPositionLimit[i], self.model.upperPositionLimit[i]
            if joint.nq == 2 and joint.nv == 1:
                angle = rng.uniform(-math.pi, math.pi)
                q[i : i + 2] = (math.cos(angle), math.sin(angle))
            elif joint.nq == 1 and math.isfinite(low) and math.isfinite(high):
                if not 0 <= 2 * margin <= high - low:
                    expected = "a margin >= 0 [rad or m] smaller than half of every joint range"
                    raise InputError("margin", expected, got=margin)
                q[i] = rng.uniform(low + margin, high - margin)
        return q

    def check_configuration(self, q: object, field: str = "q0") -> np.ndarray:
        """Convert a configuration to a float array and check it.

        A :class:`JointValues` (a scenario's ``initial.q``) is converted with
        :meth:`configuration`, in its unit.

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
        array = _float_array(q, field, expected)
        if array.shape != (self.nq,):
            raise InputError(field, expected, got=_shown(array))
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
        scale = _unit_scale(unit, f"{field} unit")
        joints = self.model.joints[1:]
        angle_form = self.nq != self.nv and all(
            joint_kind(j) in (REVOLUTE, PRISMATIC, CONTINUOUS) for j in joints
        )
        angle_unit = "deg" if unit == "deg" else "rad"
        expected = (
            f"an array of {self.nq} finite joint values [{angle_unit} for revolute joints, "
            f"m for prismatic ones] for {self.name}"
        )
        if angle_form:
            expected += f" (or {self.nv}, a continuous joint as its angle)"
        array = _float_array(values, field, expected)
        if array.shape == (self.nq,):
            q = array.copy()
            for joint in joints:
                if joint_kind(joint) == REVOLUTE:
                    q[joint.idx_q] *= scale
            return q
        if angle_form and array.shape == (self.nv,):
            q = np.empty(self.nq)
            for joint in joints:
                value = float(array[joint.idx_v])
                kind = joint_kind(joint)
                if kind == CONTINUOUS:
                    angle = value * scale
                    q[joint.idx_q : joint.idx_q + 2] = (math.cos(angle), math.sin(angle))
                else:
                    q[joint.idx_q] = value * scale if kind == REVOLUTE else value
            return q
        raise InputError(field, expected, got=_shown(array))

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
        outside = []
        for name, joint in zip(self.joint_names, self.model.joints[1:], strict=True):
            kind = joint_kind(joint)
            if kind not in (REVOLUTE, PRISMATIC):
                continue  # continuous (cos, sin), spherical, free: no position limits
            i = joint.idx_q
            low = self.model.lowerPositionLimit[i]
            high = self.model.upperPositionLimit[i]
            value = float(q[i])
            if value < low - tolerance or value > high + tolerance:
                text = f"{name!r} = {value:.6g} not in [{low:.6g}, {high:.6g}]"
                if kind == PRISMATIC:
                    text += " m"
                else:
                    deg = [math.degrees(v) for v in (value, low, high)]
                    text += f" rad ({deg[0]:.4g} deg not in [{deg[1]:.4g}, {deg[2]:.4g}] deg)"
                outside.append(text)
        if outside:
            raise InfeasibleError(
                field,
                f"the configuration is outside the joint limits of {self.name}: "
                f"{'; '.join(outside)}",
            )

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, nq={self.nq}, nv={self.nv})"


def _float_array(values: object, field: str, expected: str) -> np.ndarray:
    """``values`` as a 1-D (or any shape) float array of finite numbers, else InputError."""
    try:
        array = np.array(values, dtype=float)
    except (TypeError, ValueError):
        raise InputError(field, expected, got=values) from None
    if not np.all(np.isfinite(array)):
        raise InputError(field, expected, got=_shown(array))
    return array


def _shown(array: np.ndarray) -> object:
    """An array as shown in an error message: its values, or its shape when large."""
    return array.tolist() if array.size <= 20 else f"an array of shape {array.shape}"


def _mimic_joints(root: etree._Element, urdf: Path) -> dict[str, Mimic]:
    """The URDF's ``<joint><mimic joint=... multiplier=... offset=.../></joint>`` entries.

    Raises:
        RobotLoadError: A ``<mimic>`` without a joint name, or with a multiplier or
            offset that is not a finite number.
    """
    mimics: dict[str, Mimic] = {}
    for joint in root.findall("joint"):
        element = joint.find("mimic")
        if element is None:
            continue
        name = joint.get("name")
        leader = element.get("joint")
        if not leader:
            raise RobotLoadError(
                urdf, f"joint {name!r} has a <mimic> without joint=...", line=element.sourceline
            )
        numbers: dict[str, float] = {}
        for attribute, default in (("multiplier", 1.0), ("offset", 0.0)):
            text = element.get(attribute)
            try:
                value = default if text is None else float(text)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise RobotLoadError(
                    urdf,
                    f"joint {name!r} has a <mimic> {attribute} {text!r}, expected a finite number",
                    line=element.sourceline,
                )
            if abs(value) > MAX_MIMIC:
                raise RobotLoadError(
                    urdf,
                    f"joint {name!r} has a <mimic> {attribute} {text!r}, expected a number of "
                    f"magnitude at most {MAX_MIMIC:g}",
                    line=element.sourceline,
                )
            numbers[attribute] = value
        mimics[name] = Mimic(leader, numbers["multiplier"], numbers["offset"])
    return mimics


def _build_models(
    urdf: Path, package_dirs: list[str], text: str | None
) -> tuple[pin.Model, pin.GeometryModel]:
    """Pinocchio's model and collision model of the file ``urdf``, or of ``text``.

    Args:
        urdf: The URDF file (named in errors).
        package_dirs: Folders for ``package://`` and relative mesh files.
        text: The URDF expanded from the xacro file ``urdf``, or None to read ``urdf``.

    Raises:
        RobotLoadError: Pinocchio refuses the description.
    """
    try:
        if text is None:
            model, collision_model = pin.buildModelsFromUrdf(
                str(urdf), package_dirs=package_dirs, geometry_types=[pin.COLLISION]
            )
        else:
            model = pin.buildModelFromXML(text)
            collision_model = pin.buildGeomFromUrdfString(
                model, text, pin.COLLISION, package_dirs=package_dirs
            )
    except (ValueError, RuntimeError) as error:
        problem = f"Pinocchio cannot build the model: {native_message(error)}"
        raise RobotLoadError(urdf, problem) from None
    return model, collision_model


def _check_mesh_extents(urdf: Path, collision_model: pin.GeometryModel) -> None:
    """Refuse a collision mesh whose scaled vertices leave the accepted range.

    The cheap checks (:func:`clik.urdf_check.check_urdf`) bound a binary STL's
    vertices from the file; other formats are bounded here, after loading and
    before any convex hull is built from them.

    Raises:
        RobotLoadError: A mesh's vertices are not finite or beyond
            :data:`~clik.mesh_check.MAX_COORDINATE` [m] from its origin.
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


def _q_slice(model: pin.Model, joint_id: int) -> slice:
    """The configuration values of one joint."""
    joint = model.joints[joint_id]
    return slice(joint.idx_q, joint.idx_q + joint.nq)


def _digest(path: Path) -> str | None:
    """SHA-256 of a file's bytes, or None when it cannot be read."""
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def _parent_dirs(urdf: Path) -> list[Path]:
    """The URDF's folder and its two parents, without the filesystem root.

    A ``package://pkg/...`` URI is looked up as ``<dir>/pkg/...``: with the root
    among the folders, a URDF in a shallow folder could name any system file.
    """
    folders = [urdf.parent, urdf.parent.parent, urdf.parent.parent.parent]
    absolute = [folder.absolute() for folder in folders]
    kept = [f for f, a in zip(folders, absolute, strict=True) if a.parent != a]
    return list(dict.fromkeys(kept)) or [urdf.parent]


def _reference_configuration(
    model: pin.Model, srdf: Path | None, posture: str | None
) -> np.ndarray:
    """The SRDF's reference posture if there is one, else neutral clipped into the limits."""
    if srdf is not None and posture is not None:
        parse_xml(srdf)
        pin.loadReferenceConfigurations(model, str(srdf), False)
        if posture in model.referenceConfigurations:
            q = pin.normalize(model, model.referenceConfigurations[posture].copy())
            return _clipped_reference(model, q, posture)
    q = pin.neutral(model)
    return np.clip(q, model.lowerPositionLimit, model.upperPositionLimit)


def _clipped_reference(model: pin.Model, q: np.ndarray, posture: str) -> np.ndarray:
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
            stacklevel=4,
        )
    return q


def _our_robots() -> dict[str, Path]:
    """Our shipped robots: ``robots/<name>.urdf``."""
    folder = importlib.resources.files("clik.robots")
    return {
        entry.name.removesuffix(".urdf"): Path(str(entry))
        for entry in folder.iterdir()
        if entry.name.endswith(".urdf")
    }


class _ErdLoader(Protocol):
    """What clik reads of an example-robot-data loader class (never instantiated)."""

    path: str
    urdf_filename: str
    urdf_subpath: str
    srdf_filename: str
    srdf_subpath: str
    ref_posture: str
    model_path: str | None


def _erd_robots() -> dict[str, _ErdLoader]:
    """example-robot-data's loader classes that describe a URDF."""
    try:
        from example_robot_data.robots_loader import ROBOTS
    except ImportError:  # the loaders are a separate package
        return {}
    return {name: loader for name, loader in ROBOTS.items() if loader.urdf_filename}


@dataclass(frozen=True)
class _SourceFiles:
    """Where :meth:`Robot.load` reads a robot from.

    Attributes:
        name: The robot's name.
        urdf: The URDF file.
        package_dirs: Default folders for ``package://`` meshes.
        srdf: The SRDF file, or None.
        posture: Name of the SRDF's reference posture, or None.
    """

    name: str
    urdf: Path
    package_dirs: list[Path]
    srdf: Path | None = None
    posture: str | None = None


def _source_files(source: str | Path) -> _SourceFiles:
    """Files of ``source``: a URDF path, one of our robots, or an example-robot-data name.

    Raises:
        UnknownRobotError: ``source`` is neither a file nor a known name.
    """
    source_str = str(source)
    path = Path(source)
    if path.is_file() or path.suffix in (".urdf", ".xacro") or "/" in source_str:
        name = Path(path.name.removesuffix(".xacro")).stem if is_xacro(path) else path.stem
        return _SourceFiles(name, path, _parent_dirs(path))
    ours = _our_robots()
    if source_str in ours:
        return _SourceFiles(source_str, ours[source_str], [ours[source_str].parent])
    if source_str in _erd_robots():
        return _erd_files(source_str)
    raise UnknownRobotError(source_str, Robot.available())


def _erd_files(name: str) -> _SourceFiles:
    """URDF, package dirs, SRDF and reference posture of an example-robot-data robot.

    Reads the loader class's attributes without instantiating it (that would
    build a RobotWrapper with its meshes).

    Raises:
        RobotLoadError: example-robot-data does not have the URDF file.
    """
    from example_robot_data.robots_loader import getModelPath

    loader = _erd_robots()[name]
    subpath = join(loader.path, loader.urdf_subpath, loader.urdf_filename)
    try:
        model_path = loader.model_path or getModelPath(subpath)
    except OSError:
        raise RobotLoadError(name, f"example-robot-data has no file {subpath}") from None
    srdf = None
    if loader.srdf_filename:
        srdf = Path(model_path, loader.path, loader.srdf_subpath, loader.srdf_filename)
    urdf = Path(model_path, subpath).resolve()
    package_dirs = [Path(model_path, "../..").resolve()]
    return _SourceFiles(name, urdf, package_dirs, srdf, loader.ref_posture)
