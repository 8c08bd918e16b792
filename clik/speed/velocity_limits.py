r"""A run that respects the joint speed limits: time scaling of the reference, in passes.

docs/method.md, "Joint speed limits: time scaling of the reference". The law runs
as configured (any engine, any constraints); from the recorded ``qdot`` (and
``qddot``) the ratio :math:`r_k` of each sample is computed
(:mod:`clik.speed.speed_limits`). While :math:`\max_k r_k > 1` the reference is re-timed
(:mod:`clik.speed.time_scaling`: the same path, its clock slowed where the joints were
too fast, :class:`~clik.trajectory.retimed.Retimed`) and the run is made again,
at most ``max_passes`` times, stopping early when a pass lowers the ratio by less
than :data:`PROGRESS` (one that raises it is undone and made again with a
smoother slowdown). The run kept is the one with the lowest ratio among those
that reached the end of their trajectory.

The passes run the law without the tracker's own joint speed limits
(:mod:`clik.loop.speed_step`: their ratios say how fast the law wants to go; with
the limits in the law they would stop at 1); when the tracker has them, the kept
reference is run once more with them, and that run is the result.

A run whose ratio stays above 1 (the law's own correction ``K e``, e.g. a start far
from the reference, is not slowed by time scaling) does not claim it respected
the limits: ``completed`` becomes ``velocity_limit``, with the joint, the ratio
and the time in its reason. Its record is in ``summary()["velocity_limits"]``
(see :func:`retiming_record`).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import InputError
from clik.loop.joint_speed import JointSpeed
from clik.loop.tracker import JOINT_SPEED, ReachWarning, StabilityWarning, Tracker
from clik.loop.tracking import ProgressCallback
from clik.loop.tracking_status import RAN_TO_END  # a run that reached its end: re-timed
from clik.speed.speed_limits import SpeedBounds, SpeedLimits
from clik.speed.time_scaling import retime, slowdown

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet
    from clik.loop.laws import LawName
    from clik.outputs.result import TrackingResult
    from clik.tasks.task import Task
    from clik.trajectory import Trajectory
    from clik.trajectory.retimed import Retimed

PROGRESS = 0.01
"""A pass must lower the largest ratio by this fraction of it, or re-timing stops."""


@dataclass
class _Passes:
    """The runs made so far: the one kept, the ratio of each, the current window [s]."""

    kept: TrackingResult
    kept_ratio: float
    ratios: list[float]
    window: float
    kept_retimed: Retimed | None = None
    kept_pass: int = 0
    stop: str = ""
    wall_time_s: float = 0.0

    def keep(self, result: TrackingResult, ratio: float, retimed: Retimed) -> None:
        """Keep ``result`` when it reached its end with a lower ratio than the kept run."""
        if result.status in RAN_TO_END and ratio < self.kept_ratio:
            self.kept, self.kept_ratio, self.kept_retimed = result, ratio, retimed
            self.kept_pass = len(self.ratios) - 1


def peak_ratio(result: TrackingResult, bounds: SpeedBounds) -> float:
    """The largest ratio :math:`r_k` over the recorded samples of ``result``."""
    ratio = bounds.ratio(result.qdot, result.qddot)
    return float(ratio.max()) if ratio.size else 0.0


def run_within_limits(
    tracker: Tracker,
    trajectory: Trajectory,
    q0: np.ndarray | Sequence[float] | None,
    limits: SpeedLimits,
    *,
    record_every: int = 1,
    settle: float = 0.0,
    progress: ProgressCallback | None = None,
    **run_settings: Any,
) -> TrackingResult:
    """Run ``tracker`` along ``trajectory``, re-timed until the joint speeds are within limits.

    A pass that raises the ratio by more than :data:`PROGRESS` (the slowdown's own
    changes of rate add acceleration) is undone: the next pass starts again from
    the run kept, with the window doubled. A pass that changes it by less than
    :data:`PROGRESS` either way ends the re-timing.

    Args:
        tracker: The law, gains and constraints (any engine).
        trajectory: The reference as given; its path is kept.
        q0: Start configuration (nq,) (default: the robot's reference configuration).
        limits: The speed limits and the re-timing settings.
        record_every: As :meth:`Tracker.run`; only recorded samples are compared.
        settle: As :meth:`Tracker.run` [s], after the stretched duration.
        progress: Called during the first run only.
        **run_settings: Further :meth:`Tracker.run` arguments (``tolerance``,
            ``settling_time``, ...), passed to every run.

    Returns:
        The run kept, its status ``velocity_limit`` when it ran to its end with its
        ratio above 1, and its record in ``info["summary_extra"]["velocity_limits"]``.

    Raises:
        JointNotFound: An acceleration limit for an unknown joint.
        InputError: A robot with no velocity limit and no acceleration limit given.
    """
    bounds = limits.bounds(tracker.robot)
    kwargs: dict[str, Any] = {"record_every": record_every, "settle": settle, **run_settings}
    limited, tracker = tracker, tracker.without_speed_limits()  # passes: the law's own speeds
    result = tracker.run(trajectory, q0, progress=progress, **kwargs)
    ratio = peak_ratio(result, bounds)
    passes = _Passes(result, ratio, [ratio], limits.window, wall_time_s=result.wall_time_s)
    retimed: Retimed | None = None
    while passes.kept_ratio > 1.0 and not passes.stop:
        passes.stop = _cannot_retime(result, trajectory, passes, limits)
        if passes.stop:
            break
        r_k = bounds.ratio(result.qdot, result.qddot)
        factor = slowdown(r_k, tracker.dt * record_every, passes.window, limits.margin)
        retimed = retime(trajectory, retimed, result.t, factor, tracker.dt)
        try:  # the stretched run within the step and record budgets
            tracker.check_size(retimed.duration + settle, record_every)
        except InputError as exc:
            passes.stop = f"stretching it further would exceed a budget ({exc})"
            break
        with warnings.catch_warnings():  # said once, by the first run
            warnings.simplefilter("ignore", ReachWarning)
            warnings.simplefilter("ignore", StabilityWarning)
            result = tracker.run(retimed, q0, **kwargs)
        new = peak_ratio(result, bounds)
        passes.ratios.append(new)
        passes.wall_time_s += result.wall_time_s
        passes.keep(result, new, retimed)
        if new > ratio * (1.0 + PROGRESS):  # undone: from the kept run, a smoother slowdown
            result, retimed, ratio = passes.kept, passes.kept_retimed, passes.kept_ratio
            passes.window *= 2.0
        elif new > ratio * (1.0 - PROGRESS):
            passes.stop = (
                f"a pass lowered the ratio by less than {PROGRESS:.0%} ({ratio:.3g} -> "
                f"{new:.3g}): the excess is not the reference's speed (e.g. the law's "
                "correction K e of a start far from the reference), which time scaling "
                "cannot slow"
            )
        ratio = new if new <= ratio * (1.0 - PROGRESS) else ratio
    if limited.speed is not None:
        _run_kept_with_limits(limited, passes, trajectory, q0, kwargs, bounds)
    return _finish(passes, bounds, limits, trajectory)


def _run_kept_with_limits(
    tracker: Tracker,
    passes: _Passes,
    trajectory: Trajectory,
    q0: np.ndarray | Sequence[float] | None,
    kwargs: dict[str, Any],
    bounds: SpeedBounds,
) -> None:
    """Run the kept reference once more, with the law's own speed limits: the result."""
    with warnings.catch_warnings():  # said once, by the first run
        warnings.simplefilter("ignore", ReachWarning)
        warnings.simplefilter("ignore", StabilityWarning)
        reference = trajectory if passes.kept_retimed is None else passes.kept_retimed
        passes.kept = tracker.run(reference, q0, **kwargs)
    passes.kept_ratio = peak_ratio(passes.kept, bounds)
    passes.wall_time_s += passes.kept.wall_time_s


def _cannot_retime(
    result: TrackingResult, trajectory: Trajectory, passes: _Passes, limits: SpeedLimits
) -> str:
    """Why no further pass is made ("" when one is)."""
    if len(passes.ratios) > limits.max_passes:
        return f"max_passes = {limits.max_passes} re-timing passes made"
    if result.status not in RAN_TO_END:
        return f"the last run ended {result.status!r} before the end of its trajectory"
    if trajectory.duration <= 0.0:
        return "the reference has no duration to stretch"
    return ""


def _finish(
    passes: _Passes, bounds: SpeedBounds, limits: SpeedLimits, trajectory: Trajectory
) -> TrackingResult:
    """The kept run with its status, reason and record."""
    result = passes.kept
    excess = bounds.worst(result.t, result.qdot, result.qddot)
    record = retiming_record(passes, limits, trajectory.duration)
    record["worst"] = excess.describe() if excess.ratio > 1.0 else None
    kept_duration = (
        trajectory.duration if passes.kept_retimed is None else passes.kept_retimed.duration
    )
    stretched = (
        f"{trajectory.duration:.6g} s stretched to {kept_duration:.6g} s"
        if passes.kept_retimed is not None
        else f"{trajectory.duration:.6g} s, not stretched"
    )
    n = len(passes.ratios) - 1
    if excess.ratio <= 1.0 and n == 0:
        result.reason += (
            f"; joint speeds within the limits (largest ratio {excess.ratio:.3g}; "
            "no re-timing needed)"
        )
    elif excess.ratio <= 1.0:
        result.reason += (
            f"; joint speeds within the limits (largest ratio {excess.ratio:.3g}, "
            f"{passes.ratios[0]:.3g} before re-timing; {n} re-timing pass(es), {stretched})"
        )
    else:
        clause = (
            f"joint speed limits not respected: {excess.describe()}; ratio "
            f"{passes.ratios[0]:.3g} before re-timing, {excess.ratio:.3g} after {n} "
            f"re-timing pass(es) ({stretched}); {passes.stop or 'no pass made'}"
        )
        if result.status == "completed":
            result.status, result.reason = "velocity_limit", clause
        else:
            result.reason += f"; {clause}"
    result.info["duration"] = float(trajectory.duration)
    result.info.setdefault("summary_extra", {})["velocity_limits"] = record
    return result


def retiming_record(passes: _Passes, limits: SpeedLimits, duration: float) -> dict[str, Any]:
    """The ``velocity_limits`` block of ``summary.json`` (see the README).

    Keys: ``enabled``, the settings (``scale``, ``acceleration``, ``margin``,
    ``max_passes``, ``window_s``), ``duration_s`` (the reference's own duration
    [s]), ``stretched_duration_s`` (the kept run's [s]), ``passes`` (re-timing
    passes made), ``kept_pass`` (0: the run as configured), ``max_ratio_before``
    (the first run's largest ratio), ``max_ratio`` (the kept run's),
    ``ratio_by_pass``, ``respected`` (``max_ratio <= 1``), ``stop`` (why
    re-timing stopped early, or "") and ``wall_time_all_passes_s`` (the loops of
    every run [s]; ``wall_time_s`` is the kept run's). :func:`_finish` adds
    ``worst``: the kept run's largest excess in words, or None.
    """
    return {
        "enabled": True,
        **limits.as_dict(),
        "duration_s": float(duration),
        "stretched_duration_s": float(
            duration if passes.kept_retimed is None else passes.kept_retimed.duration
        ),
        "passes": len(passes.ratios) - 1,
        "kept_pass": passes.kept_pass,
        "max_ratio_before": passes.ratios[0],
        "max_ratio": passes.kept_ratio,
        "ratio_by_pass": list(passes.ratios),
        "respected": passes.kept_ratio <= 1.0,
        "stop": passes.stop,
        "wall_time_all_passes_s": passes.wall_time_s,
    }


def track_within_limits(
    task: Task,
    trajectory: Trajectory,
    *,
    velocity_limits: SpeedLimits | None = None,
    q0: np.ndarray | Sequence[float] | None = None,
    law: LawName = "transpose",
    gain: float | Sequence[float] = 1000.0,
    dt: float = 1e-3,
    damping: float = 0.0,
    constraints: ConstraintSet | None = None,
    record_every: int = 1,
    progress: ProgressCallback | None = None,
    engine: str = "compiled",
    joint_speed: JointSpeed | None = JOINT_SPEED,
) -> TrackingResult:
    """:func:`clik.track` that respects the joint speed limits (the same arguments).

    Args:
        task: The task.
        trajectory: The reference; its path is kept, its timing stretched where needed.
        velocity_limits: The limits and the re-timing settings (default: ``SpeedLimits()``,
            the URDF velocity limits, no acceleration limit).
        q0: Start configuration (nq,).
        law: ``"transpose"`` (9), ``"nonlinear"`` (8) or ``"pseudoinverse"`` (10).
        gain: ``alpha`` or ``K`` [1/s], scalar or per task row.
        dt: Sample time [s].
        damping: Constant damping of law (10).
        constraints: Obstacle and joint-range rows.
        record_every: Keep every k-th sample; only recorded samples are compared.
        progress: Called during the first run.
        engine: ``"compiled"`` or ``"python"``.
        joint_speed: The joint speed limits the law keeps (the kept run's; None: none).

    Example:
        >>> limits = SpeedLimits(scale=0.8, acceleration=20.0)
        >>> result = track_within_limits(task, line, velocity_limits=limits, law="pseudoinverse")
        >>> result.summary()["velocity_limits"]["stretched_duration_s"]
    """
    tracker = Tracker(
        task, law=law, gain=gain, dt=dt, damping=damping, constraints=constraints, engine=engine,
        joint_speed=joint_speed,
    )  # fmt: skip
    limits = SpeedLimits() if velocity_limits is None else velocity_limits
    return run_within_limits(
        tracker, trajectory, q0, limits, record_every=record_every, progress=progress
    )
