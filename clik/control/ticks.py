"""One tick in each engine: the offline run's own sample, called once per control tick.

A controller keeps an open run (:class:`clik.loop.tracking._Run` on a
:class:`~clik.loop.clock.Clock`, its record a ring) and, at each tick, runs the one
sample of it that ``clik.track`` runs in its loop: :meth:`_Run.sample` in the Python
engine, ``TrackingRun.advance(k, k + 1)`` in the compiled one. What differs from an
offline run is only what happens after a check fires (docs/method.md, "Online
control"): the session goes on; a divergence holds the joints.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from clik.constraints.violations import ViolationRecord
from clik.loop.compiled_run import CompiledConstraints, engine_run, stopped, synced

if TYPE_CHECKING:
    from clik.loop.tracking import _Run

Stop = tuple[str, str] | None
"""A check that fired at the tick: its status (``"deadlock"``, ``"diverged"``) and reason."""


class PythonTicks:
    """Ticks of an open run in the Python engine (the specification)."""

    def __init__(self, run: _Run, q: np.ndarray) -> None:
        self.run = run
        self.q = np.array(q, dtype=float)
        run.rec.start(self.q)

    def tick(self, k: int, refs: tuple[Any, ...]) -> Stop:
        """Sample ``k`` at :attr:`q` with this tick's references; :attr:`q` becomes next."""
        run = self.run
        p_d, R_d, ff, at_rest, g_ref, g_ff = refs
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            stop = run.sample(
                k, self.q, None if p_d is None else p_d[0], None if R_d is None else R_d[0],
                ff[0], bool(at_rest[0]), None if g_ref is None else g_ref[0],
                None if g_ff is None else g_ff[0],
            )  # fmt: skip
            if stop is None or stop[0] != "diverged":
                self.q = run.integrate(self.q)
        return stop

    @property
    def qdot(self) -> np.ndarray:
        """``qdot_k`` of the last tick."""
        return self.run.qdot

    @property
    def notes(self) -> int:
        """Limits crossed so far, counted at every tick."""
        return self.run.monitor.notes

    def events_since(self, n: int) -> list[dict[str, Any]]:
        """Constraint events after the first ``n``."""
        crun = self.run.crun
        return [] if crun is None else list(crun.events[n:])

    def active(self) -> list[str]:
        """The constraints active at the last tick."""
        crun = self.run.crun
        return [] if crun is None else crun.active_names()

    def errors(self) -> list[tuple[float, float]]:
        """Each task's error norms at the last tick, in task order."""
        run = self.run
        out = [(float(run.err), float(run.err_rot))]
        if run.goals.rows is not None:
            out += [(float(a), float(b)) for a, b in run.goals.rows.last]
        return out

    def crossed(self, tk: float) -> list[Any]:
        """The limits crossed at time ``tk`` (their violation records)."""
        return [r for r in self.run.monitor.records.values() if r.t_last == tk]

    def sync(self) -> None:
        """Nothing to bring back: the run is in Python."""


class CompiledTicks(PythonTicks):
    """Ticks of an open run in the compiled engine (``TrackingRun.advance(k, k + 1)``)."""

    def __init__(self, run: _Run, q: np.ndarray) -> None:
        self.run = run
        self.q = np.array(q, dtype=float)
        self.native = engine_run(run)

    def tick(self, k: int, refs: tuple[Any, ...]) -> Stop:
        """Sample ``k`` in the engine; :attr:`q` is updated in place to the next joints."""
        p_d, R_d, ff, at_rest, g_ref, g_ff = refs
        more = {} if g_ref is None else {"goal_ref": g_ref, "goal_ff": g_ff}
        out = self.native.advance(k, k + 1, p_d, R_d, ff, at_rest, self.q, **more)
        if not out[1]:
            return None
        run: Any = self.run
        if run.cset is not None:  # the active constraints' names, for the reason
            live = {"limit": 0, "active_names": self.native.active_names, "skipped": []}
            run.crun = CompiledConstraints(run.cset, live)
        return stopped(run, self.native, out)

    @property
    def qdot(self) -> np.ndarray:
        """``qdot_k`` of the last tick."""
        return np.asarray(self.native.qdot)

    @property
    def notes(self) -> int:
        """Limits crossed so far, counted at every tick."""
        return int(self.native.notes)

    def events_since(self, n: int) -> list[dict[str, Any]]:
        """Constraint events after the first ``n``."""
        return [
            {"t": t, "constraint": name, "action": action}
            for t, name, action in self.native.events_since(n)
        ]

    def active(self) -> list[str]:
        """The constraints active at the last tick."""
        return list(self.native.active_names)

    def errors(self) -> list[tuple[float, float]]:
        """Each task's error norms at the last tick, in task order."""
        native = self.native
        out = [(float(native.last_error), float(native.last_orientation_error))]
        if self.run.goals.rows is not None:
            out += [(float(a), float(b)) for a, b in np.asarray(native.goal_last)]
        return out

    def crossed(self, tk: float) -> list[Any]:
        """The limits crossed at time ``tk`` (their violation records)."""
        self.sync_violations()
        return super().crossed(tk)

    def sync_violations(self) -> None:
        """The engine's violation records into the run's monitor."""
        synced_violations(self.run, self.native)

    def sync(self) -> None:
        """The engine's state into the run (before its result is made)."""
        synced(self.run, self.native)


def synced_violations(run: _Run, native: Any) -> None:
    """The engine's violation records into ``run.monitor`` (as :func:`synced` does)."""
    for constraint, kind, t_first, t_last, worst in native.violations:
        record = ViolationRecord(constraint, kind, t_first, worst)
        record.t_last = t_last
        run.monitor.records[constraint] = record
