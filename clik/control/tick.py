"""What one tick of a :class:`~clik.control.Controller` gives back."""

from __future__ import annotations

from abc import ABCMeta
from dataclasses import dataclass, field
from typing import Any

import numpy as np

VERDICTS = ("ok", "deadlock", "violated", "diverged", "off_track", "measurement_jump")
"""A tick's verdicts (docs/method.md, "Online control"), the worst first when several hold:
``diverged``, ``deadlock``, ``measurement_jump``, ``violated``, ``off_track``, then
``ok``."""


@dataclass(slots=True)
class Tick(metaclass=ABCMeta):
    """One tick: the next joints, this tick's events and errors, and a verdict.

    The compiled engine returns its own form, ``clik._engine.Tick``, with the same
    attributes (read-only); ``isinstance(tick, Tick)`` holds for both. A tick's arrays are
    its own copies (the compiled engine's made when first read): keep them, write into
    them, nothing else changes.

    Attributes:
        q: ``q_{k+1}``, the joints to command next (nq,) [rad or m]; ``q_k`` itself
            when the verdict is ``diverged`` (the step is not applied).
        qdot: ``qdot_k``, the law's joint velocity at this tick (nv,) [rad/s or m/s].
        t: This tick's time ``t_k`` [s] (``k dt`` since the last reset).
        k: This tick's index.
        verdict: ``"ok"``, ``"deadlock"``, ``"violated"``, ``"diverged"``,
            ``"off_track"`` or ``"measurement_jump"`` (a ``q_measured`` refused by eq.
            (M3): the tick ran from the controller's own joints) (:data:`VERDICTS`).
        reason: What happened, with numbers ("" when ``ok``).
        events: This tick's constraint events, ``{"t", "constraint", "action"}``
            (``action``: ``"activate"``, ``"release"`` or ``"skipped"``).
        active: The constraints whose rows are active at this tick, in row order.
        errors: Each task's error norms by name, ``(first, second)``: a frame task's
            position [m] (or orientation [rad] for an orientation task) and orientation
            [rad] errors, a posture's [rad or m] and 0, a centre of mass's [m] and 0.
    """

    q: np.ndarray
    qdot: np.ndarray
    t: float
    k: int
    verdict: str = "ok"
    reason: str = ""
    events: list[dict[str, Any]] = field(default_factory=list)
    active: list[str] = field(default_factory=list)
    errors: dict[str, tuple[float, float]] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Whether the verdict is ``ok``."""
        return self.verdict == "ok"
