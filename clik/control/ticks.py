"""One tick in each engine: the offline run's own sample, called once per control tick.

A controller keeps an open run (:class:`clik.loop.tracking._Run` on a
:class:`~clik.trajectory.clock.Clock`, its record a ring) and, at each tick, runs the
one sample of it that ``clik.track`` runs in its loop: :meth:`_Run.sample` in the Python
engine, ``TrackingRun.advance(k, k + 1)`` in the compiled one (through ``_engine.Ticker``,
which also reads a frame task's target directly: the fast path). What differs from an
offline run is what happens after a check fires (docs/method.md, "Online control"):
the session goes on, a divergence holds the joints, and the tick gets a verdict.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from clik.constraints.violations import ViolationRecord
from clik.control.tick import Tick
from clik.engine import load
from clik.loop.compiled_run import CompiledConstraints, engine_run, stopped, synced

if TYPE_CHECKING:
    from clik.constraints.obstacle import Obstacle
    from clik.loop.tracking import _Run

VERDICT_CODES = ("ok", "deadlock", "violated", "diverged", "off_track")
"""The verdicts by the engine's codes (``_engine.Ticker``)."""


class PythonTicks:
    """Ticks of an open run in the Python engine (the specification of the engine's)."""

    def __init__(self, run: _Run, q: np.ndarray) -> None:
        self.run = run
        self.q = np.array(q, dtype=float)
        run.rec.start(self.q)
        self._next = 0  # the next tick
        self.seen = 0  # events given in ticks so far
        self.notes = 0
        self.above_since: float | None = None

    def tick(self, k: int, refs: tuple[Any, ...]) -> tuple[str, str]:
        """Sample ``k`` at :attr:`q` with this tick's references; its verdict and reason.

        :attr:`q` becomes ``q_{k+1}`` (``q_k`` after a divergence).
        """
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
        self._next = k + 1
        return self.verdict(stop, float(run.t[k]))

    @property
    def k(self) -> int:
        """The next tick."""
        return self._next

    def verdict(self, stop: tuple[str, str] | None, tk: float) -> tuple[str, str]:
        """The worst verdict that holds at ``tk``: a check's, a limit crossed, off_track."""
        seen, self.notes = self.notes, self.run.monitor.notes
        if stop is not None:
            return stop
        if self.notes != seen:
            return "violated", violated_reason(self.crossed(tk))
        run, tol = self.run, self.run.tolerance
        limit = tol.position if run.task.has_position else tol.orientation
        above = not (run.err <= limit)
        if run.task.has_position and run.task.has_orientation:
            above = above or not (run.err_rot <= tol.orientation)
        if not above:
            self.above_since = None
            return "ok", ""
        if self.above_since is None:
            self.above_since = tk
        if tk - self.above_since <= tol.settling_time:
            return "ok", ""
        return "off_track", off_track_reason(run, self.above_since, tk)

    @property
    def qdot(self) -> np.ndarray:
        """``qdot_k`` of the last tick (a copy)."""
        return self.run.qdot.copy()

    def new_events(self) -> list[dict[str, Any]]:
        """The constraint events since the last tick that gave them."""
        crun = self.run.crun
        if crun is None:
            return []
        events = list(crun.events[self.seen :])
        self.seen += len(events)
        return events

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

    def crossed(self, tk: float) -> list[ViolationRecord]:
        """The limits crossed at time ``tk`` (their violation records)."""
        return [r for r in self.run.monitor.records.values() if r.t_last == tk]

    def move_obstacle(self, obstacle: Obstacle, position: np.ndarray, tk: float) -> None:
        """Obstacle ``obstacle`` (its new rpy and velocity) at ``position`` at time ``tk``."""
        assert self.run.crun is not None
        self.run.crun.move_obstacle(obstacle.moved(position - tk * obstacle.velocity))

    def sync(self) -> None:
        """Nothing to bring back: the run is in Python."""


class CompiledTicks(PythonTicks):
    """Ticks of an open run in the compiled engine (``_engine.Ticker``)."""

    def __init__(self, run: _Run, q: np.ndarray) -> None:
        self.run = run
        self.q = np.array(q, dtype=float)
        self.native = engine_run(run)
        self.qdot_buffer = np.zeros(run.robot.nv)  # written by the engine at each tick
        tol, engine = run.tolerance, load()
        Tick.register(engine.Tick)  # the fast path's ticks are Ticks
        self.ticker = engine.Ticker(
            self.native, self.q, self.qdot_buffer, tol.position, tol.orientation,
            tol.settling_time, name="task", empty=np.empty, ndarray=np.ndarray,
            float64=np.dtype(np.float64),
        )  # fmt: skip

    @property
    def k(self) -> int:
        """The next tick (the engine's run counts them)."""
        return int(self.native.next)

    def tick(self, k: int, refs: tuple[Any, ...]) -> tuple[str, str]:
        """Sample ``k`` in the engine; :attr:`q` is updated in place to the next joints."""
        p_d, R_d, ff, at_rest, g_ref, g_ff = refs
        out = self.ticker.step_arrays(
            None if p_d is None else p_d[0], None if R_d is None else R_d[0], ff[0], at_rest,
            None if g_ref is None else g_ref[0], None if g_ff is None else g_ff[0],
        )  # fmt: skip
        return self.verdict_of(out[0], float(self.run.t[k]))

    def verdict_of(self, code: int, tk: float) -> tuple[str, str]:
        """The engine's verdict ``code`` at ``tk`` and its reason, in words."""
        verdict = VERDICT_CODES[code]
        if verdict == "ok":
            return "ok", ""
        run: Any = self.run
        if verdict in ("deadlock", "diverged"):
            if run.cset is not None:  # the active constraints' names, for the reason
                live = {"limit": 0, "active_names": self.native.active_names, "skipped": []}
                run.crun = CompiledConstraints(run.cset, live)
            return stopped(run, self.native, self.ticker.stop)
        if verdict == "violated":
            return verdict, violated_reason(self.crossed(tk))
        run.err = self.native.last_error
        return verdict, off_track_reason(run, self.ticker.above_since, tk)

    @property
    def qdot(self) -> np.ndarray:
        """``qdot_k`` of the last tick (a copy)."""
        return self.qdot_buffer.copy()

    def new_events(self) -> list[dict[str, Any]]:
        """The constraint events since the last tick that gave them (either path)."""
        ticker = self.ticker
        events = [
            {"t": t, "constraint": name, "action": action}
            for t, name, action in self.native.events_since(ticker.seen)
        ]
        ticker.seen += len(events)
        return events

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

    def crossed(self, tk: float) -> list[ViolationRecord]:
        """The limits crossed at time ``tk`` (their violation records)."""
        return [
            _record(*v) for v in self.native.violations if v[3] == tk
        ]  # (constraint, kind, t_first, t_last, worst)

    def move_obstacle(self, obstacle: Obstacle, position: np.ndarray, tk: float) -> None:
        """Obstacle ``obstacle`` (its new rpy and velocity) at ``position`` at time ``tk``."""
        self.native.move_obstacle(obstacle.name, position, obstacle.velocity, obstacle.rotation)

    def sync(self) -> None:
        """The engine's state into the run (before its result is made)."""
        synced(self.run, self.native)


def _record(constraint: str, kind: str, t_first: float, t_last: float, worst: float) -> Any:
    record = ViolationRecord(constraint, kind, t_first, worst)
    record.t_last = t_last
    return record


def violated_reason(crossed: list[ViolationRecord]) -> str:
    """The ``violated`` verdict's reason: the worst limit crossed at this tick."""
    if not crossed:
        return "a limit was crossed"
    worst = max(crossed, key=lambda r: (r.kind == "obstacle", r.worst))
    more = f" ({len(crossed)} limits in all)" if len(crossed) > 1 else ""
    return f"a limit was crossed: {worst.describe()}{more}"


def off_track_reason(run: Any, since: float, tk: float) -> str:
    """The ``off_track`` verdict's reason: how long and how far above the tolerance."""
    tol = run.tolerance
    return (
        f"off_track: the task error has stayed above the tolerance ({tol.position:g} m, "
        f"{tol.orientation:g} rad) for {tk - since:.3g} s, since t = {since:.6g} s (now "
        f"{run.err:.4g}); the settling time is {tol.settling_time:g} s"
    )
