"""What a tracking run returns: the joint trajectory, the task record, the status.

Arrays are sampled at ``t`` (every ``record_every``-th sample of the run, and
always the last one). Scalars such as ``max_task_error`` and ``joint_min``
are taken over *every* sample of the run, recorded or not.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import InputError
from clik.outputs.export import (
    FORMATS,
    check_every,
    check_formats,
    joint_trajectory,
    write_trajectory,
)
from clik.outputs.io import atomic_write, json_safe, json_text
from clik.outputs.speed_record import max_acceleration_ratio, speed_limited
from clik.outputs.velocity_report import (
    VelocityLimits,
    model_velocity_limits,
    run_velocity_limits,
    velocity_report,
)
from clik.tasks.manipulability import manipulability_record, min_manipulability

if TYPE_CHECKING:
    from clik.model.robot import Robot

STATUSES = (
    "completed",
    "violated",
    "velocity_limit",
    "off_track",
    "deadlock",
    "diverged",
    "converged",
    "max_iterations",
)
"""Run statuses: ``completed`` (reached the end of the trajectory, tracked within the
tolerance, no limit crossed, no joint above its speed limit), ``violated`` (reached the
end, but a constraint's limit was crossed: see ``violations``), ``velocity_limit``
(reached the end with a joint above its speed limit: the law's bound, else the URDF's;
or, with ``velocity_limits`` enabled, still above after re-timing: see
:mod:`clik.speed.velocity_limits`), ``off_track`` (reached the end, but the task error
stayed above the tolerance for longer than the settling time, or ended above it: see
:mod:`clik.loop.tracking_status`), ``deadlock``
(Remark 2: the law cannot reduce the task error, e.g. the task and the constraints
conflict), ``diverged`` (a non-finite value, a joint step above the bound, or unstable
gains), and for solve mode ``converged`` / ``max_iterations``."""

FAILED_STATUSES = ("violated", "velocity_limit", "off_track", "deadlock", "diverged")
"""Statuses of a run that did not do what was asked (``clik solve`` exits with 3)."""

_ARRAYS = (
    "t",
    "q",
    "qdot",
    "qddot",
    "position",
    "reference_position",
    "task_error_norm",
    "orientation_error_norm",
    "min_obstacle_distance",
    "active_count",
)


@dataclass
class TrackingResult:
    """Outcome of :func:`clik.track`.

    Attributes:
        t: Sample times (N,) [s].
        q: Joint positions (N, nq) [rad or m].
        qdot: Joint velocities (N, nv) from the law [rad/s].
        qddot: Joint accelerations (N, nv), backward differences of ``qdot`` [rad/s^2].
        position: Task frame origin in the world (N, 3) [m].
        reference_position: Desired frame origin (N, 3) [m], or None for an orientation task.
        task_error_norm: Norm of the position rows of the task error (N,) [m]; for a pure
            orientation task, of the orientation rows [rad].
        orientation_error_norm: Norm of the orientation rows (N,) [rad], or None.
        status: One of :data:`STATUSES`.
        reason: Why the run stopped, in words.
        wall_time_s: Wall time of the loop [s].
        steps: Number of CLIK iterations run.
        max_task_error: Maximum of the task error norm over every step [m or rad].
        final_task_error: Task error norm at the last step [m or rad].
        joint_min: Minimum of each joint over every step (nq,).
        joint_max: Maximum of each joint over every step (nq,).
        events: Constraint events ``{"t", "constraint", "action"}`` (see ``clik.constraints``):
            every one of an offline run, the last ones of a controller's session.
        events_dropped: Events of a controller's session no longer kept (its
            ``event_size`` last are; 0 for an offline run, which keeps every one).
        violations: Limits crossed, ``{"constraint", "t_first", "t_last", "worst"}``
            (``worst``: deepest penetration [m] or largest excursion [rad or m]); see
            :mod:`clik.constraints.violations`.
        min_obstacle_distance: Minimum link-obstacle distance per sample (N,) [m], or None.
        info: Free-form metadata (robot, frame, law, gain, dt, ...), JSON-serialisable.
        extra: Further per-sample arrays: constraint records (``active``, ``witness``,
            ...) and ``manipulability``, the task's ``w`` (D1) at each recorded sample
            [m^p] (:mod:`clik.tasks.manipulability`; filled by :meth:`summary` when missing).
        task_errors: Each task's errors by name: ``max`` (over every sample) and
            ``final`` [m or rad] (its position rows', or its only rows'), with
            ``max_orientation`` and ``final_orientation`` [rad] for a pose task, its
            ``kind``, ``priority`` and ``task`` in words; a run of one task names it
            ``"task"``. The other tasks' recorded error norms are in
            ``extra["task_errors"]`` (N, G, 2).
        velocity_limits: The robot's joint velocity limits per velocity coordinate
            (``model.velocityLimit``) [rad/s or m/s], taken from ``robot`` when not given;
            saved with the result so a loaded result reports the same joint speeds.
    """

    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    qddot: np.ndarray
    position: np.ndarray
    reference_position: np.ndarray | None
    task_error_norm: np.ndarray
    orientation_error_norm: np.ndarray | None
    status: str
    reason: str
    wall_time_s: float
    steps: int
    max_task_error: float
    final_task_error: float
    joint_min: np.ndarray
    joint_max: np.ndarray
    events: list[dict[str, Any]] = field(default_factory=list)
    events_dropped: int = 0
    violations: list[dict[str, Any]] = field(default_factory=list)
    min_obstacle_distance: np.ndarray | None = None
    active_count: np.ndarray | None = None
    info: dict[str, Any] = field(default_factory=dict)
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    task_errors: dict[str, dict[str, Any]] = field(default_factory=dict)
    robot: Robot | None = field(default=None, repr=False, compare=False)
    velocity_limits: VelocityLimits | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.velocity_limits is None and self.robot is not None:
            self.velocity_limits = model_velocity_limits(self.robot.model)

    @property
    def success(self) -> bool:
        """True when the run reached the end of its trajectory."""
        return self.status == "completed"

    def summary(self) -> dict[str, Any]:
        """The run's numbers as a JSON-ready dict (the ``summary.json`` contract)."""
        summary: dict[str, Any] = {
            "status": self.status,
            "reason": self.reason,
            "steps": int(self.steps),
            "wall_time_s": float(self.wall_time_s),
            "max_task_error": float(self.max_task_error),
            "final_task_error": float(self.final_task_error),
            "joint_min": [float(v) for v in self.joint_min],
            "joint_max": [float(v) for v in self.joint_max],
            "events": [dict(e) for e in self.events],
            "events_dropped": int(self.events_dropped),
            "violations": [dict(v) for v in self.violations],
            "task_errors": {k: dict(v) for k, v in self.task_errors.items()},
        }
        if self.orientation_error_norm is not None and self.reference_position is not None:
            summary["max_orientation_error"] = float(np.max(self.orientation_error_norm))
        bounds = run_velocity_limits(self.info, self.velocity_limits)
        summary.update(velocity_report(self.t, self.qdot, bounds).as_summary())
        names = self.velocity_limits.names if self.velocity_limits is not None else []
        limited, limited_time = speed_limited(self.t, self.qdot, names, self.info)
        summary["speed_limited"] = limited
        summary["speed_limited_time"] = limited_time
        summary["max_acceleration_ratio"] = max_acceleration_ratio(self.qddot, self.info)
        summary["recovery"] = []  # filled from summary_extra for a start inside a threshold
        summary["min_manipulability"] = min_manipulability(self)
        summary.update(self.info.get("summary_extra", {}))
        summary["info"] = {k: v for k, v in self.info.items() if k != "summary_extra"}
        return summary

    def export(
        self,
        out: str | os.PathLike[str],
        formats: str | Sequence[str] = FORMATS,
        every: int = 1,
        robot: Robot | None = None,
    ) -> dict[str, Path]:
        """Write the joint trajectory for a controller: ``trajectory.csv``, ``trajectory.json``.

        See :mod:`clik.outputs.export` for the two formats, continuous joints and the
        accelerations (``numpy.gradient`` of the recorded ``qdot`` over ``t``).

        Args:
            out: The output folder (created if missing).
            formats: ``"csv"``, ``"json"``, or both.
            every: Keep every ``every``-th recorded sample and the last (>= 1).
            robot: The run's robot, for a result without one (loaded from a file).

        Returns:
            The file written per format.

        Raises:
            InputError: An unknown format, ``every`` not an integer >= 1, or no robot.
            ExportError: A joint that is not revolute, prismatic or continuous.
        """
        formats, every = check_formats(formats), check_every(every)
        robot = robot if robot is not None else self.robot
        if robot is None:
            raise InputError("robot", "the run's robot (this result has none: pass robot=...)")
        trajectory = joint_trajectory(self.t, self.q, self.qdot, robot.model, every)
        return write_trajectory(trajectory, Path(out), formats)

    # -- persistence -------------------------------------------------------------------

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the result to a ``.npz`` file (atomically: a temporary file, then a rename)."""
        path = Path(path)
        manipulability_record(self)  # kept in extra: a loaded result reports it without a robot
        arrays = {name: getattr(self, name) for name in _ARRAYS if getattr(self, name) is not None}
        arrays.update({f"extra_{k}": v for k, v in self.extra.items()})
        arrays["joint_min"] = self.joint_min
        arrays["joint_max"] = self.joint_max
        if self.velocity_limits is not None:
            arrays["velocity_limit"] = self.velocity_limits.limit
            arrays["velocity_names"] = np.array(self.velocity_limits.names, dtype=str)
            arrays["velocity_source"] = np.array(self.velocity_limits.sources(), dtype=str)
        meta = {
            "status": self.status,
            "reason": self.reason,
            "wall_time_s": self.wall_time_s,
            "steps": self.steps,
            "max_task_error": self.max_task_error,
            "final_task_error": self.final_task_error,
            "events": self.events,
            "events_dropped": self.events_dropped,
            "violations": self.violations,
            "info": self.info,
            "task_errors": self.task_errors,
        }
        arrays["meta_json"] = np.array(json.dumps(meta))
        atomic_write(path, lambda f: np.savez_compressed(f, **arrays))
        return path

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> TrackingResult:
        """Read a result written by :meth:`save` (without its robot)."""
        with np.load(path, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
        meta = json.loads(str(arrays.pop("meta_json")))
        extra = {k[6:]: arrays.pop(k) for k in list(arrays) if k.startswith("extra_")}
        kwargs: dict[str, Any] = {name: arrays.get(name) for name in _ARRAYS}
        limits = None
        if "velocity_limit" in arrays and "velocity_names" in arrays:
            names = [str(n) for n in arrays["velocity_names"]]
            source = arrays.pop("velocity_source", None)
            source = None if source is None else [str(s) for s in source]
            limits = VelocityLimits(names, arrays["velocity_limit"], source)
        return cls(
            **kwargs,
            joint_min=arrays["joint_min"],
            joint_max=arrays["joint_max"],
            extra=extra,
            velocity_limits=limits,
            **meta,
        )


def write_outputs(result: TrackingResult, out: Path) -> dict[str, Any]:
    """Write ``trajectory.npz`` then ``summary.json`` into ``out``; returns the summary.

    All or nothing: the summary is made JSON-safe and turned into text before
    anything is written. A value that is not finite (the distance to an obstacle
    placed at 1e308, ...) becomes ``null``, and its key path is listed under
    ``non_finite`` (present only then). An old ``summary.json`` is removed first
    and the new one written last, so a ``summary.json`` sits only beside the
    complete ``trajectory.npz`` of the same run; when writing the summary fails,
    the new ``trajectory.npz`` is removed too.
    """
    summary, replaced = json_safe(result.summary())
    if replaced:
        summary["non_finite"] = replaced
    text = json_text(summary)
    npz, json_file = out / "trajectory.npz", out / "summary.json"
    json_file.unlink(missing_ok=True)
    result.save(npz)
    try:
        atomic_write(json_file, lambda f: f.write(text), mode="w")
    except BaseException:
        npz.unlink(missing_ok=True)
        raise
    return summary
