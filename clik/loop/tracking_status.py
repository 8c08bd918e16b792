"""Did a run that reached its end track its reference, within the joints' speed limits?

docs/method.md, "Statuses and violations". A run that reached the end of its
trajectory is ``completed`` only when it also

1. crossed no limit (else ``violated``: :meth:`clik.loop.tracking._Run._final_status`);
2. kept every joint within its speed limit (else ``velocity_limit``,
   :func:`speed_excess`): ``|qdot_i| <= v_i (1 + 1e-9)`` at every recorded sample, ``v_i``
   the law's bound (``info["joint_speed"]["velocity"]``) when the run had one, else the
   URDF's ``<limit velocity>`` where it is finite and positive;
3. tracked its reference (else ``off_track``, :func:`off_track`): the task error never
   stayed above the tolerance for longer than the settling time, and is within it at the
   last sample.

The rules read the recorded samples of the result only, so both engines give the same
status. :func:`judge` applies them in that order.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import InputError

if TYPE_CHECKING:
    from clik.outputs.result import TrackingResult

SPEED_ROUNDING = 1e-9
"""A recorded speed above its bound by more than this fraction of it is above its limit."""

DEFAULT_TOLERANCE = (0.01, 0.05)
"""Default task error tolerance: position [m], orientation [rad]."""

DEFAULT_SETTLING_TIME = 0.5
"""Default time [s] the task error may stay above the tolerance."""


@dataclass(frozen=True)
class Tolerance:
    """How closely a run must track its reference (``Tracker.run``'s settings).

    Attributes:
        position: Largest position error [m] (the task error of a position or pose task).
        orientation: Largest orientation error [rad].
        settling_time: Longest time [s] the error may stay above the tolerance (a start
            far from the reference, a corner of the path).
    """

    position: float = DEFAULT_TOLERANCE[0]
    orientation: float = DEFAULT_TOLERANCE[1]
    settling_time: float = DEFAULT_SETTLING_TIME

    def as_dict(self) -> dict[str, float]:
        """``{"position", "orientation", "settling_time"}`` (``result.info["tolerance"]``)."""
        return {
            "position": self.position,
            "orientation": self.orientation,
            "settling_time": self.settling_time,
        }


def _positive(value: object, field: str, unit: str) -> float:
    expected = f"a finite number > 0 {unit}"
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise InputError(field, expected, value)
    number = float(value)
    if not math.isfinite(number) or number <= 0.0:
        raise InputError(field, expected, value)
    return number


def checked_tolerance(tolerance: Sequence[float], settling_time: float) -> Tolerance:
    """``Tracker.run``'s ``tolerance`` (position [m], orientation [rad]) and ``settling_time``.

    Raises:
        InputError: Not a pair, or a value that is not a finite number > 0 (named:
            ``tolerance[0]``, ``tolerance[1]``, ``settling_time``).
    """
    if isinstance(tolerance, str) or not isinstance(tolerance, Sequence | np.ndarray):
        raise InputError("tolerance", "a pair (position [m], orientation [rad])", tolerance)
    if len(tolerance) != 2:
        raise InputError("tolerance", "a pair (position [m], orientation [rad])", tolerance)
    return Tolerance(
        _positive(tolerance[0], "tolerance[0]", "(position [m])"),
        _positive(tolerance[1], "tolerance[1]", "(orientation [rad])"),
        _positive(settling_time, "settling_time", "[s]"),
    )


# -- rule 2: joint speeds ---------------------------------------------------------------


def speed_bounds(result: TrackingResult) -> np.ndarray | None:
    """The bound on ``|qdot_i|`` per velocity coordinate [rad/s or m/s] (nan: none).

    The law's own (``info["joint_speed"]["velocity"]``, its scale applied) when the run
    had one, else the URDF's limits where finite and > 0; None when there are none.
    """
    joint_speed = result.info.get("joint_speed")
    if joint_speed is not None and joint_speed.get("velocity") is not None:
        return np.asarray(joint_speed["velocity"], dtype=float)
    if result.velocity_limits is None:
        return None
    limit = np.array(result.velocity_limits.limit, dtype=float)
    limit[~(np.isfinite(limit) & (limit > 0.0))] = np.nan
    return limit


def speed_excess(result: TrackingResult) -> str | None:
    """Why the run is ``velocity_limit`` (the fastest joint past its bound), or None.

    Rule 2 of the module docstring, on the recorded ``qdot``.
    """
    bound = speed_bounds(result)
    if bound is None or result.qdot.shape[0] == 0 or bound.shape[0] != result.qdot.shape[1]:
        return None
    limited = np.isfinite(bound) & (bound > 0.0)
    # Each coordinate's fastest sample first (along the rows of the transposed copy:
    # ~10x faster than along axis 0 of a long (N, nv) array); max(s) / b == max(s / b)
    # exactly (rounding is monotonic), so no sample is over when no coordinate's peak is.
    peak = np.abs(np.ascontiguousarray(result.qdot.T)).max(axis=1)
    if np.isfinite(peak).all():
        with np.errstate(invalid="ignore"):
            peak_ratio = np.where(limited, peak / bound, 0.0)
        if not (peak_ratio > 1.0 + SPEED_ROUNDING).any():
            return None
    speed = np.abs(result.qdot)
    speed[~np.isfinite(speed)] = 0.0
    with np.errstate(invalid="ignore"):
        ratio = np.where(limited, speed / bound, 0.0)
    over = ratio > 1.0 + SPEED_ROUNDING
    if not over.any():
        return None
    k, i = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
    names = result.velocity_limits.names if result.velocity_limits is not None else []
    name = names[i] if i < len(names) else f"coordinate {i}"
    sources = result.velocity_limits.sources() if result.velocity_limits is not None else []
    which = (
        "the law's bound"
        if "velocity" in (result.info.get("joint_speed") or {})
        else ("its base speed" if sources[i : i + 1] == ["base_speed"] else "its URDF limit")
    )
    return (
        f"joint {name} above its speed limit: {speed[k, i]:.4g} at t = {result.t[k]:.6g} s, "
        f"{ratio[k, i]:.3g} times {which} {bound[i]:.4g} (rad/s or m/s); "
        f"{int(over.any(axis=0).sum())} joint(s) above their limit on "
        f"{int(over.any(axis=1).sum())} recorded sample(s)"
    )


# -- rule 3: tracking -------------------------------------------------------------------


@dataclass(frozen=True)
class Stretch:
    """Consecutive recorded samples ``a .. b`` (inclusive) of one error above its tolerance."""

    a: int
    b: int
    error: str
    unit: str
    tolerance: float
    values: np.ndarray

    def peak(self) -> int:
        """The recorded sample of the largest error in the stretch (a non-finite one first)."""
        part = np.asarray(self.values[self.a : self.b + 1], dtype=float)
        bad = np.flatnonzero(~np.isfinite(part))
        return self.a + int(bad[0] if bad.size else np.argmax(part))


def _stretches(over: np.ndarray) -> list[tuple[int, int]]:
    """Runs of True in ``over``, as inclusive index pairs."""
    edges = np.diff(np.concatenate(([0], over.astype(np.int8), [0])))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return list(zip(starts.tolist(), ends.tolist(), strict=True))


def _errors(result: TrackingResult, tol: Tolerance) -> list[tuple[str, str, float, np.ndarray]]:
    """Each recorded error with its name, unit and tolerance (its kind's words: ``task_errors``)."""
    entries = list(result.task_errors.items())
    primary = entries[0][1] if entries else {}
    unit = str(primary.get("unit", "m"))
    name = "task error" if unit == "m" else str(primary.get("error", "task error"))
    out = [(name, unit, _tolerance(tol, unit), result.task_error_norm)]
    if result.orientation_error_norm is not None and "second_unit" in primary:
        second = str(primary["second_unit"])
        label = str(primary.get("second_error", "orientation error"))
        out.append((label, second, _tolerance(tol, second), result.orientation_error_norm))
    return out + _other_tasks_errors(result, tol)


def _tolerance(tol: Tolerance, unit: str) -> float:
    """The tolerance of an error in ``unit``: the position one for [m], else the orientation one."""
    return tol.position if unit == "m" else tol.orientation


def _other_tasks_errors(
    result: TrackingResult, tol: Tolerance
) -> list[tuple[str, str, float, np.ndarray]]:
    """The recorded errors of the first level's other tasks (lower levels give way)."""
    record = result.extra.get("task_errors")
    entries = list(result.task_errors.items())[1:]
    if record is None or not entries:
        return []
    top = min(int(e.get("priority", 1)) for _, e in result.task_errors.items())
    out = []
    for i, (name, entry) in enumerate(entries):
        if int(entry.get("priority", 1)) != top:
            continue
        unit = str(entry.get("unit", "m"))
        out.append((f"error of task {name!r}", unit, _tolerance(tol, unit), record[:, i, 0]))
        if "second_unit" in entry:
            second = str(entry["second_unit"])
            label = f"{entry.get('second_error', 'orientation error')} of task {name!r}"
            out.append((label, second, _tolerance(tol, second), record[:, i, 1]))
    return out


def off_track_stretch(result: TrackingResult, tol: Tolerance) -> Stretch | None:
    """The longest stretch above the tolerance that makes the run ``off_track``, or None.

    A stretch counts when it lasts longer than ``tol.settling_time`` (from its first to
    its last recorded sample) or holds the last sample.
    """
    t, n = result.t, result.t.shape[0]
    found: list[Stretch] = []
    for name, unit, limit, error in _errors(result, tol):
        over = ~(np.asarray(error) <= limit)  # a non-finite error is above too
        for a, b in _stretches(over):
            if t[b] - t[a] > tol.settling_time or b == n - 1:
                found.append(Stretch(a, b, name, unit, limit, error))
    if not found:
        return None
    return max(found, key=lambda s: float(t[s.b] - t[s.a]))


def _holding(result: TrackingResult, a: int, b: int) -> list[str]:
    """Constraints whose rows were active at some recorded sample ``a .. b``."""
    active = result.extra.get("active")
    names = result.info.get("constraint_names", [])
    if active is None or not names:
        return []
    codes = np.unique(np.asarray(active[a : b + 1]))
    return [names[c] for c in codes.tolist() if 0 <= c < len(names)]


def off_track(result: TrackingResult, tol: Tolerance) -> str | None:
    """Why the run is ``off_track`` (rule 3 of the module docstring), or None."""
    s = off_track_stretch(result, tol)
    if s is None:
        return None
    t, peak = result.t, s.peak()
    last = " (and at the last sample)" if s.b == t.shape[0] - 1 else ""
    holding = _holding(result, s.a, s.b)
    why = (
        f"while constraint(s) {', '.join(holding)} held the arm off the reference"
        if holding
        else "with no constraint in conflict"
    )
    return (
        f"off_track: the {s.error} stayed above the tolerance {s.tolerance:g} {s.unit} for "
        f"{t[s.b] - t[s.a]:.3g} s (t = {t[s.a]:.6g} .. {t[s.b]:.6g} s{last}, largest "
        f"{s.values[peak]:.4g} {s.unit} at t = {t[peak]:.6g} s) {why}; the settling time is "
        f"{tol.settling_time:g} s"
    )


# -- the status ---------------------------------------------------------------------------


RAN_TO_END = ("completed", "violated", "velocity_limit", "off_track")
"""Statuses of a run that reached the end of its trajectory."""


def judge(
    result: TrackingResult, tol: Tolerance, recovery: list[dict[str, Any]], clause: str = ""
) -> None:
    """Rules 2 and 3 on a run that ended ``completed``: its status and reason, in place.

    Stores the settings in ``result.info["tolerance"]`` and the ``recovery`` records
    (:mod:`clik.constraints.recovery`) in the summary's.

    Args:
        result: The run.
        tol: Its tolerance.
        recovery: One record per constraint the run started inside.
        clause: Those records in words, added to the reason of a run that reached its end.
    """
    result.info["tolerance"] = tol.as_dict()
    if recovery:
        result.info.setdefault("summary_extra", {})["recovery"] = recovery
    if result.status == "completed":
        end = " (the trajectory was run to its end)"
        why = speed_excess(result)
        if why is not None:
            lag = off_track(result, tol)
            result.status, result.reason = "velocity_limit", why + end
            result.reason += "" if lag is None else f"; also {lag}"
        elif (why := off_track(result, tol)) is not None:
            result.status, result.reason = "off_track", why + end
    if result.status in RAN_TO_END:
        result.reason += clause
