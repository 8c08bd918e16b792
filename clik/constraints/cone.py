r"""Tool axis cone (clik's addition): a frame axis kept within an angle of a fixed direction.

For a unit axis ``a_f`` fixed in a frame, its world direction is ``a(q) = R(q) a_f``;
with a fixed unit direction ``u`` (world frame) the angle between them is

    theta = atan2(|a x u|, a . u)                                   (C1)

and the constraint is ``theta <= theta_max``. With threshold ``d_c`` [rad] the
distance to the limit is ``theta_max - theta`` and, as (17),

- error ``e_c = d_c - (theta_max - theta)`` (C2), positive inside the band;
- ``adot = omega x a`` with ``omega = J_w qdot`` (the frame's world-aligned angular
  Jacobian), so ``d(cos theta)/dt = u . (omega x a) = omega . (a x u)`` and
  ``thetadot = -n^T J_w qdot`` with ``n = (a x u) / |a x u|``: the row is the
  gradient of the angle, ``j_c = n^T J_w`` (``edot_c = thetadot = -j_c qdot``) (C3),
  no feed-forward. At ``theta = pi`` (``a = -u``) any ``n`` normal to ``a`` is a
  gradient; clik takes the one normal to ``a`` and the world axis least along it.

The limit guarded is the cone's surface: ``theta > theta_max``. Key: ``cone:<name>``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.constraints.kind import (
    CHECK_TOLERANCE,
    Candidate,
    ConstraintKind,
    KindRun,
    PoseCheck,
    RunSetup,
    Sample,
    Violation,
    read_gain,
)
from clik.constraints.region import Region, Surface
from clik.constraints.words import AS_IS, DEGREES, LimitWords
from clik.errors import InputError
from clik.schema import MAX_LENGTH, Table

if TYPE_CHECKING:
    from clik.constraints.violations import ViolationMonitor
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult

PARALLEL_SINE = 1e-12
"""Below this ``|a x u|`` the axis is along the direction (or against it): ``n`` of (C3)
is then taken normal to ``a`` and the world axis least along it."""
DEFAULT_THRESHOLD = math.radians(5.0)
"""Default ``d_c`` [rad]."""
DRAWN_LENGTH = 0.25
"""Length [m] of a drawn cone, apex to base."""
MAX_DRAWN_ANGLE = math.radians(80.0)
"""A wider cone is drawn at this half-angle (its base would be huge)."""
DRAWN_SEGMENTS = 32
"""Triangles around a drawn cone."""


def _unit(value: Any, field: str) -> np.ndarray:
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError):
        v = np.full(1, math.nan)
    norm = float(np.linalg.norm(v)) if v.shape == (3,) else math.nan
    if not (math.isfinite(norm) and norm > 1e-9 and np.all(np.isfinite(v))):
        raise InputError(field, "a non-zero 3-vector of finite numbers", value)
    return v / norm


def angle_and_normal(a: np.ndarray, u: np.ndarray) -> tuple[float, np.ndarray]:
    """``theta`` (C1) [rad] between unit vectors ``a`` and ``u``, and ``n`` of (C3)."""
    cross = np.cross(a, u)
    s = float(np.linalg.norm(cross))
    theta = math.atan2(s, float(a @ u))
    if s > PARALLEL_SINE:
        return theta, cross / s
    basis = np.eye(3)[int(np.argmin(np.abs(a)))]  # a = +-u: any normal is a gradient
    n = np.cross(a, basis)
    return theta, n / np.linalg.norm(n)


class Cone(ConstraintKind):
    """A frame axis kept within ``angle`` of a fixed world direction.

    Args:
        robot: The robot (its frames).
        frame: The frame carrying the axis.
        axis: The axis in the frame (3,), any length.
        direction: The cone's axis in the world frame (3,), any length.
        angle: The cone's half-angle ``theta_max`` [rad], in (0, pi].
        threshold: ``d_c`` [rad]: the row is active within this angle of the surface;
            smaller than ``angle``.
        name: Its name in constraint keys (default: the frame's name).
        gain: The row's gain [1/s]; None: the law's default.

    Raises:
        InputError: A bad vector, angle, threshold or gain (the field is named).
        FrameNotFound: No such frame.
    """

    name = "cone"
    table = "cone"
    """The scenario table: ``[[constraints.cone]]``."""
    depth_measure = AS_IS
    limit_words = LimitWords("crossed by {}", DEGREES)
    """The surface crossed: by how far [rad], in deg."""

    def __init__(
        self,
        robot: Robot,
        frame: str,
        axis: Sequence[float] | np.ndarray,
        direction: Sequence[float] | np.ndarray,
        angle: float,
        threshold: float = DEFAULT_THRESHOLD,
        name: str | None = None,
        gain: float | None = None,
    ) -> None:
        where = "constraints.cone"
        self.frame = str(frame)
        self.frame_id = robot.frame_id(self.frame)
        self.label = self.frame if name is None else str(name)
        if not self.label:
            raise InputError(f"{where}.name", "a non-empty name", name)
        self.axis = _unit(axis, f"{where}.axis")
        self.direction = _unit(direction, f"{where}.direction")
        self.axis.flags.writeable = self.direction.flags.writeable = False
        if not _number(angle) or not 0.0 < angle <= math.pi:
            raise InputError(f"{where}.angle", "an angle in (0, pi] [rad]", angle)
        self.angle = float(angle)
        if not _number(threshold) or not 0.0 < threshold < self.angle:
            raise InputError(
                f"{where}.threshold", f"an angle > 0 and below angle = {self.angle:.6g} [rad]",
                threshold,
            )  # fmt: skip
        self.threshold = float(threshold)
        if gain is not None and not (_number(gain) and gain > 0):
            raise InputError(f"{where}.gain", "a positive gain [1/s]", gain)
        self.gain = gain
        self.key = f"cone:{self.label}"

    @classmethod
    def read_table(cls, table: Table, dt: float) -> dict[str, Any]:
        """One ``[[constraints.cone]]`` table, checked.

        Keys: ``frame``, ``axis``, ``direction``, ``angle``, ``threshold`` (default 5 deg)
        in ``unit`` (``"rad"``, default, or ``"deg"``), ``name``, ``gain`` [1/s].
        """
        unit = table.string("unit", "rad", ("rad", "deg"))
        scale = math.pi / 180.0 if unit == "deg" else 1.0
        default = DEFAULT_THRESHOLD / scale
        out = {
            "frame": table.string("frame"),
            "axis": table.vector("axis", 3, bound=MAX_LENGTH),
            "direction": table.vector("direction", 3, bound=MAX_LENGTH),
            "angle": table.number(
                "angle", minimum=0.0, strict=True, unit=f"[{unit}]", bound=math.pi / scale
            ) * scale,
            "threshold": table.number(
                "threshold", default, minimum=0.0, strict=True, unit=f"[{unit}]",
                bound=math.pi / scale,
            ) * scale,  # below the angle: checked in the table's unit below
            "name": table.string("name", None),
            "gain": read_gain(table, dt),
        }  # fmt: skip
        if out["threshold"] >= out["angle"]:
            raise table.error(
                "threshold", f"an angle > 0 and below angle = {out['angle'] / scale:g} [{unit}]",
                out["threshold"] / scale,
            )  # fmt: skip
        table.done()
        return out

    @classmethod
    def check_name(cls, key: str) -> str:
        """``cone:upright`` -> ``cone 'upright'``."""
        return f"cone {key.partition(':')[2]!r}"

    @classmethod
    def region(cls, spec: dict[str, Any]) -> Region:
        """The cone's surface, :data:`DRAWN_LENGTH` long, its apex on the frame's origin."""
        u = np.asarray(spec["direction"], float)
        u = u / np.linalg.norm(u)
        angle = min(float(spec["angle"]), MAX_DRAWN_ANGLE)
        _, n = angle_and_normal(u, u)  # a unit vector normal to u
        m = np.cross(u, n)
        phi = np.linspace(0.0, 2.0 * math.pi, DRAWN_SEGMENTS, endpoint=False)
        radius = DRAWN_LENGTH * math.tan(angle)
        rim = DRAWN_LENGTH * u + radius * (np.outer(np.cos(phi), n) + np.outer(np.sin(phi), m))
        vertices = np.vstack([np.zeros(3), rim])  # the apex, then the base's rim
        k = np.arange(DRAWN_SEGMENTS)
        triangles = np.stack([np.zeros_like(k), 1 + k, 1 + (k + 1) % DRAWN_SEGMENTS], axis=1)
        surface = Surface("cone", vertices, triangles, smooth=True)
        return Region((surface,), follows=str(spec["frame"]))

    def __repr__(self) -> str:
        return (
            f"Cone({self.frame!r}, axis={self.axis.tolist()}, "
            f"direction={self.direction.tolist()}, angle={self.angle!r})"
        )

    def world_axis(self, placement: pin.SE3) -> np.ndarray:
        """``a = R a_f`` in the world frame."""
        return placement.rotation @ self.axis

    def start(self, setup: RunSetup) -> ConeRun:
        """The row's state for one run."""
        return ConeRun(self)

    def engine_config(self) -> Any:
        """``_engine.ConeConfig``."""
        from clik.engine import load

        return load().ConeConfig(
            frame=self.frame_id, axis=self.axis, direction=self.direction, angle=self.angle,
            threshold=self.threshold, key=self.key, gain=self.gain,
        )  # fmt: skip

    def finish(
        self, result: TrackingResult, records: dict[str, Any], n_rec: int, extra: dict[str, Any]
    ) -> None:
        """The cone as ``cone_used`` and as a region of the view (:meth:`region` draws it)."""
        extra.setdefault("cone_used", []).append(
            {
                "name": self.label, "frame": self.frame, "axis": self.axis.tolist(),
                "direction": self.direction.tolist(), "angle": self.angle,
                "threshold": self.threshold, "gain": self.gain,
            }
        )  # fmt: skip
        result.info.setdefault("shapes", []).append(
            {
                "name": self.key, "shape": "cone", "frame": self.frame,
                "direction": self.direction.tolist(), "angle": self.angle,
                "threshold": self.threshold,
            }
        )  # fmt: skip

    def check(self, checker: PoseCheck, q: np.ndarray) -> list[Violation]:
        """The axis within the threshold of the cone's surface (C2) at ``q``."""
        theta, _ = angle_and_normal(
            self.world_axis(checker.frame_placement(q, self.frame_id)), self.direction
        )
        error = self.threshold - (self.angle - theta)
        if error <= CHECK_TOLERANCE:
            return []
        detail = (
            f"{self.frame} axis at {math.degrees(theta):.4g} deg from the direction, cone "
            f"{math.degrees(self.angle):.4g} deg (threshold {math.degrees(self.threshold):.4g} deg)"
        )
        return [Violation(self.check_name(self.key), detail, error)]

    def with_margin(self, margin: float) -> Cone:
        """The threshold ``margin`` larger (solve mode)."""
        return self.replaced(threshold=self.threshold + margin)

    def fingerprint(self) -> tuple[Any, ...]:
        """Frame, axes, angles and gain."""
        return (
            self.frame_id, self.axis.tobytes(), self.direction.tobytes(), self.angle,
            self.threshold, self.gain,
        )  # fmt: skip


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


class ConeRun(KindRun):
    """A cone's row in one run."""

    def __init__(self, kind: Cone) -> None:
        super().__init__(kind)
        self.kind: Cone = kind
        self.theta = 0.0
        self.n = np.zeros(3)

    def evaluate(self, s: Sample, out: list[Candidate]) -> None:
        """The error (C2): a candidate inside the band, or active."""
        kind = self.kind
        placement = pin.updateFramePlacement(s.model, s.data, kind.frame_id)
        self.theta, self.n = angle_and_normal(kind.world_axis(placement), kind.direction)
        error = kind.threshold - (kind.angle - self.theta)
        if error > 0.0 or kind.key in s.active_keys:
            out.append(Candidate(kind.key, self, 0, error, kind.threshold, kind.threshold))

    def row(self, s: Sample, c: Candidate, out: np.ndarray) -> None:
        """Row (C3): ``n^T J_w``."""
        J = pin.getFrameJacobian(s.model, s.data, self.kind.frame_id, pin.LOCAL_WORLD_ALIGNED)
        np.dot(self.n, J[3:], out=out)
        c.feed = 0.0

    def observe_limits(self, tk: float, monitor: ViolationMonitor) -> None:
        """The axis outside the cone."""
        excess = self.theta - self.kind.angle
        if excess > 0.0:
            monitor.observe_excursion(tk, self.kind.key, "angle", excess)
