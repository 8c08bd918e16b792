"""A run that started inside a constraint's threshold: how deep, and how long it took out.

docs/method.md, "Statuses and violations". A run may start with a link inside an
obstacle's threshold, or a joint past a joint-range row's threshold: the row activates
at the first sample (an ``activate`` event, or ``skipped`` when no row was free, at
``t[0]``), or the pose is simply inside a threshold of a kind that adds no row. Each
such constraint gets one ``recovery`` record (``summary()["recovery"]``)::

    {"constraint", "depth", "t_start", "t_end", "duration", "recovered"}

``depth`` is the constraint's error at the start, how far inside its threshold [m or
rad, the kind's unit]; ``t_end`` the first recorded time [s] it was back at or outside
its threshold (its error at most :data:`BACK_AT_THRESHOLD` of ``depth``) or its row was
released, None if neither happened; ``duration = t_end - t_start`` [s] or None.

Errors are measured after the run, at the recorded configurations, by the single-pose
check of solve mode (:class:`~clik.constraints.pose_check.PoseCheck`, each kind's own
``check``), so both engines give the same records. That check takes each obstacle's
nearest link (an obstacle's rows on several links share its depth) and obstacles at
their start placement (a moving obstacle is not followed).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from clik.constraints.kind import Violation
from clik.constraints.pose_check import PoseCheck
from clik.constraints.registry import kind_of
from clik.constraints.words import AS_IS

if TYPE_CHECKING:
    from clik.constraints.constraint_set import ConstraintSet
    from clik.outputs.result import TrackingResult
    from clik.tasks.task import Task

BACK_AT_THRESHOLD = 1e-6
"""Back at its threshold: an error at most this fraction of the depth at the start."""

STARTED = ("activate", "skipped")
"""Event actions at ``t[0]`` that mean the run started inside that constraint's threshold."""


def check_name(key: str) -> str:
    """The pose check's name of a row key, as the kind that owns the key names it.

    ``obstacle:ball:link4`` -> ``obstacle 'ball'``
    (:meth:`~clik.constraints.kind.ConstraintKind.check_name`); a key no registered kind
    owns is its own name.
    """
    kind = kind_of(key)
    return key if kind is None else kind.check_name(key)


def _started_inside(result: TrackingResult) -> list[str]:
    """Keys of the rows activated (or skipped) at the first sample, in event order."""
    t0 = round(float(result.t[0]), 9)
    keys = [
        e["constraint"]
        for e in result.events
        if e["action"] in STARTED and abs(float(e["t"]) - t0) <= 1e-9
    ]
    return list(dict.fromkeys(keys))


def _released(result: TrackingResult, key: str) -> float | None:
    """The first time [s] the row ``key`` was released, or None."""
    times = [
        float(e["t"]) for e in result.events if e["constraint"] == key and e["action"] == "release"
    ]
    return min(times) if times else None


def _error(found: list[Violation], name: str) -> float:
    """The shortfall of constraint ``name`` among ``found`` (0: clear)."""
    return max((v.shortfall for v in found if v.constraint == name), default=0.0)


def _back(result: TrackingResult, check: PoseCheck, name: str, depth: float,
          released: float | None) -> float | None:  # fmt: skip
    """The first recorded time the constraint was back at its threshold, or released."""
    t = result.t
    last = t.shape[0] if released is None else int(np.searchsorted(t, released, side="right"))
    for j in range(1, last):
        if _error(check.violations(result.q[j]), name) <= BACK_AT_THRESHOLD * depth:
            return float(t[j])
    return released


def recovery_records(
    result: TrackingResult, cset: ConstraintSet, task: Task | None = None
) -> list[dict[str, Any]]:
    """One record per constraint the run started inside (see the module docstring).

    Args:
        result: The run (its recorded ``t``, ``q`` and its ``events``).
        cset: The run's constraint set.
        task: The task (the dexterity kind checks its rows), or None.
    """
    if result.t.shape[0] == 0:
        return []
    if not any(e["t"] == result.t[0] for e in result.events):  # nothing (de)activated at the
        return []  # start: no threshold was violated then (a violated one activates or skips)
    check = PoseCheck(cset, task)
    start = check.violations(result.q[0])
    keys = _started_inside(result)
    names = {check_name(k) for k in keys}
    keys += [v.constraint for v in start if v.constraint not in names]  # no row offered
    t0 = float(result.t[0])
    records = []
    for key in dict.fromkeys(keys):
        name = check_name(key)
        depth = _error(start, name)
        t_end = _back(result, check, name, depth, _released(result, key))
        records.append(
            {
                "constraint": key,
                "depth": depth,
                "t_start": t0,
                "t_end": t_end,
                "duration": None if t_end is None else round(t_end - t0, 9),
                "recovered": t_end is not None,
            }
        )
    return records


def recovery_clause(records: list[dict[str, Any]]) -> str:
    """``"; started inside the threshold of X (depth 8.8 mm), recovered in 0.031 s"``.

    Each depth is written as the kind that owns its key says
    (:attr:`~clik.constraints.kind.ConstraintKind.depth_measure`: mm for lengths).
    """
    out = ""
    for r in records:
        kind = kind_of(r["constraint"])
        depth = f"depth {(AS_IS if kind is None else kind.depth_measure).format(r['depth'])}"
        how = (
            f"recovered in {r['duration']:.3g} s"
            if r["recovered"]
            else "not back outside it by the end of the run"
        )
        out += f"; started inside the threshold of {r['constraint']} ({depth}), {how}"
    return out
