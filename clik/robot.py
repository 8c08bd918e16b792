"""A fixed-base robot: Pinocchio's kinematic and geometry models, loaded safely.

:meth:`Robot.load` takes a URDF path, the name of one of clik's robots
(``planar4r``) or an example-robot-data name (``panda``, ``ur5``, ...). Every
URDF goes through :func:`clik.urdf_check.check_urdf` before Pinocchio reads it.
The visual model is built on first use: meshes for display are slow to read
(about 0.5 s for the Panda) and the kinematics never needs them.
"""

from __future__ import annotations

import hashlib
import importlib.resources
import math
from collections.abc import Mapping, Sequence
from os.path import join
from pathlib import Path

import numpy as np
import pinocchio as pin

from clik.errors import (
    FrameNotFound,
    InfeasibleError,
    InputError,
    JointNotFound,
    RobotLoadError,
    UnknownRobotError,
    native_message,
)
from clik.urdf_check import check_urdf, parse_xml

PANDA_FINGERS = {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}
"""``lock`` for the Panda's fingers, closed: ``Robot.load("panda", lock=PANDA_FINGERS)``
has the 7 arm joints."""


class Robot:
    """A fixed-base robot model with its data.

    Configurations are Pinocchio's: ``nq`` values, one per revolute or prismatic
    joint [rad or m], two (cos, sin) per continuous joint (then ``nv < nq``).

    Attributes:
        name: The robot's name (ours or example-robot-data's, else the file stem).
        source_path: The URDF file.
        package_dirs: Folders searched for ``package://`` meshes.
        model: Pinocchio model (fixed base).
        data: Pinocchio data for ``model``.
        collision_model: Collision geometry (coal shapes).
        collision_data: Geometry data for ``collision_model``.
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

    # ------------------------------------------------------------------ loading

    @classmethod
    def load(
        cls,
        source: str | Path,
        package_dirs: Sequence[str | Path] | None = None,
        lock: Mapping[str, float] | None = None,
    ) -> Robot:
        """Load a robot from a URDF file or by name.

        ``source`` is tried, in order, as an existing file, one of our robot
        names (:meth:`available`), then an example-robot-data name. The
        reference configuration is the SRDF's reference posture where
        example-robot-data names one (the Panda's "default" ready pose), else
        Pinocchio's neutral configuration clipped into the joint limits.

        Args:
            source: A URDF path (relative to the working folder) or a robot name.
            package_dirs: Folders holding the packages of ``package://`` meshes;
                default: the URDF's folder and its two parents, never the
                filesystem root (example-robot-data robots: the loader's own folder).
            lock: Joints to lock, with their value [rad or m], e.g.
                ``{"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}``;
                the models are reduced to the other joints.

        Returns:
            The robot.

        Raises:
            UnknownRobotError: ``source`` is neither a file nor a known name.
            RobotLoadError: The file is missing or invalid.
            JointNotFound: A joint in ``lock`` does not exist.
            InputError: A lock value is not finite or outside the joint's limits.
        """
        source_str = str(source)
        srdf, posture = None, None
        if Path(source).is_file() or Path(source).suffix == ".urdf" or "/" in source_str:
            urdf = Path(source)
            name = urdf.stem
            default_dirs = _parent_dirs(urdf)
        elif source_str in _our_robots():
            urdf, name = _our_robots()[source_str], source_str
            default_dirs = [urdf.parent]
        elif source_str in _erd_robots():
            urdf, default_dirs, srdf, posture = _erd_files(source_str)
            name = source_str
        else:
            raise UnknownRobotError(source_str, Robot.available())
        dirs = [str(d) for d in (default_dirs if package_dirs is None else package_dirs)]

        check_urdf(urdf, dirs)
        digest = _digest(urdf)
        try:
            model, collision_model = pin.buildModelsFromUrdf(
                str(urdf), package_dirs=dirs, geometry_types=[pin.COLLISION]
            )
        except (ValueError, RuntimeError) as error:
            problem = f"Pinocchio cannot build the model: {native_message(error)}"
            raise RobotLoadError(urdf, problem) from None
        q_reference = _reference_configuration(model, srdf, posture)
        robot = cls(name, urdf.resolve(), dirs, model, collision_model, q_reference)
        robot._source_digest = digest
        return robot._locked(lock) if lock else robot

    def _locked(self, lock: Mapping[str, float]) -> Robot:
        """A new robot with the joints in ``lock`` fixed at the given values."""
        q_full = self.q_reference
        joint_ids = []
        for joint_name, value in lock.items():
            joint_id = self.joint_id(joint_name)
            joint = self.model.joints[joint_id]
            q_slice = slice(joint.idx_q, joint.idx_q + joint.nq)
            low, high = self.lower[joint.idx_q], self.upper[joint.idx_q]
            continuous = joint.nq == 2 and joint.nv == 1  # stored as (cos, sin)
            try:
                value = float(value)
            except (TypeError, ValueError):
                value = math.nan
            if joint.nv != 1 or not (math.isfinite(value) and (continuous or low <= value <= high)):
                expected = f"a value within the joint's limits [{low:g}, {high:g}]"
                raise InputError(f"lock[{joint_name!r}]", expected, got=value)
            q_full[q_slice] = (math.cos(value), math.sin(value)) if continuous else value
            joint_ids.append(joint_id)
        if len(joint_ids) == self.model.njoints - 1:
            raise InputError("lock", "at least one joint left free", got=list(lock))
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
        return robot

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
        it is still the one checked by :meth:`load`.

        Raises:
            RobotLoadError: The URDF was removed or changed since the robot was
                loaded, or its visual meshes cannot be read.
        """
        if self._visual_model is None and self.source_path is None:
            self._visual_model = pin.GeometryModel()
        if self._visual_model is None:
            path = self.source_path
            if self._source_digest is not None and _digest(path) != self._source_digest:
                raise RobotLoadError(
                    path,
                    "the file was removed or changed since the robot was loaded "
                    "(its visual geometry is read on first use); load the robot again",
                )
            try:
                visual = pin.buildGeomFromUrdf(
                    self._full_model, str(path), pin.VISUAL, package_dirs=self.package_dirs
                )
            except (ValueError, RuntimeError) as error:
                problem = f"Pinocchio cannot read the visual geometry: {native_message(error)}"
                raise RobotLoadError(path, problem) from None
            if self._reduction is not None:
                full_model, joint_ids, q_full = self._reduction
                _, visual = pin.buildReducedModel(full_model, visual, joint_ids, q_full)
            self._visual_model = visual
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

        Args:
            q: Joint values [rad or m], ``nq`` of them.
            field: Name of the input, used in the error message.

        Returns:
            A new float array of shape (nq,).

        Raises:
            InputError: Not ``nq`` finite numbers.
        """
        expected = f"an array of {self.nq} finite joint values [rad or m] for {self.name}"
        try:
            array = np.array(q, dtype=float)
        except (TypeError, ValueError):
            raise InputError(field, expected, got=q) from None
        if array.shape != (self.nq,) or not np.all(np.isfinite(array)):
            got = array.tolist() if array.size <= 20 else f"an array of shape {array.shape}"
            raise InputError(field, expected, got=got)
        return array

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
            if joint.nq != 1 or joint.nv != 1:
                continue  # continuous (cos, sin), spherical, free: no position limits
            i = joint.idx_q
            low = self.model.lowerPositionLimit[i]
            high = self.model.upperPositionLimit[i]
            value = float(q[i])
            if value < low - tolerance or value > high + tolerance:
                outside.append(f"{name!r} = {value:.6g} not in [{low:.6g}, {high:.6g}]")
        if outside:
            raise InfeasibleError(
                field,
                f"the configuration is outside the joint limits of {self.name} "
                f"[rad or m]: {'; '.join(outside)}",
            )

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, nq={self.nq}, nv={self.nv})"


def _q_slice(model: pin.Model, joint_id: int) -> slice:
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
            return pin.normalize(model, model.referenceConfigurations[posture].copy())
    q = pin.neutral(model)
    return np.clip(q, model.lowerPositionLimit, model.upperPositionLimit)


def _our_robots() -> dict[str, Path]:
    """Our shipped robots: ``robots/<name>.urdf``."""
    folder = importlib.resources.files("clik.robots")
    return {
        entry.name.removesuffix(".urdf"): Path(str(entry))
        for entry in folder.iterdir()
        if entry.name.endswith(".urdf")
    }


def _erd_robots() -> dict[str, type]:
    """example-robot-data's loader classes that describe a URDF."""
    try:
        from example_robot_data.robots_loader import ROBOTS
    except ImportError:  # the loaders are a separate package
        return {}
    return {name: loader for name, loader in ROBOTS.items() if loader.urdf_filename}


def _erd_files(name: str) -> tuple[Path, list[str], Path | None, str | None]:
    """URDF, package dirs, SRDF and reference posture of an example-robot-data robot.

    Reads the loader class's attributes without instantiating it (that would
    build a RobotWrapper with its meshes).
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
    return urdf, [str(Path(model_path, "../..").resolve())], srdf, loader.ref_posture
