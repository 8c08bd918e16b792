"""When a run stops early: divergence, instability, deadlock and stall, checked every sample.

- **diverged**: a non-finite value, or a joint step ``|qdot| dt`` above
  ``max_joint_step`` (checked every sample, from the step the law just gave); or the
  gains break explicit Euler's bound while the task error grows past its tolerance
  (rechecked along the run: laws (9) and (8), ``dt lambda_max(K^1/2 J_e J_e^T K^1/2) < 2``;
  law (10), ``K dt < 2`` for every row).
- **deadlock** (Remark 2, docs/method.md): the law cannot reduce the task error.
  Laws (9) and (8): ``|J_e^T K e_e|`` tiny relative to ``|J_e| |K e_e|``. Law (10):
  most of the task's demand ``K e + xdot_d`` is not realised (the task and the active
  constraints conflict, or the task is singular). Either way only while the task error
  exceeds ``deadlock_error``, for ``deadlock_window`` seconds; or, with the reference at
  rest, the error falls by less than ``stall_progress`` over ``stall_window``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from clik.bounds import MAX_STEPS, in_range, real
from clik.errors import InputError
from clik.loop.gains import stability_margin
from clik.tasks.extended_task import ExtendedTask

BLOCKED_FRACTION = 0.5
"""Law (10): the task is blocked when more than this fraction of its demand is not realised."""

STABILITY_EVERY = 10
"""Samples between stability rechecks (laws (9) and (8))."""


@dataclass
class StopSettings:
    """Thresholds of the stop checks (see the module docstring), in their ranges.

    Attributes:
        deadlock_window: Time [s] a deadlock condition must hold before stopping, > 0 and
            at most :data:`~clik.bounds.MAX_STEPS` samples.
        deadlock_ratio: Laws (9), (8): ``|J_e^T K e_e| <= ratio |J_e|_F |K e_e|``, in
            [0, 1] (the ratio of those norms never exceeds 1).
        deadlock_error: Task error [m or rad] below which no deadlock is declared, >= 0.
        max_joint_step: A joint step above this [rad or m] is divergence, > 0.
        stall_window: Time [s] over which an error at rest must fall, as
            ``deadlock_window``.
        stall_progress: Fraction it must fall by, in [0, 1].

    All finite: :func:`checked_settings` refuses anything else, naming the argument.
    """

    deadlock_window: float = 0.1
    deadlock_ratio: float = 1e-4
    deadlock_error: float = 1e-3
    max_joint_step: float = 1.0
    stall_window: float = 0.5
    stall_progress: float = 0.01


def checked_settings(dt: float, **given: object) -> StopSettings:
    """The stop settings ``given`` (keyword: value), each checked against its range.

    Args:
        dt: The run's sample time [s] (windows are counted in samples).
        **given: Values of :class:`StopSettings`' fields.

    Raises:
        InputError: A value that is not a finite number in its range (named).
    """
    longest = MAX_STEPS * dt
    window = f"a time > 0 and <= {longest:g} [s] (clik.bounds.MAX_STEPS samples)"
    ranges = {
        "deadlock_window": (0.0, longest, True, window),
        "stall_window": (0.0, longest, True, window),
        "deadlock_ratio": (0.0, 1.0, False, "a ratio in [0, 1]"),
        "deadlock_error": (0.0, math.inf, False, "a finite task error >= 0 [m or rad]"),
        "max_joint_step": (0.0, math.inf, True, "a finite joint step > 0 [rad or m]"),
        "stall_progress": (0.0, 1.0, False, "a fraction in [0, 1]"),
    }
    out: dict[str, float] = {}
    for name, value in given.items():
        low, high, strict, expected = ranges[name]
        if not in_range(value, low, high, strict):
            raise InputError(name, expected, value)
        out[name] = real(value)
    return StopSettings(**out)


class StopChecks:
    """The stop conditions of one run, fed every sample.

    Args:
        settings: Thresholds.
        law: Law name.
        dt: Sample time [s].
    """

    def __init__(self, settings: StopSettings, law: str, dt: float) -> None:
        self.s, self.law, self.dt = settings, law, dt
        self.window = max(1, round(settings.deadlock_window / dt))
        self.stall_steps = max(1, round(settings.stall_window / dt))
        self.stuck = 0
        self.stall_k, self.stall_err = -1, 0.0
        self.margin = 0.0
        self.worst_margin = 0.0

    def divergence(self, t: float, qdot: np.ndarray, err: float) -> str | None:
        """A reason when the step just computed is non-finite or too large."""
        jump = float(np.abs(qdot).max()) * self.dt if qdot.size else 0.0
        if not (math.isfinite(err) and math.isfinite(jump)):
            return non_finite_reason(t)
        if jump > self.s.max_joint_step:
            return joint_step_reason(t, jump, err, self.s.max_joint_step)
        return None

    def instability(self, k: int, ext: ExtendedTask, r: int, err: float) -> str | None:
        """A reason when the gains break explicit Euler's bound and the error has grown."""
        if self.law == "pseudoinverse":
            kdt = float(ext.K[:r].max()) * self.dt
            self.margin = kdt
        elif k % STABILITY_EVERY == 0:
            J, K = ext.J[:r], ext.K[:r]
            bound = self.dt * float(np.einsum("i,ij,ij->", K, J, J))  # trace: >= lambda_max
            self.margin = stability_margin(J, K, self.dt) if bound >= 2.0 else bound
        self.worst_margin = max(self.worst_margin, self.margin)
        if self.margin < 2.0 or err <= self.s.deadlock_error:
            return None
        return instability_reason(self.law, self.margin, err)

    def deadlock(self, ext: ExtendedTask, r: int, err: float, blocked: float) -> bool:
        """Remark 2 held for ``deadlock_window``: the law cannot reduce the task error.

        Law (10) counts the samples where the task is blocked from the first one, whatever
        the error then (it is tiny while the blocked part of the demand is the reference's
        own speed), and stops once the window is full and the error exceeds
        ``deadlock_error``; laws (9) and (8) count only while the error exceeds it.
        """
        if self.law == "pseudoinverse":
            self.stuck = self.stuck + 1 if blocked > BLOCKED_FRACTION else 0
            return self.stuck >= self.window and err > self.s.deadlock_error
        if err <= self.s.deadlock_error:
            self.stuck = 0
            return False
        J, Ke = ext.J[:r], ext.K[:r] * ext.e[:r]
        force = float(np.linalg.norm(J.T @ Ke))
        scale = float(np.linalg.norm(J)) * float(np.linalg.norm(Ke))
        stuck_now = scale > 0.0 and force <= self.s.deadlock_ratio * scale
        self.stuck = self.stuck + 1 if stuck_now else 0
        return self.stuck >= self.window

    def stall(self, k: int, err: float, at_rest: bool) -> bool:
        """With the reference at rest, the error fell by too little over ``stall_window``."""
        if not (err > self.s.deadlock_error and at_rest):
            self.stall_k = -1
            return False
        if self.stall_k < 0:
            self.stall_k, self.stall_err = k, err
            return False
        if k - self.stall_k < self.stall_steps:
            return False
        stalled = err > (1.0 - self.s.stall_progress) * self.stall_err
        self.stall_k, self.stall_err = k, err
        return stalled


def non_finite_reason(t: float) -> str:
    """Why a run diverged: a non-finite value at ``t`` [s]."""
    return f"non-finite joint velocity or task error at t = {t:.6g} s"


def joint_step_reason(t: float, jump: float, err: float, max_joint_step: float) -> str:
    """Why a run diverged: a joint step ``jump`` [rad or m] above the bound."""
    return (
        f"a joint moved {jump:.3g} rad in one step at t = {t:.6g} s (task error "
        f"{err:.3g}, limit max_joint_step = {max_joint_step:g})"
    )


def instability_reason(law: str, margin: float, err: float) -> str:
    """Why a run diverged: the gains break explicit Euler's bound (``margin`` >= 2)."""
    if law == "pseudoinverse":
        return (
            f"the gain is too high for dt: K dt = {margin:.3g} >= 2 (law (10) is "
            f"stable for K dt < 2); the task error reached {err:.3g}"
        )
    return (
        f"explicit Euler is unstable: dt lambda_max(K J_e J_e^T) = {margin:.3g} >= 2 "
        f"along the path (lower the gain or dt); the task error reached {err:.3g}"
    )
