"""A run's joint trajectory in files a controller can play: CSV and ROS-style JSON.

One column (CSV) or one entry per point (JSON) per *velocity coordinate* of the
model, named by its joint: a revolute or prismatic joint gives its position
[rad or m]; a continuous joint (Pinocchio stores its angle as ``(cos, sin)``,
``nq = 2``, ``nv = 1``) gives its angle ``atan2(sin, cos)`` [rad], unwrapped
along the trajectory (so it never jumps by 2 pi and may leave ``(-pi, pi]``).
A joint of any other kind (spherical, planar, free-flyer: several velocity
coordinates) cannot be written as one angle per name and is refused
(:class:`ExportError`): in particular a robot loaded with a planar or floating base
(``Robot.load(base=...)``, :mod:`clik.model.base`), whose message says so. Its base's
pose per sample is in the run's record (``trajectory.npz``'s ``q``: the first 4
values ``(x, y, cos, sin)``, or 7 ``(x, y, z, q_x, q_y, q_z, q_w)``). Joints locked
out of the model (``Robot.load(lock=...)``, mimic followers) are not listed.

Per exported sample:

- time ``t_k`` [s]: the record's sample times (``trajectory.npz``'s ``t``);
- velocities [rad/s or m/s]: the recorded ``qdot`` (the law's output);
- accelerations [rad/s^2 or m/s^2]: finite differences of the recorded ``qdot``
  over the recorded times, ``numpy.gradient(qdot, t, axis=0)``: second-order
  central differences inside (on an even grid, ``(qdot_{k+1} - qdot_{k-1}) /
  (t_{k+1} - t_{k-1})``), first-order one-sided ones at the two ends, zero for a
  single sample. They are taken over every recorded sample *before* decimation.

``every = K`` keeps every K-th recorded sample and always the last one.

CSV (``trajectory.csv``): a header ``time, <joint>.position, <joint>.velocity,
<joint>.acceleration, ...`` (three columns per joint, in the model's velocity
order), then one row per sample; numbers written in full precision (Python's
shortest round-trip form).

JSON (``trajectory.json``): a ROS ``trajectory_msgs/JointTrajectory``::

    {"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
     "joint_names": [...],
     "points": [{"positions": [...], "velocities": [...], "accelerations": [...],
                 "effort": [], "time_from_start": {"sec": s, "nanosec": ns}}, ...]}

``time_from_start`` is ``t_k - t_0`` rounded to the nanosecond.
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from clik.errors import ExportError, InputError
from clik.model.base import BASE_JOINT, FIXED, base_kind
from clik.outputs.io import atomic_write

FORMATS = ("csv", "json")
"""The export formats: ``csv`` (``trajectory.csv``) and ``json`` (``trajectory.json``)."""

FILE_NAMES = {"csv": "trajectory.csv", "json": "trajectory.json"}
"""The file each format writes, in the output folder."""


@dataclass(frozen=True)
class JointTrajectory:
    """Samples of a joint trajectory, one column per joint.

    Attributes:
        joint_names: The joints, one per column (n,).
        time: Sample times (M,) [s].
        positions: Joint positions (M, n) [rad or m].
        velocities: Joint velocities (M, n) [rad/s or m/s].
        accelerations: Joint accelerations (M, n) [rad/s^2 or m/s^2].
    """

    joint_names: list[str]
    time: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray


def check_formats(formats: str | Iterable[str]) -> tuple[str, ...]:
    """The formats asked for, each once, in the order given; refuses an unknown one.

    Args:
        formats: A name among :data:`FORMATS`, or several.

    Raises:
        InputError: An unknown format, or none.
    """
    chosen = (formats,) if isinstance(formats, str) else tuple(dict.fromkeys(formats))
    if not chosen or any(f not in FORMATS for f in chosen):
        raise InputError("formats", f"one or more of {', '.join(map(repr, FORMATS))}", formats)
    return chosen


def check_every(every: object) -> int:
    """``every`` as an int >= 1 (the export decimation).

    Raises:
        InputError: Not an integer >= 1.
    """
    if isinstance(every, bool) or not isinstance(every, int | np.integer) or every < 1:
        raise InputError("every", "an integer >= 1", every)
    return int(every)


def check_exportable(model: Any) -> None:
    """Refuse a model with a joint that is neither 1-DOF nor continuous.

    Args:
        model: A ``pinocchio.Model``.

    Raises:
        ExportError: Naming the first such joint.
    """
    for name, joint in zip(list(model.names)[1:], list(model.joints)[1:], strict=True):
        if joint.nv != 1 or joint.nq not in (1, 2):
            if name == BASE_JOINT and base_kind(model) != FIXED:
                raise ExportError(
                    f"joint {name!r} is the robot's {base_kind(model)} base ({joint.shortname()}, "
                    f"nq {joint.nq}, nv {joint.nv}): a controller's joint trajectory has no "
                    "entry for a base's pose; the run's trajectory.npz holds it per sample "
                    f"(q[:, :{joint.nq}]), only revolute, prismatic and continuous joints can "
                    "be exported"
                )
            raise ExportError(
                f"joint {name!r} ({joint.shortname()}, nq {joint.nq}, nv {joint.nv}) has no "
                "single position per velocity; only revolute, prismatic and continuous "
                "joints can be exported"
            )


def joint_positions(q: np.ndarray, model: Any) -> np.ndarray:
    """One position per velocity coordinate (N, nv) [rad or m] from configurations (N, nq).

    A continuous joint's ``(cos, sin)`` becomes its angle, unwrapped along the samples.

    Args:
        q: Configurations (N, nq).
        model: Their ``pinocchio.Model``.
    """
    check_exportable(model)
    q = np.asarray(q, dtype=float)
    out = np.empty((q.shape[0], int(model.nv)))
    for joint in list(model.joints)[1:]:
        i, v = joint.idx_q, joint.idx_v
        if joint.nq == 1:
            out[:, v] = q[:, i]
        else:
            out[:, v] = np.unwrap(np.arctan2(q[:, i + 1], q[:, i]))
    return out


def finite_accelerations(t: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    """Accelerations (N, nv) [rad/s^2 or m/s^2] by finite differences of ``qdot`` over ``t``.

    ``numpy.gradient`` with the sample times: second-order central differences
    inside, first-order one-sided at the ends; zeros for a single sample.

    Args:
        t: Sample times (N,), increasing [s].
        qdot: Velocities (N, nv) [rad/s or m/s].
    """
    qdot = np.asarray(qdot, dtype=float)
    if qdot.shape[0] < 2:
        return np.zeros_like(qdot)
    return np.asarray(np.gradient(qdot, np.asarray(t, dtype=float), axis=0, edge_order=1))


def decimated(n: int, every: int) -> np.ndarray:
    """Indices of the kept samples among ``n``: every ``every``-th and the last."""
    index = np.arange(0, n, check_every(every))
    if n and index[-1] != n - 1:
        index = np.append(index, n - 1)
    return index


def joint_trajectory(
    t: np.ndarray, q: np.ndarray, qdot: np.ndarray, model: Any, every: int = 1
) -> JointTrajectory:
    """The exported samples of a recorded run.

    Args:
        t: Recorded sample times (N,) [s].
        q: Recorded configurations (N, nq).
        qdot: Recorded velocities (N, nv) [rad/s or m/s].
        model: The run's ``pinocchio.Model`` (joint names and kinds).
        every: Keep every ``every``-th sample and the last.

    Raises:
        ExportError: A joint that cannot be exported, or a non-finite value.
    """
    positions = joint_positions(q, model)
    velocities = np.asarray(qdot, dtype=float)
    accelerations = finite_accelerations(t, velocities)
    keep = decimated(len(t), every)
    columns = (np.asarray(t, dtype=float)[keep], positions[keep], velocities[keep])
    if not all(np.all(np.isfinite(c)) for c in columns):
        raise ExportError("the trajectory holds non-finite values (the run diverged)")
    return JointTrajectory(
        joint_names=list(model.names)[1:],
        time=columns[0],
        positions=columns[1],
        velocities=columns[2],
        accelerations=accelerations[keep],
    )


def csv_text(trajectory: JointTrajectory) -> str:
    """The trajectory as CSV: ``time``, then position, velocity, acceleration per joint."""
    header = ["time"]
    for name in trajectory.joint_names:
        header += [f"{name}.position", f"{name}.velocity", f"{name}.acceleration"]
    table = np.stack(
        [trajectory.positions, trajectory.velocities, trajectory.accelerations], axis=2
    ).reshape(len(trajectory.time), -1)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    for tk, row in zip(trajectory.time.tolist(), table.tolist(), strict=True):
        writer.writerow([repr(tk), *map(repr, row)])
    return buffer.getvalue()


def _duration(seconds: float) -> dict[str, int]:
    """``builtin_interfaces/Duration``: whole seconds and nanoseconds."""
    sec, nanosec = divmod(round(seconds * 1e9), 1_000_000_000)
    return {"sec": int(sec), "nanosec": int(nanosec)}


def ros_trajectory(trajectory: JointTrajectory, frame_id: str = "") -> dict[str, Any]:
    """The trajectory as a ROS ``trajectory_msgs/JointTrajectory``, JSON-ready.

    Args:
        trajectory: The samples.
        frame_id: The header's frame id.
    """
    start = float(trajectory.time[0]) if len(trajectory.time) else 0.0
    points = [
        {
            "positions": p,
            "velocities": v,
            "accelerations": a,
            "effort": [],
            "time_from_start": _duration(tk - start),
        }
        for tk, p, v, a in zip(
            trajectory.time.tolist(),
            trajectory.positions.tolist(),
            trajectory.velocities.tolist(),
            trajectory.accelerations.tolist(),
            strict=True,
        )
    ]
    return {
        "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": frame_id},
        "joint_names": list(trajectory.joint_names),
        "points": points,
    }


def json_text(trajectory: JointTrajectory) -> str:
    """The trajectory as ROS-style JSON text (:func:`ros_trajectory`), one point per line."""
    data = ros_trajectory(trajectory)
    points = ",\n".join(json.dumps(p, allow_nan=False) for p in data.pop("points"))
    head = json.dumps(data, allow_nan=False)[:-1]  # without its closing brace
    return f'{head}, "points": [\n{points}\n]}}\n'


def write_trajectory(
    trajectory: JointTrajectory, out: Path, formats: str | Sequence[str] = FORMATS
) -> dict[str, Path]:
    """Write the trajectory into folder ``out`` (atomically, one file per format).

    Args:
        trajectory: The samples.
        out: The output folder (created if missing).
        formats: Among :data:`FORMATS`.

    Returns:
        The file written per format.
    """
    written: dict[str, Path] = {}
    for fmt in check_formats(formats):
        path = Path(out) / FILE_NAMES[fmt]
        text = csv_text(trajectory) if fmt == "csv" else json_text(trajectory)
        _write_text(path, text)
        written[fmt] = path
    return written


def _write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    atomic_write(path, lambda f: f.write(text), mode="w")
