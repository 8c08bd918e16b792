r"""One run's constraint bookkeeping: candidates, activation, rows, release, records.

A :class:`~clik.constraints.ConstraintSet` describes the constraints; each run
makes its own :class:`ConstraintRun` on it (and each kind its own
:class:`~clik.constraints.kind.KindRun`), so a set shared by several trackers
(or runs) never mixes their state. This is the core every kind shares; it never
names a kind. Per sample (docs/method.md, "Constraints enlarge the task"):

1. every kind offers its candidates (:meth:`KindRun.evaluate`: errors that are
   positive, or rows that are active);
2. **activation**: a constraint whose threshold is violated (error > 0) is
   activated, the most violated first, up to the bound on active rows (22);
   the others are recorded as ``skipped``;
3. its row is written into the run's extended task (24)-(25): ``J_e``,
   ``e_e``, gains and feed-forward;
4. **release**: ``"sign"`` is the paper's rule (release when the error turns
   negative, less a hysteresis); ``"projection"`` releases a constraint only
   when it is at or beyond its threshold and the law computed *without* its
   row moves away from it: one activation and at most one release per
   constraint where the sign rule chatters.

Events are ``{"t", "constraint", "action"}`` records with action ``activate``,
``release`` or ``skipped``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.constraints.event_log import EventLog
from clik.constraints.kind import Candidate, KindRun, RunSetup, Sample
from clik.outputs.ring import unrolled
from clik.tasks.extended_task import ExtendedTask

if TYPE_CHECKING:
    from clik.clouds.cloud_obstacle import CloudObstacle
    from clik.constraints.constraint_set import ConstraintSet
    from clik.constraints.obstacle import Obstacle
    from clik.constraints.violations import ViolationMonitor
    from clik.outputs.result import TrackingResult
    from clik.trajectory.clock import Clock

LawFunction = Callable[[int, np.ndarray], Any]
"""``law(r, out)``: the law's joint velocity on the first ``r`` rows of the extended task."""

AT_THRESHOLD = 1e-6
"""A constraint is "at its threshold" when its error is below this fraction of its scale."""


class ConstraintRun:
    """The state of one run's constraints.

    Args:
        cset: The constraint set (its kinds, the collision scene).
        m: Task rows (every task's: the constraint rows start there).
        law: Law name (sets the default gains and the bound on active rows).
        alpha: The task's largest gain [1/s].
        t: The run's time grid [s].
        n_rec: Number of recorded samples.
        frame_id: The task's frame (rows that need it: dexterity).
        task_rows: The (primary) task's rows among ``(x, y, z, rx, ry, rz)`` (idem): the
            extended task's first rows, which the kinds read as "the task".
        data: The run's Pinocchio data, where the loop computes the kinematics the rows
            read; None: a new one.
        events: The events kept (the last ones; 0: every one): a controller's session.

    The run reads ``cset`` as it is now (its kinds, scene and settings; a change to the
    set, such as :meth:`~clik.constraints.ConstraintSet.set_obstacles`, applies to the
    next run) and places the scene in its own :class:`~clik.constraints.collision_scene.SceneRun`
    (:attr:`scene`): runs on one set never share state.

    Raises:
        InputError: A kind that cannot run with this task (dexterity without a frame).
    """

    def __init__(
        self,
        cset: ConstraintSet,
        m: int,
        law: str,
        alpha: float,
        t: np.ndarray | Clock,
        n_rec: int,
        frame_id: int = -1,
        task_rows: np.ndarray | None = None,
        data: pin.Data | None = None,
        events: int = 0,
    ) -> None:
        self.frame_id = frame_id
        self.task_rows = np.arange(m) if task_rows is None else np.asarray(task_rows, np.intp)
        self.cset = cset = cset.snapshot()
        self.robot = cset.robot
        self.data = cset.robot.model.createData() if data is None else data
        self.scene = None if cset.scene is None else cset.scene.start()
        """The run's own state of the set's collision scene (None without a scene)."""
        self.release_rule, self.hysteresis = cset.release_rule, cset.hysteresis
        self.m = m
        self.law = law
        self.alpha = alpha
        self.limit = cset.row_limit(m, law)
        self.t = t
        self.task_m = task_m = len(self.task_rows)  # the primary task's rows (0 .. task_m)
        setup = RunSetup(
            cset.robot, task_m, law, t, n_rec, frame_id, self.task_rows, cset.scene,
            cset.monitor_margin, self.scene,
        )  # fmt: skip
        self.runs: list[KindRun] = [kind.start(setup) for kind in cset.kinds]
        self._qdot = np.zeros(self.robot.nv)
        self.active: list[Candidate] = []
        self._skipped: set[str] = set()
        self._ever_skipped: set[str] = set()
        self.events = EventLog(events)
        self.sample_events: list[dict[str, Any]] = []
        """The events of the last :meth:`update` (a controller's tick: all of them)."""
        self.codes: dict[str, int] = {}
        slots = max(self.limit, 1)
        self.rec_active = np.full((n_rec, slots), -1, dtype=np.int32)
        self.rec_witness = np.full((n_rec, slots, 2, 3), np.nan)
        self._q_prev: np.ndarray | None = None

    @property
    def min_distance(self) -> float:
        """This sample's exact nearest obstacle distance [m] (``inf``: none exact)."""
        return min((run.min_distance for run in self.runs), default=np.inf)

    # -- per sample --------------------------------------------------------------------

    def update(
        self, k: int, q: np.ndarray, ext: ExtendedTask, law: LawFunction, exact: bool
    ) -> int:
        """Evaluate, activate, fill the active rows into ``ext`` and release.

        Args:
            k: Sample index.
            q: Configuration (kinematics and joint Jacobians already computed at it).
            ext: The run's extended task; rows ``m .. m + v`` are written.
            law: The law on the first ``r`` rows (the projection release rule runs it).
            exact: Make every obstacle's nearest distance exact (a recorded sample).

        Returns:
            ``v``, the number of active constraint rows.
        """
        tk = float(self.t[k])
        self.sample_events = []
        dq_abs = None
        if self._q_prev is not None:  # |dq| since the last sample, for the certificates
            dq = pin.difference(self.robot.model, self._q_prev, q)
            dq_abs = np.abs(dq, out=dq)
        s = Sample(
            tk, q, dq_abs, self.robot, ext.J[: self.task_m], exact, self.active, self.scene,
            self.data,
        )  # fmt: skip
        candidates: list[Candidate] = []
        for run in self.runs:
            run.evaluate(s, candidates)
        self._q_prev = q  # the tracker makes a new array per step (pin.integrate)
        self._refresh_active(tk, candidates)
        self._activate(tk, candidates)
        v = self._fill_rows(s, ext)
        if self.release_rule == "projection" and v:
            v = self._project_release(tk, ext, law, v)
        return v

    def _refresh_active(self, tk: float, candidates: list[Candidate]) -> None:
        """Refresh the active constraints' data; release those the sign rule lets go."""
        current = {c.key: c for c in candidates}
        hysteresis = self.hysteresis
        still = []
        for c in self.active:
            new = current.get(c.key)
            if new is None:  # no longer evaluated: far from its threshold
                self._event(tk, c.key, "release")
            elif self.release_rule == "sign" and new.error < -hysteresis * new.scale:
                self._event(tk, c.key, "release")
            else:
                still.append(new)
        self.active = still

    def _activate(self, tk: float, candidates: list[Candidate]) -> None:
        """Activation, most violated first, within the bound on active rows (22)."""
        active_keys = {c.key for c in self.active}
        fresh = sorted(
            (
                c
                for c in candidates
                if c.key not in active_keys and c.error > AT_THRESHOLD * c.scale
            ),
            key=lambda c: -c.error / c.scale,
        )
        for c in fresh:
            if len(self.active) < self.limit:
                self.active.append(c)
                self._event(tk, c.key, "activate")
                self._skipped.discard(c.key)
            elif c.key not in self._skipped:
                self._skipped.add(c.key)
                self._event(tk, c.key, "skipped")
        if self._skipped:
            self._skipped &= {c.key for c in fresh}

    # -- rows --------------------------------------------------------------------------

    def _gain(self, c: Candidate, row_norm2: float) -> float:
        """A row's gain: its kind's, else ``alpha`` (law (10)) or ``alpha / (2 max(1, |j|^2))``."""
        given = c.run.kind.gain
        if given is not None:
            return given
        if self.law == "pseudoinverse":
            return self.alpha
        return 0.5 * self.alpha / max(1.0, row_norm2)

    def _fill_rows(self, s: Sample, ext: ExtendedTask) -> int:
        """Write the active constraints' rows (each kind's) into the extended task (24)-(25)."""
        m = self.m
        for i, c in enumerate(self.active):
            row = ext.J[m + i]
            c.run.row(s, c, row)
            ext.e[m + i] = c.error
            ext.ff[m + i] = c.feed
            ext.K[m + i] = self._gain(c, float(row @ row))
        return len(self.active)

    def _project_release(self, tk: float, ext: ExtendedTask, law: LawFunction, v: int) -> int:
        """Release one constraint at its threshold whose row-free solution moves away."""
        m = self.m
        for i in range(v):
            c = self.active[i]
            if c.error > AT_THRESHOLD * c.scale:
                continue
            last = m + v - 1
            if i != v - 1:  # move this row last, so the law can run without it
                ext.swap(m + i, last)
                self.active[i], self.active[v - 1] = self.active[v - 1], self.active[i]
            law(last, self._qdot)
            edot = ext.ff[last] - float(ext.J[last] @ self._qdot)
            if edot <= 0.0:
                self.active.pop()
                self._event(tk, c.key, "release")
                return v - 1
        return v

    def _event(self, tk: float, key: str, action: str) -> None:
        if action == "skipped":
            self._ever_skipped.add(key)
        event = {"t": round(tk, 9), "constraint": key, "action": action}
        self.events.append(event)
        self.sample_events.append(event)

    # -- limits and records ------------------------------------------------------------

    def observe_limits(self, tk: float, monitor: ViolationMonitor) -> None:
        """Every limit the kinds guard that is crossed at this sample, to ``monitor``."""
        for run in self.runs:
            run.observe_limits(tk, monitor)

    def replace_cloud(self, cloud: CloudObstacle) -> bool:
        """A cloud replaced by a controller, in the kind that has it; False: none so named."""
        return any([run.replace_cloud(cloud) for run in self.runs])

    def move_obstacle(self, obstacle: Obstacle) -> bool:
        """An obstacle moved by a controller (from ``t = 0``), in every kind that has it.

        False: no obstacle so named.
        """
        moved = [run.move_obstacle(obstacle) for run in self.runs]
        return any(moved)

    def clear(self, j: int) -> None:
        """Empty slot ``j`` of the active set's record (a ring reuses its slots)."""
        self.rec_active[j] = -1
        self.rec_witness[j] = np.nan

    def record(self, j: int) -> None:
        """Keep this sample's active set, witness points and the kinds' records in slot ``j``."""
        for run in self.runs:
            run.record(j)
        for i, c in enumerate(self.active):
            code = self.codes.setdefault(c.key, len(self.codes))
            self.rec_active[j, i] = code
            if c.witness is not None:
                self.rec_witness[j, i, 0] = c.witness[0]
                self.rec_witness[j, i, 1] = c.witness[1]

    def active_names(self) -> list[str]:
        """Names of the active constraints."""
        return [c.key for c in self.active]

    def active_rows(self) -> list[Candidate]:
        """The active constraints, in row order."""
        return list(self.active)

    def skipped_names(self) -> list[str]:
        """Constraints that were violated but found no free row, in the order met."""
        return sorted(self._ever_skipped)

    def records(self, n_rec: int) -> dict[str, Any]:
        """The run's records, with the keys the compiled engine returns."""
        return {
            "events": list(self.events),
            "events_dropped": self.events.dropped,
            "constraint_names": sorted(self.codes, key=self.codes.__getitem__),
            "active": self.rec_active,
            "witness": self.rec_witness,
            "kinds": [run.records(n_rec) for run in self.runs],
        }

    def finish(
        self, result: TrackingResult, n_rec: int, ring: tuple[int, int] | None = None
    ) -> None:
        """Move the run's records into the result (``ring``: see :func:`finish_constraints`)."""
        finish_constraints(self.cset, self.records(n_rec), result, n_rec, ring)


def finish_constraints(
    cset: ConstraintSet, records: dict[str, Any], result: TrackingResult, n_rec: int,
    ring: tuple[int, int] | None = None,
) -> None:  # fmt: skip
    """A run's constraint records (either engine's) into its result and summary.

    Args:
        cset: The run's constraint set.
        records: ``events``, ``constraint_names``, ``active``, ``witness`` and per kind
            (in the set's order) ``kinds``, as :meth:`ConstraintRun.records` gives them.
        result: The result to fill.
        n_rec: Samples recorded.
        ring: ``(kept, capacity)`` of a ring record (a controller's): its per-sample
            arrays are unrolled, oldest first, and ``n_rec`` is what it holds.
    """
    if ring is not None:  # the per-sample arrays, oldest first (not per-obstacle ones)
        kinds = [
            {key: unrolled(v, *ring) if key in kind.per_sample else v for key, v in kr.items()}
            for kind, kr in zip(cset.kinds, records["kinds"], strict=True)
        ]
        active, witness = unrolled(records["active"], *ring), unrolled(records["witness"], *ring)
        records = {**records, "active": active, "witness": witness, "kinds": kinds}
        n_rec = min(ring)
    result.events = list(records["events"])
    result.events_dropped = int(records["events_dropped"])
    result.info["constraint_names"] = list(records["constraint_names"])
    result.info["links"] = cset.link_labels
    result.extra["active"] = records["active"][:n_rec]
    result.extra["witness"] = records["witness"][:n_rec]
    extra: dict[str, Any] = {}
    for kind, kind_records in zip(cset.kinds, records["kinds"], strict=True):
        kind.finish(result, kind_records, n_rec, extra)
    result.info["summary_extra"] = extra
