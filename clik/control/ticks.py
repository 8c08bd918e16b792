"""One tick in each engine: the offline run's own sample, called once per control tick.

A controller keeps an open run (:class:`clik.loop.tracking._Run` on a
:class:`~clik.trajectory.clock.Clock`, its record a ring) and, at each tick, runs the
one sample of it that ``clik.track`` runs in its loop: :meth:`_Run.sample` in the Python
engine (:class:`PythonTicks`, the specification), ``TrackingRun.advance(k, k + 1)`` in the
compiled one (``_engine.Ticker``, ``src/engine/loop/bind_ticker.cpp``). Both take the
controller's turn (one thread at a time), read the tick's targets in the same two phases
(:mod:`clik.control.targets`), and return a tick that is entirely its own. What differs
from an offline run is what happens after a check fires (docs/method.md, "Online
control"): the session goes on, a divergence holds the joints, and the tick gets a verdict.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.constraints.registry import limit_words
from clik.constraints.violations import ViolationRecord
from clik.control.measured import MEASUREMENT_JUMP, JumpFound, MeasuredJoints
from clik.control.targets import TickTargets
from clik.control.tick import Tick
from clik.engine import load
from clik.loop.compiled_run import CompiledConstraints, stopped, synced

if TYPE_CHECKING:
    from clik.clouds.cloud_obstacle import CloudObstacle
    from clik.constraints.obstacle import Obstacle
    from clik.loop.tracking import _Run

_RANK = {
    "diverged": 5, "deadlock": 4, MEASUREMENT_JUMP: 3, "violated": 2, "off_track": 1, "ok": 0,
}  # fmt: skip


class Session:
    """One session of a controller (from a reset): its run and its worst verdict so far.

    Args:
        run: The session's open run.
        measured: The controller's measured joints (their reasons).
        native: The compiled engine's run (``_engine.TrackingRun``), or None.
    """

    def __init__(self, run: _Run, measured: MeasuredJoints, native: Any = None) -> None:
        self.run, self.measured, self.native = run, measured, native
        self.worst: tuple[str, str] = ("ok", "")
        self.jumps = 0  # ticks whose measurement was refused (M3)

    def note(self, verdict: str, reason: str) -> None:
        """Keep the session's worst verdict (its result's status)."""
        self.jumps += verdict == MEASUREMENT_JUMP
        if _RANK[verdict] > _RANK[self.worst[0]]:
            self.worst = (verdict, reason)

    def explain(
        self, tick: Any, stop: tuple[Any, ...], above_since: float, jump: JumpFound | None
    ) -> str:
        """A compiled tick's reason (its verdict other than ok), noted; the engine's call."""
        run: Any = self.run
        native = self.native
        verdict = tick.verdict
        if verdict == MEASUREMENT_JUMP:
            assert jump is not None
            reason = self.measured.reason(jump)
        elif verdict in ("deadlock", "diverged"):
            if run.cset is not None:  # the active constraints' names, for the reason
                live = {"limit": 0, "active_names": native.active_names, "skipped": []}
                run.crun = CompiledConstraints(run.cset, live)
            _, reason = stopped(run, native, stop)
        elif verdict == "violated":
            reason = violated_reason(self.crossed(tick.t))
        else:
            run.err = native.last_error
            reason = off_track_reason(run, above_since, tick.t)
        self.note(verdict, reason)
        return reason

    def crossed(self, tk: float) -> list[ViolationRecord]:
        """The limits crossed at time ``tk`` (their violation records)."""
        if self.native is None:
            return [r for r in self.run.monitor.records.values() if r.t_last == tk]
        return [_record(*v) for v in self.native.violations if v[3] == tk]

    def move_obstacle(self, obstacle: Obstacle, position: np.ndarray, tk: float) -> None:
        """Obstacle ``obstacle`` (its new rpy and velocity) at ``position`` at time ``tk``."""
        if self.native is not None:
            self.native.move_obstacle(obstacle.name, position, obstacle.velocity, obstacle.rotation)
            return
        assert self.run.crun is not None
        self.run.crun.move_obstacle(obstacle.moved(position - tk * obstacle.velocity))

    def replace_cloud(self, cloud: CloudObstacle, threshold: float) -> None:
        """Cloud ``cloud.name`` replaced by ``cloud`` (threshold [m]) from the next tick."""
        if self.native is not None:  # the spheres and grid built by the engine (cloud_build.cpp)
            config, _ = load().CloudConfig.build(
                cloud.name, cloud.local, cloud.voxel, cloud.rotation, cloud.position, threshold
            )
            self.native.replace_cloud(config)
            return
        assert self.run.crun is not None
        self.run.crun.replace_cloud(cloud)

    def sync(self) -> None:
        """The engine's state into the run (before its result is made)."""
        if self.native is not None:
            synced(self.run, self.native)


class PythonTicks:
    """A controller's ticks in the Python engine (the specification of ``_engine.Ticker``).

    Args:
        turn: The controller's turn (``_engine.Turn``).
        names: The tasks' names.
        readers: Their readers of a target (``task.tick_target()``), in the same order.
        measured: The controller's measured joints.
    """

    def __init__(
        self, turn: Any, names: list[str], readers: list[Any], measured: MeasuredJoints
    ) -> None:
        self.turn, self.names, self.measured = turn, names, measured
        self.targets = TickTargets(readers, names)
        self.wall = 0.0

    def restart(self, run: _Run, q0: np.ndarray, session: Session) -> None:
        """A new session at ``q0`` (the controller's turn held)."""
        self.run, self.session = run, session
        self.q = np.array(q0, dtype=float)
        self.measured.restart(self.q, run.rec.capacity)
        self.measured_given = 0  # ticks given q_measured this session
        run.rec.start(self.q)
        self.targets.restart()
        self._next = 0
        self.notes = 0
        self.above_since: float | None = None
        self.wall = 0.0

    @property
    def k(self) -> int:
        """The next tick."""
        return self._next

    def step(
        self, targets: Any, velocities: Any, q_measured: Any = None, qdot_measured: Any = None
    ) -> Tick:
        """One tick (:meth:`clik.Controller.step`), the controller's turn taken."""
        self.turn.take("Controller.step")
        try:
            return self._step(targets, velocities, q_measured, qdot_measured)
        finally:
            self.turn.give()

    def step_held(
        self, targets: Any, velocities: Any, q_measured: Any = None, qdot_measured: Any = None
    ) -> Tick:
        """:meth:`step` when the caller holds the turn (obstacles moved first)."""
        assert self.turn.mine()
        return self._step(targets, velocities, q_measured, qdot_measured)

    def _step(self, targets: Any, velocities: Any, q_measured: Any, qdot_measured: Any) -> Tick:
        staged = self.targets.stage(targets, velocities)  # may run the caller's code
        given = q_measured is not None or qdot_measured is not None
        q_m, qdot_m = self.measured.stage(q_measured, qdot_measured) if given else (None, None)
        run = self.run
        run.robot.check_model(full=False)  # changed meanwhile: named by the robot
        p_d, R_d, ff, at_rest, g_ref, g_ff = self.targets.read(staged)
        start = time.perf_counter()
        k = self._next
        commanded, jump = self.q, None  # q_k, the controller's own
        law_q = commanded  # the joints the law runs from
        if q_m is not None:  # (M1): the law runs at q_m unless (M3) refuses it
            self.measured_given += 1
            jump = self.measured.jump(q_m, k)
            if jump is None:
                self.measured.accept(q_m, k)
                law_q = q_m
        kept = run.rec.j
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            stop = run.sample(k, law_q, p_d, R_d, ff, at_rest, g_ref, g_ff)
            if stop is None or stop[0] != "diverged":
                self.q = run.integrate(commanded)  # (M2): q_{k+1} = q_k (+) qdot_k dt
        if run.rec.j != kept:
            self.measured.keep(kept % run.rec.capacity, commanded, q_m, qdot_m)
        self._next = k + 1
        tk = float(run.t[k])
        verdict, reason = self.verdict(stop, tk, jump)
        self.session.note(verdict, reason)
        crun = run.crun
        events = [] if crun is None else list(crun.sample_events)
        errors = [(float(run.err), float(run.err_rot))]
        if run.goals.rows is not None:
            errors += [(float(a), float(b)) for a, b in run.goals.rows.last]
        self.wall += time.perf_counter() - start
        return Tick(
            q=self.q.copy(), qdot=run.qdot.copy(), t=tk, k=k, verdict=verdict, reason=reason,
            events=events, active=[] if crun is None else crun.active_names(),
            errors=dict(zip(self.names, errors, strict=True)),
        )  # fmt: skip

    def verdict(
        self, stop: tuple[str, str] | None, tk: float, jump: JumpFound | None = None
    ) -> tuple[str, str]:
        """The worst verdict that holds at ``tk``: a check's, a jump, a limit, off_track."""
        seen, self.notes = self.notes, self.run.monitor.notes
        if stop is not None:
            return stop
        if jump is not None:
            return MEASUREMENT_JUMP, self.measured.reason(jump)
        if self.notes != seen:
            return "violated", violated_reason(self.session.crossed(tk))
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


def _record(constraint: str, kind: str, t_first: float, t_last: float, worst: float) -> Any:
    record = ViolationRecord(constraint, kind, t_first, worst, limit_words(constraint))
    record.t_last = t_last
    return record


def violated_reason(crossed: list[ViolationRecord]) -> str:
    """The ``violated`` verdict's reason: the worst limit crossed at this tick."""
    if not crossed:
        return "a limit was crossed"
    worst = max(crossed, key=ViolationRecord.rank)
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
