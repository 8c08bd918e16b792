"""Obstacles: convex volumes as coal geometries, with a pose and a constant velocity.

docs/method.md, "Obstacle avoidance (13)-(15)": obstacles are convex volumes; a
point is a sphere of radius 0 (the paper's case study). A mesh obstacle is
replaced by its convex hull, computed once.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import TypeVar

import coal
import numpy as np
import pinocchio as pin

from clik.errors import GeometryError, InputError, native_message
from clik.model.mesh_check import (
    SCALE_RANGE,
    MeshRefused,
    check_mesh_file,
    check_scale,
    sanitized_obj,
    vertex_problem,
)

T = TypeVar("T")

SHAPES = ("sphere", "box", "capsule", "cylinder", "mesh")


def _vector3(value: Sequence[float] | np.ndarray, field: str) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float).reshape(-1)  # a copy: the caller keeps theirs
    except (TypeError, ValueError):
        raise InputError(field, "three finite numbers", value) from None
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InputError(field, "three finite numbers", value)
    return arr


def read_only_vector3(value: Sequence[float] | np.ndarray, field: str) -> np.ndarray:
    """Three finite numbers as a new read-only array (an obstacle's position, rpy...)."""
    arr = _vector3(value, field)
    arr.flags.writeable = False
    return arr


def _nonnegative(value: object, field: str, strict: bool = False) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        v = float("nan")
    if isinstance(value, bool) or not np.isfinite(v) or v < 0.0 or (strict and v == 0.0):
        shown = v if isinstance(value, np.floating) else value  # 0.0, not np.float64(0.0)
        raise GeometryError(
            f"{field}: expected a {'positive' if strict else 'non-negative'} finite size [m], "
            f"got {shown!r}"
        )
    return v


class Obstacle:
    """A convex obstacle.

    Args:
        name: Unique name (used in events and results).
        shape: ``"sphere"``, ``"box"``, ``"capsule"``, ``"cylinder"`` or ``"mesh"``.
        position: Center in the world frame (3,) [m] at ``t = 0``.
        rpy: Orientation as roll, pitch, yaw [rad].
        velocity: Constant linear velocity (3,) [m/s] (a moving obstacle, ``cdot`` of eq. (14)).
        threshold: Threshold distance ``d_o`` [m] for this obstacle (None: the constraint's).
        radius: Sphere, capsule or cylinder radius [m] (sphere radius 0 is a point).
        size: Box side lengths (3,) [m].
        length: Capsule or cylinder length along the local z axis [m].
        file: Mesh file (STL, OBJ, DAE or PLY, see :mod:`clik.model.mesh_check` for the
            budgets); its convex hull is used.
        scale: Mesh scale (3,), each factor's magnitude within
            :data:`~clik.model.mesh_check.SCALE_RANGE`.

    Attributes:
        geometry: The coal collision geometry (convex).
        bounding_radius: Radius of a sphere centred at ``position`` enclosing the geometry [m].
    """

    def __init__(
        self,
        name: str,
        shape: str,
        position: Sequence[float] | np.ndarray,
        rpy: Sequence[float] = (0.0, 0.0, 0.0),
        velocity: Sequence[float] = (0.0, 0.0, 0.0),
        threshold: float | None = None,
        *,
        radius: float | None = None,
        size: Sequence[float] | None = None,
        length: float | None = None,
        file: str | Path | None = None,
        scale: Sequence[float] = (1.0, 1.0, 1.0),
    ) -> None:
        if not isinstance(name, str) or not name:
            raise InputError("obstacle.name", "a non-empty string", name)
        if shape not in SHAPES:
            raise InputError(f"obstacles.{name}.shape", "one of " + ", ".join(SHAPES), shape)
        self.name = name
        self.shape = shape
        self.position = _vector3(position, f"obstacles.{name}.position")
        self.rpy = _vector3(rpy, f"obstacles.{name}.rpy")
        self.velocity = _vector3(velocity, f"obstacles.{name}.velocity")
        if threshold is not None:
            try:
                value = float(threshold)
            except (TypeError, ValueError):
                value = float("nan")
            if isinstance(threshold, bool) or not (np.isfinite(value) and value > 0):
                raise InputError(
                    f"obstacles.{name}.threshold", "a positive distance [m]", threshold
                )
        self.threshold = None if threshold is None else float(threshold)
        self.rotation = pin.rpy.rpyToMatrix(*self.rpy)
        for array in (self.position, self.rpy, self.velocity, self.rotation):
            array.flags.writeable = False  # a set's scene is built on them: change by a copy
        self.params: dict[str, object] = {}
        where = f"obstacles.{name}"
        if shape == "sphere":
            r = _nonnegative(_required(radius, where, "radius"), f"{where}.radius")
            self.geometry = coal.Sphere(r)
            self.bounding_radius = r
            self.params = {"radius": r}
        elif shape == "box":
            s = _vector3(_required(size, where, "size"), f"{where}.size")
            for v in s:
                _nonnegative(v, f"{where}.size", strict=True)
            self.geometry = coal.Box(*s)
            self.bounding_radius = 0.5 * float(np.linalg.norm(s))
            self.params = {"size": s.tolist()}
        elif shape in ("capsule", "cylinder"):
            strict = shape == "cylinder"
            r = _nonnegative(_required(radius, where, "radius"), f"{where}.radius", strict)
            h = _nonnegative(_required(length, where, "length"), f"{where}.length", strict)
            self.geometry = coal.Capsule(r, h) if shape == "capsule" else coal.Cylinder(r, h)
            self.bounding_radius = float(np.hypot(r, 0.5 * h)) + (r if shape == "capsule" else 0)
            self.params = {"radius": r, "length": h}
        else:
            self.geometry, self.bounding_radius = _mesh_hull(
                _required(file, where, "file"), _vector3(scale, f"{where}.scale"), where
            )
            self.params = {"file": str(file), "scale": list(map(float, scale))}

    def placement(self, t: float = 0.0) -> pin.SE3:
        """Pose in the world at time ``t`` [s] (constant velocity, no rotation)."""
        return pin.SE3(self.rotation, self.position + t * self.velocity)

    @property
    def moving(self) -> bool:
        """True when the obstacle has a non-zero velocity."""
        return bool(np.any(self.velocity != 0.0))

    def moved(
        self,
        position: Sequence[float] | np.ndarray | None = None,
        rpy: Sequence[float] | None = None,
        velocity: Sequence[float] | np.ndarray | None = None,
    ) -> Obstacle:
        """This obstacle (its geometry shared) with a new position, rpy or velocity.

        The position [m] is at ``t = 0``, rpy [rad], velocity [m/s]; each is checked
        (three finite numbers) and read-only.

        Raises:
            InputError: Not three finite numbers (``obstacles.<name>.<field>``).
        """
        out = Obstacle.__new__(Obstacle)
        out.__dict__.update(self.__dict__)
        for key, value in (("position", position), ("rpy", rpy), ("velocity", velocity)):
            if value is not None:
                setattr(out, key, read_only_vector3(value, f"obstacles.{self.name}.{key}"))
        if rpy is not None:
            out.rotation = pin.rpy.rpyToMatrix(*out.rpy)
            out.rotation.flags.writeable = False
        return out

    def __repr__(self) -> str:
        return f"Obstacle({self.name!r}, {self.shape!r}, position={self.position.tolist()})"


def _required(value: T | None, where: str, key: str) -> T:
    """``value``, refused when the shape needs it and it is missing."""
    if value is None:
        raise InputError(f"{where}.{key}", f"a value for this shape ({key})")
    return value


def _mesh_hull(file: object, scale: np.ndarray, where: str) -> tuple[coal.ConvexBase, float]:
    """Convex hull of a mesh file, and its bounding radius about the mesh origin.

    The cheap checks of :func:`clik.model.mesh_check.check_mesh_file` run first (a
    regular file, a known format, within the size and count budgets, not a
    symlink out of the folder its path names); an OBJ file is handed to the
    loader as a copy without its ``mtllib``/``usemtl`` lines, in a private
    temporary folder, so the loader reads no other file. The scaled vertices
    must lie within :data:`~clik.model.mesh_check.MAX_COORDINATE` before the hull.
    """
    path = Path(str(file))
    try:
        check_scale(scale, f"{where}.scale")
    except MeshRefused:
        low, high = SCALE_RANGE
        expected = f"three scale factors of magnitude within [{low:g}, {high:g}]"
        raise InputError(f"{where}.scale", expected, scale.tolist()) from None
    try:
        root = Path(os.path.normpath(path.absolute().parent))
        facts = check_mesh_file(path, scale, root, what="mesh file")
    except MeshRefused as refused:
        raise GeometryError(f"{where}.file: {refused}") from None
    with tempfile.TemporaryDirectory(prefix="clik-mesh-") as private:  # mode 0700
        readable = facts.path
        if facts.kind == ".obj":
            readable = Path(private, "mesh.obj")
            readable.write_bytes(sanitized_obj(facts.path.read_bytes()))
        try:
            mesh = coal.MeshLoader().load(str(readable), scale)
        except Exception as exc:  # coal/assimp raise plain RuntimeErrors
            message = native_message(exc).replace(str(readable), str(path))
            raise GeometryError(f"{where}.file: cannot read mesh {path}: {message}") from None
    problem = vertex_problem(np.asarray(mesh.vertices()))
    if problem is not None:
        raise GeometryError(f"{where}.file: {path}: {problem}")
    return convex_hull(mesh, f"{where}.file")


def convex_hull(mesh: coal.BVHModelBase, field: str) -> tuple[coal.ConvexBase, float]:
    """Convex hull of a coal mesh (computed once), with its bounding radius [m]."""
    if mesh.num_vertices < 4:
        raise GeometryError(f"{field}: the mesh has {mesh.num_vertices} vertices, a volume needs 4")
    vertices = np.asarray(mesh.vertices())
    if not np.all(np.isfinite(vertices)):
        raise GeometryError(f"{field}: the mesh has non-finite vertices")
    centered = vertices - vertices.mean(axis=0)
    if np.linalg.matrix_rank(centered, tol=1e-9) < 3:
        raise GeometryError(f"{field}: degenerate mesh (all vertices on a plane or a line)")
    try:
        mesh.buildConvexHull(True, "Qt")
    except Exception as exc:
        raise GeometryError(f"{field}: convex hull failed: {native_message(exc)}") from None
    radius = float(np.max(np.linalg.norm(vertices, axis=1)))
    return mesh.convex, radius
