r"""Workspace box (clik's addition): a frame's origin kept inside an axis-aligned box.

For a frame origin ``p(q)`` (world frame) and a box ``lower <= p <= upper`` [m],
each of the six walls is a constraint like a joint range (16)-(19) in Cartesian
space. With threshold ``d_w`` and ``d`` the distance to a wall
(``d = p_a - lower_a`` or ``d = upper_a - p_a``, ``a`` one of x, y, z):

- error ``e_w = d_w - d`` (W1), positive inside the threshold band;
- ``edot_w = -+ pdot_a = -+ J_a qdot`` with ``J_a`` row ``a`` of the frame's
  world-aligned linear Jacobian, so the row is ``j_w = +J_a`` (lower wall) or
  ``-J_a`` (upper wall) (W2), no feed-forward (the box is at rest).

The limit guarded is the wall itself: ``p_a < lower_a`` or ``p_a > upper_a``.
Keys: ``workspace:<name>:<axis>:<lower|upper>``.
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
from clik.constraints.read_only import ReadOnlyList
from clik.constraints.region import Lines, Region, Surface, box_edges, box_surface
from clik.constraints.words import MILLIMETRES, LimitWords
from clik.errors import InputError
from clik.schema import MAX_LENGTH, Table

if TYPE_CHECKING:
    from clik.constraints.violations import ViolationMonitor
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult

AXES = ("x", "y", "z")
SIDES = ("lower", "upper")
WALL_FRACTION = 0.25
"""Largest threshold, as a fraction of the box's side: two walls never fire together."""
DEFAULT_THRESHOLD = 0.02
"""Default ``d_w`` [m]."""


def _vector3(value: Any, field: str) -> np.ndarray:
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError):
        v = np.full(1, math.nan)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise InputError(field, "three finite numbers [m]", value)
    return v


class Workspace(ConstraintKind):
    """A frame's origin kept inside an axis-aligned box of the world frame.

    Args:
        robot: The robot (its frames).
        frame: The frame whose origin is kept in the box.
        lower: The box's lower corner (3,) [m], world frame, ``lower < upper``.
        upper: The box's upper corner (3,) [m], world frame.
        threshold: ``d_w`` [m]: a wall's row is active within this distance of it;
            at most a quarter of the box's shortest side.
        name: The box's name in constraint keys (default: the frame's name).
        gain: The rows' gain [1/s]; None: the law's default.

    Raises:
        InputError: A bad corner, threshold or gain (the field is named).
        FrameNotFound: No such frame.
    """

    name = "workspace"
    table = "workspace"
    """The scenario table: ``[[constraints.workspace]]``."""
    depth_measure = MILLIMETRES
    limit_words = LimitWords("crossed by {}", MILLIMETRES)
    """A wall crossed: by how far [m], in mm."""

    def __init__(
        self,
        robot: Robot,
        frame: str,
        lower: Sequence[float] | np.ndarray,
        upper: Sequence[float] | np.ndarray,
        threshold: float = DEFAULT_THRESHOLD,
        name: str | None = None,
        gain: float | None = None,
    ) -> None:
        where = "constraints.workspace"
        self.frame = str(frame)
        self.frame_id = robot.frame_id(self.frame)
        self.label = self.frame if name is None else str(name)
        if not self.label:
            raise InputError(f"{where}.name", "a non-empty name", name)
        self.lower = _vector3(lower, f"{where}.lower")
        self.upper = _vector3(upper, f"{where}.upper")
        self.lower.flags.writeable = self.upper.flags.writeable = False
        if not np.all(self.lower < self.upper):
            raise InputError(
                f"{where}.upper", f"a corner above lower = {self.lower.tolist()} on every axis",
                self.upper.tolist(),
            )  # fmt: skip
        side = float(np.min(self.upper - self.lower))
        if not (isinstance(threshold, (int, float)) and not isinstance(threshold, bool)) or not (
            math.isfinite(threshold) and 0.0 < threshold <= WALL_FRACTION * side
        ):
            raise InputError(
                f"{where}.threshold",
                f"a distance [m] > 0 and at most a quarter of the box's shortest side "
                f"({WALL_FRACTION * side:.6g} m)",
                threshold,
            )
        self.threshold = float(threshold)
        if gain is not None and not (math.isfinite(gain) and gain > 0):
            raise InputError(f"{where}.gain", "a positive gain [1/s]", gain)
        self.gain = gain
        self.keys = ReadOnlyList(
            (f"workspace:{self.label}:{a}:{s}" for s in SIDES for a in AXES),
            "Workspace.keys",
            "a new Workspace(...)",
        )
        """The six walls' keys: lower x, y, z, then upper x, y, z."""

    @classmethod
    def read_table(cls, table: Table, dt: float) -> dict[str, Any]:
        """One ``[[constraints.workspace]]`` table, checked.

        Keys: ``frame``, ``lower``, ``upper`` [m], ``threshold`` [m] (default 0.02),
        ``name``, ``gain`` [1/s].
        """
        out = {
            "frame": table.string("frame"),
            "lower": table.vector("lower", 3, unit="[m]", bound=MAX_LENGTH),
            "upper": table.vector("upper", 3, unit="[m]", bound=MAX_LENGTH),
            "threshold": float(
                table.number(
                    "threshold", DEFAULT_THRESHOLD, minimum=0.0, strict=True, unit="[m]",
                    bound=MAX_LENGTH,
                )
            ),
            "name": table.string("name", None),
            "gain": read_gain(table, dt),
        }  # fmt: skip
        table.done()
        return out

    @classmethod
    def check_name(cls, key: str) -> str:
        """``workspace:cell:x:upper`` -> ``workspace 'cell'``."""
        return f"workspace {key.partition(':')[2].rsplit(':', 2)[0]!r}"

    @classmethod
    def region(cls, spec: dict[str, Any]) -> Region:
        """The box's walls (translucent) and edges, and the inner box of its threshold."""
        lower, upper = np.asarray(spec["lower"], float), np.asarray(spec["upper"], float)
        parts: list[Surface | Lines] = [
            Surface("walls", *box_surface(lower, upper)),
            Lines("edges", box_edges(lower, upper)),
        ]
        thr = float(spec.get("threshold") or 0.0)
        if thr > 0.0 and np.all(upper - lower > 2 * thr):
            parts.append(Lines("threshold", box_edges(lower + thr, upper - thr)))
        return Region(tuple(parts))

    def __repr__(self) -> str:
        return (
            f"Workspace({self.frame!r}, lower={self.lower.tolist()}, "
            f"upper={self.upper.tolist()}, threshold={self.threshold!r})"
        )

    def distances(self, p: np.ndarray) -> np.ndarray:
        """Distances (6,) [m] from ``p`` to the walls: ``p - lower`` then ``upper - p``."""
        return np.concatenate([p - self.lower, self.upper - p])

    def start(self, setup: RunSetup) -> WorkspaceRun:
        """The walls' state for one run."""
        return WorkspaceRun(self)

    def engine_config(self) -> Any:
        """``_engine.WorkspaceConfig``."""
        from clik.engine import load

        return load().WorkspaceConfig(
            frame=self.frame_id, lower=self.lower, upper=self.upper,
            threshold=self.threshold, keys=list(self.keys), gain=self.gain,
        )  # fmt: skip

    def finish(
        self, result: TrackingResult, records: dict[str, Any], n_rec: int, extra: dict[str, Any]
    ) -> None:
        """The box as ``workspace_used`` and as a region of the view (:meth:`region` draws it)."""
        extra.setdefault("workspace_used", []).append(
            {
                "name": self.label, "frame": self.frame, "lower": self.lower.tolist(),
                "upper": self.upper.tolist(), "threshold": self.threshold, "gain": self.gain,
            }
        )  # fmt: skip
        result.info.setdefault("shapes", []).append(
            {
                "name": self.keys[0].rsplit(":", 2)[0], "shape": "box",
                "lower": self.lower.tolist(), "upper": self.upper.tolist(),
                "threshold": self.threshold,
            }
        )  # fmt: skip

    def check(self, checker: PoseCheck, q: np.ndarray) -> list[Violation]:
        """Walls nearer than the threshold (W1) at ``q``."""
        p = checker.frame_placement(q, self.frame_id).translation
        out = []
        for i, d in enumerate(self.distances(p)):
            if self.threshold - d > CHECK_TOLERANCE:
                side, axis = SIDES[i // 3], AXES[i % 3]
                wall = (self.lower if side == "lower" else self.upper)[i % 3]
                detail = (
                    f"{self.frame} at {axis} = {p[i % 3]:.6g} m, {d:.4g} m from the {side} "
                    f"wall {axis} = {wall:.6g} m (threshold {self.threshold:.4g} m)"
                )
                out.append(Violation(self.check_name(self.keys[i]), detail, self.threshold - d))
        return out

    def with_margin(self, margin: float) -> Workspace:
        """The threshold ``margin`` larger (solve mode)."""
        return self.replaced(threshold=self.threshold + margin)

    def fingerprint(self) -> tuple[Any, ...]:
        """Frame, box, threshold and gain."""
        return (
            self.frame_id,
            self.lower.tobytes(),
            self.upper.tobytes(),
            self.threshold,
            self.gain,
        )


class WorkspaceRun(KindRun):
    """A box's six walls in one run."""

    def __init__(self, kind: Workspace) -> None:
        super().__init__(kind)
        self.kind: Workspace = kind
        self.d = np.zeros(6)
        self._J = np.zeros((6, 0))

    def evaluate(self, s: Sample, out: list[Candidate]) -> None:
        """The walls' errors (W1): candidates inside their band, or active."""
        kind = self.kind
        p = pin.updateFramePlacement(s.model, s.data, kind.frame_id).translation
        self.d = kind.distances(p)
        thr = kind.threshold
        for i in range(6):
            error = thr - float(self.d[i])
            key = kind.keys[i]
            if error > 0.0 or key in s.active_keys:
                out.append(Candidate(key, self, i, error, thr, thr))

    def row(self, s: Sample, c: Candidate, out: np.ndarray) -> None:
        """Row (W2): ``+-`` the frame's linear Jacobian row along the wall's axis."""
        J = pin.getFrameJacobian(s.model, s.data, self.kind.frame_id, pin.LOCAL_WORLD_ALIGNED)
        sign = 1.0 if c.item < 3 else -1.0
        np.multiply(J[c.item % 3], sign, out=out)
        c.feed = 0.0

    def observe_limits(self, tk: float, monitor: ViolationMonitor) -> None:
        """The origin beyond a wall (its distance below zero)."""
        for i in np.flatnonzero(self.d < 0.0):
            monitor.observe_excursion(tk, self.kind.keys[i], "length", float(-self.d[i]))
