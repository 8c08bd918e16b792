"""Violations: every constraint whose *limit* (not its threshold) a run crossed.

A threshold is where a constraint's row switches on; a limit is what must never
be crossed: an obstacle's surface (a signed distance below zero), a joint's
limit (the tighter of the robot's own and a joint-range constraint's), two links
of the robot touching. A run records, per constraint, when the limit was first
and last crossed and the worst excursion:

``{"constraint", "t_first", "t_last", "worst"}``, ``worst`` being the deepest
penetration [m] or the largest excursion past the limit [rad or m].

A record reads as the kind that owns its key says
(:attr:`~clik.constraints.kind.ConstraintKind.limit_words`: "penetrated 3.2 mm deep",
"crossed by 12 deg"), found by the key
(:func:`clik.constraints.registry.limit_words`, given to the monitor by the loop).

A run that would be ``completed`` but has violations ends ``violated``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from clik.constraints.words import LimitWords
from clik.model.robot import Robot

JOINT_TOLERANCE = 1e-9
"""Excursion past a joint limit not counted (rounding) [rad or m]."""


class ViolationRecord:
    """First and last time a constraint's limit was crossed, and the worst excursion.

    Args:
        constraint: The constraint's key.
        kind: What the engine measured: ``"joint"``, ``"obstacle"`` (a penetration),
            ``"length"`` or ``"angle"`` (both engines' records carry it).
        t: The time it was first crossed [s].
        worst: The excursion then [m or rad].
        words: How it reads: the words of the kind that owns ``constraint``.
    """

    __slots__ = ("constraint", "kind", "t_first", "t_last", "words", "worst")

    def __init__(
        self, constraint: str, kind: str, t: float, worst: float, words: LimitWords
    ) -> None:
        self.constraint, self.kind = constraint, kind
        self.t_first = self.t_last = t
        self.worst = worst
        self.words = words

    def rank(self) -> tuple[bool, float]:
        """Which record is the worst: a penetration before any excursion, then the larger."""
        return (self.words.penetration, self.worst)

    def as_dict(self) -> dict[str, Any]:
        """The record as ``{"constraint", "t_first", "t_last", "worst"}``."""
        return {
            "constraint": self.constraint,
            "t_first": round(self.t_first, 9),
            "t_last": round(self.t_last, 9),
            "worst": float(self.worst),
        }

    def describe(self) -> str:
        """One line for a reason: what was crossed, by how much, when."""
        when = (
            f"at t = {self.t_first:.6g} s"
            if self.t_first == self.t_last
            else f"from t = {self.t_first:.6g} to {self.t_last:.6g} s"
        )
        return f"{self.words.describe(self.constraint, self.worst)} {when}"


class JointRange:
    """The joint limits a run must stay in: the robot's own, tightened by a constraint's.

    Args:
        robot: The robot (its URDF limits).
        tighter: A joint-range constraint's ``(lower, upper)`` per joint name [rad or m].
    """

    def __init__(
        self,
        robot: Robot,
        tighter: Mapping[str, tuple[float, float]] | None = None,
    ) -> None:
        index, low, high, labels = [], [], [], []
        model = robot.model
        given = tighter or {}
        for name, joint in zip(robot.joint_names, model.joints[1:], strict=True):
            if joint.nq != 1 or joint.nv != 1:
                continue  # continuous, spherical, free: no position limits
            i = joint.idx_q
            lo, hi = float(model.lowerPositionLimit[i]), float(model.upperPositionLimit[i])
            if name in given:
                lo, hi = max(lo, float(given[name][0])), min(hi, float(given[name][1]))
            if math.isfinite(lo) or math.isfinite(hi):
                index.append(i)
                low.append(lo)
                high.append(hi)
                labels.append(name)
        self.index = np.asarray(index, dtype=np.intp)
        self.lower = np.asarray(low)
        self.upper = np.asarray(high)
        self.names = labels


class ViolationMonitor:
    """Watches one run's limits, every sample.

    Args:
        joints: The joint limits to stay in.
        words: The words of a constraint's key
            (:func:`clik.constraints.registry.limit_words`).
    """

    def __init__(self, joints: JointRange, words: Callable[[str], LimitWords]) -> None:
        self.joints = joints
        self.words = words
        self.records: dict[str, ViolationRecord] = {}
        self.notes = 0
        """Limits crossed so far, counted at every sample (a controller's ``violated``)."""
        self._low = joints.lower - JOINT_TOLERANCE
        self._high = joints.upper + JOINT_TOLERANCE

    def observe_joints(self, t: float, q: np.ndarray) -> None:
        """Record joints past their limits at time ``t`` [s]."""
        if not self.joints.index.size:
            return
        qi = q[self.joints.index]
        if np.all(qi >= self._low) and np.all(qi <= self._high):
            return
        for s in np.flatnonzero(qi < self._low):
            self._note(
                f"joint:{self.joints.names[s]}:lower", "joint", t, self.joints.lower[s] - qi[s]
            )
        for s in np.flatnonzero(qi > self._high):
            self._note(
                f"joint:{self.joints.names[s]}:upper", "joint", t, qi[s] - self.joints.upper[s]
            )

    def observe_penetration(self, t: float, key: str, distance: float) -> None:
        """Record a signed distance below zero [m] (an obstacle or a link pair)."""
        self._note(key, "obstacle", t, -distance)

    def observe_excursion(self, t: float, key: str, kind: str, excess: float) -> None:
        """Record a limit crossed by ``excess`` > 0 [m or rad] (a wall, a cone's surface).

        ``kind`` is what was measured, ``"length"`` [m] or ``"angle"`` [rad], kept in the
        record as the compiled engine keeps it; the record's words are its key's kind's.
        """
        self._note(key, kind, t, excess)

    def _note(self, key: str, kind: str, t: float, excess: float) -> None:
        self.notes += 1
        rec = self.records.get(key)
        if rec is None:
            self.records[key] = ViolationRecord(key, kind, t, float(excess), self.words(key))
            return
        rec.t_last = t
        rec.worst = max(rec.worst, float(excess))

    def as_list(self) -> list[dict[str, Any]]:
        """The records, in the order the limits were first crossed."""
        return [r.as_dict() for r in sorted(self.records.values(), key=lambda r: r.t_first)]

    def worst(self) -> ViolationRecord | None:
        """The deepest penetration if any, else the largest excursion."""
        if not self.records:
            return None
        return max(self.records.values(), key=ViolationRecord.rank)
