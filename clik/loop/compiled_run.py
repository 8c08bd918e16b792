"""The samples of a tracking run in the compiled engine (``clik._engine``).

:meth:`clik.loop.tracking._Run.samples` is the specification: the same steps, one
sample at a time, in Python. Here Python samples the reference in chunks and
hands each chunk to the engine, which runs its samples and writes the record in
place into the run's :class:`~clik.loop.recording.Recorder`; the reasons of a stop are
then written in words by the same Python code as the specification's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from clik.constraints.constraint_run import finish_constraints
from clik.constraints.registry import limit_words
from clik.constraints.violations import ViolationRecord
from clik.engine import load
from clik.loop.stop_checks import instability_reason, joint_step_reason, non_finite_reason
from clik.trajectory.clock import Clock

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet
    from clik.constraints.violations import JointRange, ViolationMonitor
    from clik.loop.recording import Recorder
    from clik.loop.reference_stream import ReferenceChunks
    from clik.loop.stop_checks import StopChecks, StopSettings
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult
    from clik.tasks.extended_task import ExtendedTask
    from clik.tasks.task import Task


class RunState(Protocol):
    """What a run (:class:`clik.loop.tracking._Run`) shows the compiled engine."""

    robot: Robot
    task: Task
    tr: Any
    cset: ConstraintSet | None
    t: Any
    N: int
    chunks: ReferenceChunks | None
    rec: Recorder
    ext: ExtendedTask
    checks: StopChecks
    monitor: ViolationMonitor
    crun: Any
    goals: Any
    progress: Any
    event_size: int
    steps: int
    max_err: float
    err: float

    def active_clause(self, r: int) -> str: ...  # noqa: D102

    def deadlock_reason(self, tk: float, err: float, r: int, qdot: np.ndarray) -> str: ...  # noqa: D102

    def stall_reason(self, tk: float, err: float, r: int, qdot: np.ndarray) -> str: ...  # noqa: D102


def compiled_samples(run: RunState, q: np.ndarray) -> tuple[str, str]:
    """Run every sample of ``run`` from ``q`` in the engine; returns the status and reason.

    Sets ``run.steps``, ``run.max_err`` and ``run.err``, the record, the violations
    and the stability margin, as :meth:`clik.loop.tracking._Run.samples` does.
    """
    native = engine_run(run)
    q = np.array(q, dtype=float)
    N = run.N
    tick = max(1, N // 100) if run.progress is not None else N
    k = 0
    stop: tuple[Any, ...] = ("",)
    goals, chunks = run.goals, run.chunks
    assert chunks is not None  # an offline run (a controller ticks its own)
    while k < N:
        c0, c1, P_d, R_d, FF, at_rest = chunks.load(k - k % chunks.size)
        G_ref, G_ff, at_rest = goals.load(c0, at_rest)
        end = min(c1, (k // tick + 1) * tick)
        a, b = k - c0, end - c0
        more = (
            {} if G_ref is None else {"goal_ref": _rows(G_ref, a, b), "goal_ff": _rows(G_ff, a, b)}
        )
        stop = native.advance(
            k, end, _rows(P_d, a, b), _rows(R_d, a, b), _rows(FF, a, b), _rows(at_rest, a, b), q,
            **more,
        )  # fmt: skip
        k = stop[0]
        if stop[1]:
            break
        if run.progress is not None and k < N:
            run.progress(k, N)
    synced(run, native)
    if not stop[1]:
        return "completed", f"reached the end of the trajectory at t = {run.t[-1]:.6g} s"
    return stopped(run, native, stop)


def synced(run: RunState, native: Any) -> None:
    """The engine's run state into ``run``: counts, errors, record, violations, constraints."""
    goals = run.goals
    run.steps, run.max_err, run.err = native.steps, native.max_error, native.last_error
    if goals.rows is not None:
        goals.rows.largest[:] = native.goal_max
        goals.rows.last[:] = native.goal_last
    run.rec.j = native.kept
    run.checks.worst_margin = native.worst_margin
    for constraint, kind, t_first, t_last, worst in native.violations:
        record = ViolationRecord(constraint, kind, t_first, worst, limit_words(constraint))
        record.t_last = t_last
        run.monitor.records[constraint] = record
    if run.cset is not None:
        run.crun = CompiledConstraints(run.cset, native.constraint_records())


def _rows(array: np.ndarray | None, a: int, b: int) -> np.ndarray | None:
    """Rows ``a:b`` of a chunk array, contiguous (the engine reads raw memory)."""
    return None if array is None else np.ascontiguousarray(array[a:b])


def engine_run(run: RunState) -> Any:
    """The engine's run, on the run's robot, task, law, checks and record (typed configs).

    An open run (a controller's: its times a :class:`~clik.loop.clock.Clock`, its record
    a ring) is built open: ``t`` None, ``t0`` its first time.
    """
    engine, tr = load(), run.tr
    more: dict[str, Any] = {}
    if isinstance(run.t, Clock):
        more["t0"] = run.t.t0
    if run.goals.rows is not None:
        more["goals"] = [g.task.engine_goal(engine) for g in tr.stack.extras]
    return engine.TrackingRun(
        model=run.robot.model,
        task=_task_config(engine, run.task),
        law=_law_config(engine, tr, run.goals),
        stop=_stop_config(engine, run.checks.s),
        t=None if isinstance(run.t, Clock) else run.t,
        record=_record_arrays(engine, run.rec, run.goals),
        joints=_joint_monitor_config(engine, run.monitor.joints),
        constraints=None if run.cset is None else run.cset.engine_config(),
        events=run.event_size,
        **more,
    )


def _task_config(engine: Any, task: Task) -> Any:
    """The task's frame and rows as ``_engine.TaskConfig``."""
    return engine.TaskConfig(
        frame=int(task.frame_id),
        rows=[int(r) for r in task.rows],
        has_position=bool(task.has_position),
        has_orientation=bool(task.has_orientation),
    )


def _law_config(engine: Any, tr: Any, goals: Any) -> Any:
    """The tracker's law, gains, rows, levels, objectives and joint speed limits (``LawConfig``)."""
    speed = tr.speed
    vmax = None if speed is None else np.asarray(speed.velocity, dtype=float)
    amax = None
    if speed is not None and speed.acceleration is not None:
        amax = np.asarray(speed.acceleration, dtype=float)
    more: dict[str, Any] = {}
    if len(tr.ends) > 1 or goals.objectives:
        more["levels"] = [int(e) for e in tr.ends]
        more["objectives"] = [_objective_config(engine, *o) for o in goals.objectives]
    return engine.LawConfig(
        law=tr.law, damping=float(tr.damping), dt=float(tr.dt), beta_max=float(tr.beta_max),
        K_task=np.asarray(tr.K_task, dtype=float), rows=int(tr.rows), alpha=float(tr.alpha),
        vmax=vmax, amax=amax, **more,
    )  # fmt: skip


def _objective_config(engine: Any, level: int, objective: Any, setup: dict[str, Any]) -> Any:
    """One objective of eq. (5) as ``_engine.ObjectiveConfig``."""
    arrays = {
        k: np.asarray(v, dtype=float)
        for k, v in setup.items()
        if k in ("center", "half_range", "q_ref")
    }
    index = {k: [int(i) for i in v] for k, v in setup.items() if k in ("idx_q", "idx_v")}
    return engine.ObjectiveConfig(
        kind=objective.kind, gain=float(objective.gain), level=int(level), **index, **arrays
    )


def _stop_config(engine: Any, s: StopSettings) -> Any:
    """The stop checks' settings as ``_engine.StopConfig``."""
    return engine.StopConfig(
        deadlock_window=s.deadlock_window, deadlock_ratio=s.deadlock_ratio,
        deadlock_error=s.deadlock_error, max_joint_step=s.max_joint_step,
        stall_window=s.stall_window, stall_progress=s.stall_progress,
    )  # fmt: skip


def _record_arrays(engine: Any, rec: Recorder, goals: Any) -> Any:
    """The Recorder's own arrays (written in place) as ``_engine.RecordArrays``."""
    more: dict[str, Any] = {} if goals.rows is None else {"goal_error": goals.rows.record}
    if rec.ring:
        more["ring"] = True
    return engine.RecordArrays(**more,
        N=rec.N, every=rec.every, idx=rec.idx, q=rec.q, qdot=rec.qdot, qddot=rec.qddot,
        position=rec.position, reference=rec.reference, error=rec.error,
        orientation_error=rec.orientation_error, active=rec.active, distance=rec.distance,
        joint_min=rec.joint_min, joint_max=rec.joint_max, qdot_prev=rec._qdot_prev,
    )  # fmt: skip


def _joint_monitor_config(engine: Any, joints: JointRange) -> Any:
    """The joint limits to stay in as ``_engine.JointMonitorConfig``."""
    return engine.JointMonitorConfig(
        index=[int(i) for i in joints.index],
        lower=np.asarray(joints.lower, dtype=float),
        upper=np.asarray(joints.upper, dtype=float),
        names=list(joints.names),
    )


def stopped(run: RunState, native: Any, stop: tuple[Any, ...]) -> tuple[str, str]:
    """The status and reason of a run the engine stopped at sample ``k``."""
    _, why, k, r, err = stop
    tk = float(run.t[k])
    ext = run.ext
    ext.J[:], ext.e[:] = native.ext_J, native.ext_e
    ext.K[:], ext.ff[:] = native.ext_K, native.ext_ff
    qdot = native.qdot
    if why == "non_finite":
        return "diverged", non_finite_reason(tk) + run.active_clause(r)
    if why == "joint_step":
        reason = joint_step_reason(tk, native.jump, err, run.checks.s.max_joint_step)
        return "diverged", reason + run.active_clause(r)
    if why == "unstable":
        return "diverged", instability_reason(run.tr.law, native.margin, err) + run.active_clause(r)
    if why == "deadlock":
        return "deadlock", run.deadlock_reason(tk, err, r, qdot)
    return "deadlock", run.stall_reason(tk, err, r, qdot)


class _Active:
    """An active constraint, by name (what the reasons of a stop read)."""

    def __init__(self, key: str) -> None:
        self.key = key


class CompiledConstraints:
    """The end of a compiled run's constraints, as :class:`ConstraintRun` shows it.

    Args:
        cset: The run's constraint set.
        records: What the engine's constraint run recorded (``constraint_records``).
    """

    def __init__(self, cset: ConstraintSet, records: dict[str, Any]) -> None:
        self.cset, self.records = cset, records
        self.limit: int = records["limit"]

    def active_names(self) -> list[str]:
        """Names of the constraints active when the run ended, in row order."""
        return list(self.records["active_names"])

    def active_rows(self) -> list[_Active]:
        """The active constraints, in row order."""
        return [_Active(name) for name in self.records["active_names"]]

    def skipped_names(self) -> list[str]:
        """Constraints that were violated but found no free row."""
        return list(self.records["skipped"])

    def finish(
        self, result: TrackingResult, n_rec: int, ring: tuple[int, int] | None = None
    ) -> None:
        """Move the run's records into the result, as ``ConstraintRun.finish`` does."""
        finish_constraints(self.cset, self.records, result, n_rec, ring)
