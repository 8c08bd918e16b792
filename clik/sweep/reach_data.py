"""What a reachability map solves and what it found: :class:`ReachSpec`, :class:`ReachMap`.

Each point is *reachable* (solved), *blocked* (solved without the constraints of the
spec's scenario, not with them: :attr:`clik.SolveResult.blocked`) or *unreachable*
(not solved even without constraints). Without a scenario no point is blocked.

Plain data and its table (Parquet or CSV). The solving is in
:mod:`clik.sweep.reach`, the 3-D view in :mod:`clik.sweep.reach_view`, and
:func:`clik.sweep.reach_output.write_reach` writes a map's files.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from clik.errors import InputError
from clik.outputs.io import atomic_write

COLUMNS = (
    "x",
    "y",
    "z",
    "success",
    "iterations",
    "attempts",
    "position_error",
    "orientation_error",
    "manipulability",
)
"""Columns of the map's table (lengths [m], angles [rad])."""

BLOCKED = "blocked"
"""The table's last column with a scenario: the point is blocked by its constraints."""

TABLE_FORMATS = ("auto", "parquet", "csv")
"""Values of ``fmt`` of :meth:`ReachMap.write_table`."""


@dataclass(frozen=True)
class ReachSpec:
    """What a reachability map solves.

    Attributes:
        robot: Robot name or URDF path (:meth:`clik.Robot.load`).
        frame: The frame to place.
        box: ``(xmin, ymin, zmin, xmax, ymax, zmax)`` [m].
        step: Grid spacing [m].
        orientation_rpy: Fixed orientation as roll, pitch, yaw [rad] (a pose task), or
            None (a position task).
        lock: Joints locked at a value [rad or m].
        axes: Task components kept (e.g. ``["x", "y"]`` for a planar arm), or None for all.
        restarts: Random restarts of :func:`clik.solve` after a failed attempt.
        tolerance: Position tolerance [m].
        orientation_tolerance: Orientation tolerance [rad].
        seed: Seed of the restarts (the same for every point).
        scenario: The scenario file whose robot, obstacles and constraints the map
            respects (absolute path), or None: the robot alone.
        scenario_data: That file's contents as read (TOML); workers rebuild the robot and
            the :class:`~clik.constraints.ConstraintSet` from it.
        tracking_attempts: With a scenario, starts of the constrained law per point
            (:func:`clik.solve`).
    """

    robot: str
    frame: str
    box: tuple[float, float, float, float, float, float]
    step: float
    orientation_rpy: tuple[float, float, float] | None = None
    lock: dict[str, float] = field(default_factory=dict)
    axes: tuple[str, ...] | None = None
    restarts: int = 20
    tolerance: float = 1e-4
    orientation_tolerance: float = 1e-3
    seed: int = 0
    scenario: str | None = None
    scenario_data: dict[str, Any] | None = field(default=None, compare=False, repr=False)
    tracking_attempts: int = 4

    @property
    def kind(self) -> Literal["position", "pose"]:
        """``"pose"`` with a fixed orientation, else ``"position"``."""
        return "position" if self.orientation_rpy is None else "pose"

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready description (written to ``DIR/reach.json``)."""
        return {
            "robot": self.robot,
            "frame": self.frame,
            "box": list(self.box),
            "step": self.step,
            "kind": self.kind,
            "orientation_rpy": None if self.orientation_rpy is None else list(self.orientation_rpy),
            "lock": dict(self.lock),
            "axes": None if self.axes is None else list(self.axes),
            "restarts": self.restarts,
            "tolerance": self.tolerance,
            "orientation_tolerance": self.orientation_tolerance,
            "seed": self.seed,
            "scenario": self.scenario,
            "tracking_attempts": self.tracking_attempts,
        }

    @property
    def table_columns(self) -> tuple[str, ...]:
        """The table's columns: :data:`COLUMNS`, and :data:`BLOCKED` with a scenario."""
        return COLUMNS if self.scenario is None else (*COLUMNS, BLOCKED)


@dataclass
class ReachMap:
    """A computed map.

    Attributes:
        spec: What was solved.
        points: Target points (N, 3) [m].
        success: Solved within tolerance (N,).
        iterations: Solver iterations over all attempts (N,).
        attempts: Attempts (1 + restarts used) (N,).
        position_error: Final position error [m] (N,).
        orientation_error: Final orientation error [rad] (N,).
        manipulability: ``sqrt(det(J J^T))`` at the solution, NaN where not solved (N,).
        wall_time_s: Time to solve the map [s].
        blocked: Not solved because of the scenario's constraints (N,) (all False
            without a scenario; None: all False).
    """

    spec: ReachSpec
    points: np.ndarray
    success: np.ndarray
    iterations: np.ndarray
    attempts: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    manipulability: np.ndarray
    wall_time_s: float = 0.0
    blocked: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.blocked is None:
            self.blocked = np.zeros(len(self.success), dtype=bool)

    @classmethod
    def from_columns(
        cls, spec: ReachSpec, columns: dict[str, list[Any]], wall_time_s: float = 0.0
    ) -> ReachMap:
        """A map from the columns :func:`clik.sweep.reach.solve_points` returns (or a table)."""
        w = [math.nan if v is None else float(v) for v in columns["manipulability"]]
        blocked = columns.get(BLOCKED)
        return cls(
            spec,
            np.column_stack([columns["x"], columns["y"], columns["z"]]).astype(float),
            np.asarray(columns["success"], dtype=bool),
            np.asarray(columns["iterations"], dtype=int),
            np.asarray(columns["attempts"], dtype=int),
            np.asarray(columns["position_error"], dtype=float),
            np.asarray(columns["orientation_error"], dtype=float),
            np.asarray(w, dtype=float),
            wall_time_s,
            None if blocked is None else np.asarray(blocked, dtype=bool),
        )

    @property
    def reachable_fraction(self) -> float:
        """Share of the points solved."""
        return float(np.mean(self.success)) if len(self.success) else 0.0

    def counts(self) -> dict[str, int]:
        """Points per category: ``reachable``, ``blocked`` and ``unreachable``."""
        blocked = np.zeros(0, dtype=bool) if self.blocked is None else self.blocked
        reachable, n_blocked = int(self.success.sum()), int(blocked.sum())
        return {
            "reachable": reachable,
            "blocked": n_blocked,
            "unreachable": len(self.success) - reachable - n_blocked,
        }

    def columns(self) -> dict[str, list[Any]]:
        """The table's columns (manipulability None where not solved)."""
        table = {
            "x": self.points[:, 0].tolist(),
            "y": self.points[:, 1].tolist(),
            "z": self.points[:, 2].tolist(),
            "success": self.success.tolist(),
            "iterations": self.iterations.tolist(),
            "attempts": self.attempts.tolist(),
            "position_error": self.position_error.tolist(),
            "orientation_error": self.orientation_error.tolist(),
            "manipulability": [None if math.isnan(v) else v for v in self.manipulability.tolist()],
        }
        if self.spec.scenario is not None:
            assert self.blocked is not None
            table[BLOCKED] = self.blocked.tolist()
        return table

    def write_table(self, path: str | os.PathLike[str], fmt: str = "auto") -> Path:
        """Write the map as Parquet or CSV, atomically; returns the path written.

        Args:
            path: The file. A CSV table is written with the suffix ``.csv``.
            fmt: ``"parquet"``, ``"csv"``, or ``"auto"``: Parquet for a ``.parquet``
                path, else CSV.

        Raises:
            InputError: An unknown ``fmt``.
        """
        if fmt not in TABLE_FORMATS:
            raise InputError("format", "'auto', 'parquet' or 'csv'", fmt)
        path = Path(path)
        if fmt == "auto":
            fmt = "parquet" if path.suffix == ".parquet" else "csv"
        if fmt == "parquet":
            self._write_parquet(path)
            return path
        path = path.with_suffix(".csv")
        self._write_csv(path)
        return path

    def _write_parquet(self, path: Path) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        table = pa.table(self.columns())
        atomic_write(path, lambda f: pq.write_table(table, f))

    def _write_csv(self, path: Path) -> None:
        cols = self.columns()

        def text(v: Any) -> str:
            return "" if v is None else repr(v) if isinstance(v, float) else str(v)

        names = list(cols)
        lines = [",".join(names)]
        lines += [",".join(text(cols[c][i]) for c in names) for i in range(len(self.points))]
        atomic_write(path, lambda f: f.write("\n".join(lines) + "\n"), mode="w")
