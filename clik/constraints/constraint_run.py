r"""One run's constraint bookkeeping: candidates, activation, rows, release, records.

A :class:`~clik.constraints.ConstraintSet` describes the constraints; each run
gets its own :class:`ConstraintRun` from :meth:`ConstraintSet.start`, so a set
shared by several trackers (or runs) never mixes their state. Per sample
(docs/method.md, "Constraints enlarge the task"):

1. every monitored constraint's error is evaluated (joint ranges for all
   joints at once; link-obstacle pairs through distance certificates and
   link-link pairs after a bounding-sphere prune, with coal's witness points;
   the task's manipulability (D1) from the task rows, its gradient (D3) only
   while the dexterity row is active);
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

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.constraints.dexterity import DEXTERITY_KEY, dexterity_row
from clik.constraints.obstacle_rows import obstacle_error, obstacle_row, point_jacobian
from clik.errors import InputError
from clik.extended_task import ExtendedTask

if TYPE_CHECKING:
    from clik.constraints.constraint_set import ConstraintSet
    from clik.result import TrackingResult

LawFunction = Callable[[int, np.ndarray], Any]
"""``law(r, out)``: the law's joint velocity on the first ``r`` rows of the extended task."""

_AT_THRESHOLD = 1e-6
"""A constraint is "at its threshold" when its error is below this fraction of its scale."""


class Candidate:
    """One constraint whose row may enter the extended task at this sample.

    Attributes:
        key: Constraint name (``joint:<joint>:lower``, ``obstacle:<obstacle>:<link>``,
            ``self:<link a>:<link b>``, ``dexterity``).
        kind: ``"joint"``, ``"obstacle"``, ``"self"`` or ``"dexterity"``.
        error: Its error (positive inside the threshold) [m, rad, m^2 or m^p].
        scale: Its threshold in the error's unit (``d_o``, ``d_q``, ``d_o^2 / 2`` or ``w_min``).
        threshold: The threshold ``d_o``, ``d_q`` [m or rad] or ``w_min`` [m^p].
        feed: Feed-forward term of its row (14).
        index: Joint-range row index (joint rows).
        joint, joint_b: Parent joints of the witness points (obstacle and self rows).
        distance: Signed distance [m] (obstacle and self rows).
        point_a, point_b: Witness points on the link (a) and the obstacle or other link (b).
        normal: coal's contact normal, from a toward b.
        obstacle: Obstacle index (obstacle rows).
        pair: ``(link geometry, obstacle)`` index pair (obstacle rows).
    """

    __slots__ = (
        "distance",
        "error",
        "feed",
        "index",
        "joint",
        "joint_b",
        "key",
        "kind",
        "normal",
        "obstacle",
        "pair",
        "point_a",
        "point_b",
        "scale",
        "threshold",
    )

    def __init__(self, key: str, kind: str, error: float, scale: float, threshold: float) -> None:
        self.key, self.kind, self.error, self.scale = key, kind, error, scale
        self.threshold = threshold
        self.feed = 0.0
        self.index = self.joint = self.joint_b = self.obstacle = -1
        self.distance = math.inf
        self.point_a = self.point_b = self.normal = _NO_POINT
        self.pair = (-1, -1)


_NO_POINT = np.zeros(3)


class ConstraintRun:
    """The state of one run's constraints (made by :meth:`ConstraintSet.start`).

    Args:
        cset: The constraint set (configuration, collision scene).
        m: Task rows.
        law: Law name (sets the default gains and the recovery cap).
        alpha: The task's largest gain [1/s].
        t: The run's time grid [s].
        n_rec: Number of recorded samples.
        frame_id: The task's frame (the dexterity row's Jacobian derivative).
        task_rows: The task's rows among ``(x, y, z, rx, ry, rz)`` (idem).

    Raises:
        InputError: A dexterity row without the task's frame.
    """

    def __init__(
        self,
        cset: ConstraintSet,
        m: int,
        law: str,
        alpha: float,
        t: np.ndarray,
        n_rec: int,
        frame_id: int = -1,
        task_rows: np.ndarray | None = None,
    ) -> None:
        if cset.dexterity is not None and (frame_id < 0 or task_rows is None):
            raise InputError("constraints.dexterity", "the task's frame and rows for the row")
        self.frame_id = frame_id
        self.task_rows = np.arange(m) if task_rows is None else np.asarray(task_rows, np.intp)
        self.manipulability = math.nan
        """This sample's ``w`` (D1) [m^p] (NaN without a dexterity row)."""
        self.cset = cset
        self.robot = cset.robot
        self.scene = cset.scene
        self.m = m
        self.law = law
        self.alpha = alpha
        self.limit = cset.row_limit(m, law)
        self.t = t
        nv = self.robot.nv
        self._qdot = np.zeros(nv)
        self.active: list[Candidate] = []
        self._skipped: set[str] = set()
        self.events: list[dict[str, Any]] = []
        self.min_distance = math.inf
        n_obs = len(cset.obstacles)
        self.run_min = np.full(n_obs, np.inf)
        self.run_min_link = ["" for _ in range(n_obs)]
        self.run_min_t = np.zeros(n_obs)
        self.codes: dict[str, int] = {}
        self.rec_dist = np.full((n_rec, n_obs), np.inf)
        self.rec_link = np.full((n_rec, n_obs), -1, dtype=np.int16)
        slots = max(self.limit, 1)
        self.rec_active = np.full((n_rec, slots), -1, dtype=np.int32)
        self.rec_witness = np.full((n_rec, slots, 2, 3), np.nan)
        self.dist_o = np.full(n_obs, np.inf)
        """Per obstacle, this sample's nearest link distance [m]: exact when below the
        threshold plus the monitor margin, or on a recorded sample; else a lower bound."""
        self.exact_o = np.zeros(n_obs, dtype=bool)
        self.link_o = np.full(n_obs, -1, dtype=np.int16)
        self.self_penetrations: list[tuple[str, float]] = []
        if self.scene is not None:  # distance certificates: unknown (-inf) at the start
            self._lb = np.full((self.scene.n_links, n_obs), -np.inf)
            self._evaluated = np.zeros((self.scene.n_links, n_obs), dtype=bool)
            self._near = np.zeros((self.scene.n_links, n_obs), dtype=bool)
        self._q_prev: np.ndarray | None = None
        self._dq_abs: np.ndarray | None = None
        self._joint_slack = -1.0  # unknown: evaluate at the first sample
        dt = float(t[1] - t[0]) if t.shape[0] > 1 else 0.0
        speed = np.linalg.norm(cset.obs_vel, axis=1) * dt
        self._obs_step = speed[None, :] if np.any(speed > 0.0) else None
        self._obs_index = np.arange(n_obs)
        self._everywhere = np.full(n_obs, np.inf)  # the margin of a recorded sample

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
        candidates = self._evaluate(tk, q, exact)
        if self.cset.dexterity is not None:
            self._evaluate_dexterity(ext.J[: self.m], candidates)
        self._q_prev = q  # the tracker makes a new array per step (pin.integrate)
        self._refresh_active(tk, candidates)
        self._activate(tk, candidates)
        v = self._fill_rows(ext)
        if self.cset.release_rule == "projection" and v:
            v = self._project_release(tk, ext, law, v)
        return v

    def _refresh_active(self, tk: float, candidates: list[Candidate]) -> None:
        """Refresh the active constraints' data; release those the sign rule lets go."""
        current = {c.key: c for c in candidates}
        hysteresis = self.cset.hysteresis
        still = []
        for c in self.active:
            new = current.get(c.key)
            if new is None:  # no longer evaluated: far from its threshold
                self._event(tk, c.key, "release")
            elif self.cset.release_rule == "sign" and new.error < -hysteresis * new.scale:
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
                if c.key not in active_keys and c.error > _AT_THRESHOLD * c.scale
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

    # -- evaluation --------------------------------------------------------------------

    def _evaluate(self, tk: float, q: np.ndarray, exact: bool) -> list[Candidate]:
        """Constraints whose error is positive, or that are active, at this sample."""
        out: list[Candidate] = []
        active = {c.key for c in self.active}
        if self._q_prev is None:
            self._dq_abs = None
        else:  # |dq| since the last sample, for the joint and obstacle certificates
            dq = pin.difference(self.robot.model, self._q_prev, q)
            self._dq_abs = np.abs(dq, out=dq)
        if self.cset.joint_limits is not None:
            self._evaluate_joints(q, out, active)
        if self.scene is not None:
            if self.cset.obstacles:
                self._evaluate_obstacles(tk, out, active, exact)
            if self.scene.self_pairs:
                self._evaluate_self(tk, out, active)
        return out

    def _evaluate_joints(self, q: np.ndarray, out: list[Candidate], active: set[str]) -> None:
        """Joint-range errors (17), behind a certificate.

        The smallest margin to a threshold band, lowered by ``max |dq|`` per step, says
        when a band may be entered; the rows are evaluated only then or while one is active.
        """
        jl = self.cset.joint_limits
        assert jl is not None
        if self._dq_abs is not None and self._dq_abs.size:
            self._joint_slack -= float(self._dq_abs.max())
        joint_active = any(c.kind == "joint" for c in self.active)
        if self._joint_slack > 0.0 and not joint_active:
            return
        e = jl.evaluate(q)
        self._joint_slack = -float(e.max()) if e.size else math.inf
        thr = jl.row_threshold
        for i in np.flatnonzero(e > -thr):
            key = jl.names[i]
            if e[i] > 0.0 or key in active:
                c = Candidate(key, "joint", float(e[i]), float(thr[i]), float(thr[i]))
                c.index = int(i)
                out.append(c)

    def _evaluate_obstacles(
        self, tk: float, out: list[Candidate], active: set[str], exact: bool
    ) -> None:
        """Link-obstacle pairs through distance certificates.

        Every pair keeps a lower bound of its distance: exact when coal last evaluated
        it, lowered each step by how far the link can have moved (``rho |dq|``, see
        :meth:`CollisionScene.motion_bounds`) and the obstacle's ``|v| dt``. coal is
        asked only for pairs whose bound is below the threshold (or active) and, per
        obstacle, for the nearest pair within ``threshold + monitor_margin`` (every
        obstacle's nearest pair when ``exact``), so the per-obstacle minimum is exact
        there and a lower bound only beyond it, on samples that are not recorded.
        """
        cset, scene = self.cset, self.scene
        assert scene is not None
        lb, evaluated = self._lb, self._evaluated
        if self._dq_abs is not None:
            lb -= cset.rho.dot(self._dq_abs)[:, None]
            if self._obs_step is not None:
                lb -= self._obs_step
        evaluated[:] = False
        near = np.less(lb, cset.thr_matrix, out=self._near)
        todo: list[Any] = np.argwhere(near).tolist() if near.any() else []
        todo += [c.pair for c in self.active if c.kind == "obstacle"]
        margin_o = self._everywhere if exact else cset.margin
        obs_index = self._obs_index
        placed = False
        while True:  # evaluate, then the nearest pair of each obstacle, until settled
            for i, o in todo:
                if evaluated[i, o]:
                    continue
                if not placed:
                    scene.place_geometries(self.robot.data, tk)
                    placed = True
                c = self._obstacle_candidate(int(i), int(o))
                lb[i, o] = c.distance
                evaluated[i, o] = True
                if cset.obstacle_rows and (c.distance < c.threshold or c.key in active):
                    out.append(c)
            nearest = lb.argmin(axis=0)
            dist_o = lb[nearest, obs_index]
            unsure = (dist_o < margin_o) & ~evaluated[nearest, obs_index]
            if not unsure.any():
                break
            todo = [(int(nearest[o]), int(o)) for o in np.flatnonzero(unsure)]
        self.dist_o = dist_o
        self.exact_o = evaluated[nearest, obs_index]
        self.link_o[:] = nearest
        exact_d = np.where(self.exact_o, dist_o, np.inf)
        self.min_distance = float(exact_d.min())
        better = exact_d < self.run_min
        for j in np.flatnonzero(better):
            self.run_min[j] = exact_d[j]
            self.run_min_t[j] = tk
            self.run_min_link[j] = cset.link_labels[nearest[j]]

    def _obstacle_candidate(self, i: int, o: int) -> Candidate:
        """Distance, witness points and error of link geometry ``i`` and obstacle ``o``."""
        cset, scene = self.cset, self.scene
        assert scene is not None
        dist, p_link, p_obs, normal = scene.distance(int(scene.obstacle_pairs[i, o]))
        thr = float(cset.obs_threshold[o])
        error, scale = obstacle_error(cset.form, thr, dist)
        c = Candidate(cset.pair_names[i][o], "obstacle", error, scale, thr)
        c.joint, c.distance, c.obstacle, c.pair = int(scene.link_joint[i]), dist, o, (i, o)
        c.point_a, c.point_b, c.normal = p_link, p_obs, normal
        return c

    def _evaluate_self(self, tk: float, out: list[Candidate], active: set[str]) -> None:
        """Link-link pairs whose bounding spheres are near, with coal."""
        cset, scene = self.cset, self.scene
        assert scene is not None
        data = self.robot.data
        pos, r = scene.place_joints(data), scene.joint_radius
        a, b = cset.self_slots
        gap = np.linalg.norm(pos[a] - pos[b], axis=1) - r[a] - r[b]
        close = np.flatnonzero(gap < cset.self_threshold + cset.monitor_margin)
        if close.size:
            scene.place_geometries(data, tk)
        self.self_penetrations = []
        thr = cset.self_threshold
        for idx in close:
            pair, ia, ib = scene.self_pairs[idx]
            dist, pa, pb, normal = scene.distance(pair)
            key = f"self:{cset.link_labels[ia]}:{cset.link_labels[ib]}"
            if dist < 0.0:
                self.self_penetrations.append((key, float(dist)))
            if dist < thr or key in active:
                c = Candidate(key, "self", thr - dist, thr, thr)
                c.joint, c.joint_b = int(scene.link_joint[ia]), int(scene.link_joint[ib])
                c.distance, c.point_a, c.point_b, c.normal = dist, pa, pb, normal
                out.append(c)

    def _evaluate_dexterity(self, J: np.ndarray, out: list[Candidate]) -> None:
        """The dexterity error (D2) of the task rows ``J``: a candidate when positive or active.

        Only ``w`` (D1) is evaluated here (a Cholesky factor of the m x m ``J J^T``); the
        row's gradient (D3), which needs the kinematic Hessian, only while it is active.
        """
        dex = self.cset.dexterity
        assert dex is not None
        error, self.manipulability = dex.error(J)
        if error > 0.0 or any(c.key == DEXTERITY_KEY for c in self.active):
            thr = dex.threshold
            out.append(Candidate(DEXTERITY_KEY, "dexterity", error, thr, thr))

    # -- rows --------------------------------------------------------------------------

    def _gain(self, kind: str, row_norm2: float) -> float:
        """A row's gain: the user's, else ``alpha`` (law (10)) or ``alpha / (2 max(1, |j|^2))``."""
        given = self.cset.gains.get(kind)
        if given is not None:
            return given
        if self.law == "pseudoinverse":
            return self.alpha
        return 0.5 * self.alpha / max(1.0, row_norm2)

    def _fill_rows(self, ext: ExtendedTask) -> int:
        """Write the active constraints' rows (15), (19), (D3) into the extended task (24)-(25)."""
        model, data = self.robot.model, self.robot.data
        cset, m = self.cset, self.m
        for s, c in enumerate(self.active):
            row = ext.J[m + s]
            if c.kind == "joint":
                cset.joint_limits.row(c.index, row)  # type: ignore[union-attr]
                c.feed = 0.0
            elif c.kind == "dexterity":
                dexterity_row(model, data, self.frame_id, self.task_rows, ext.J[:m], row)
                c.feed = 0.0
            else:  # obstacle (13)-(15), or a link pair: the second link in the obstacle's place
                Jp = point_jacobian(model, data, c.joint, c.point_a)
                if c.kind == "obstacle":
                    form, velocity = cset.form, cset.obs_vel[c.obstacle]
                else:
                    Jp = Jp - point_jacobian(model, data, c.joint_b, c.point_b)
                    form, velocity = "normalized", _NO_POINT
                c.error, c.feed = obstacle_row(
                    form, c.threshold, c.distance, c.point_a, c.point_b, c.normal, Jp, velocity, row
                )
            ext.e[m + s] = c.error
            ext.ff[m + s] = c.feed
            ext.K[m + s] = self._gain(c.kind, float(row @ row))
        return len(self.active)

    def _project_release(self, tk: float, ext: ExtendedTask, law: LawFunction, v: int) -> int:
        """Release one constraint at its threshold whose row-free solution moves away."""
        m = self.m
        for s in range(v):
            c = self.active[s]
            if c.error > _AT_THRESHOLD * c.scale:
                continue
            last = m + v - 1
            if s != v - 1:  # move this row last, so the law can run without it
                ext.swap(m + s, last)
                self.active[s], self.active[v - 1] = self.active[v - 1], self.active[s]
            law(last, self._qdot)
            edot = ext.ff[last] - float(ext.J[last] @ self._qdot)
            if edot <= 0.0:
                self.active.pop()
                self._event(tk, c.key, "release")
                return v - 1
        return v

    def _event(self, tk: float, key: str, action: str) -> None:
        self.events.append({"t": round(tk, 9), "constraint": key, "action": action})

    # -- recording ---------------------------------------------------------------------

    def record(self, j: int) -> None:
        """Keep this sample's distances, active set and witness points in slot ``j``."""
        if self.cset.obstacles:
            self.rec_dist[j] = self.dist_o
            self.rec_link[j] = self.link_o
        for s, c in enumerate(self.active):
            code = self.codes.setdefault(c.key, len(self.codes))
            self.rec_active[j, s] = code
            if c.kind in ("obstacle", "self"):
                self.rec_witness[j, s, 0] = c.point_a
                self.rec_witness[j, s, 1] = c.point_b

    def active_names(self) -> list[str]:
        """Names of the active constraints."""
        return [c.key for c in self.active]

    def active_rows(self) -> list[Candidate]:
        """The active constraints, in row order."""
        return list(self.active)

    def skipped_names(self) -> list[str]:
        """Constraints that were violated but found no free row, in the order met."""
        return sorted({e["constraint"] for e in self.events if e["action"] == "skipped"})

    def finish(self, result: TrackingResult, n_rec: int) -> None:
        """Move the run's records into the result."""
        cset = self.cset
        result.events = list(self.events)
        names = sorted(self.codes, key=self.codes.__getitem__)
        result.info["constraint_names"] = names
        result.info["obstacles"] = cset.obstacle_info()
        result.info["links"] = cset.link_labels
        result.extra["active"] = self.rec_active[:n_rec]
        result.extra["witness"] = self.rec_witness[:n_rec]
        extra: dict[str, Any] = {
            "min_obstacle_distance": None,
            "min_obstacle_distance_by_obstacle": {},
        }
        if cset.obstacles:
            result.extra["obstacle_distance"] = self.rec_dist[:n_rec]
            result.extra["obstacle_link"] = self.rec_link[:n_rec]
            extra["min_obstacle_distance"] = float(self.run_min.min())
            by_name = [(i, o.name) for i, o in enumerate(cset.obstacles)]
            extra["min_obstacle_distance_by_obstacle"] = {
                name: float(self.run_min[i]) for i, name in by_name
            }
            extra["min_obstacle_distance_link_by_obstacle"] = {
                name: self.run_min_link[i] for i, name in by_name
            }
            extra["min_obstacle_distance_exact_by_obstacle"] = {
                name: bool(np.isfinite(self.run_min[i])) for i, name in by_name
            }
            extra["min_obstacle_distance_time_by_obstacle"] = {
                name: float(self.run_min_t[i]) for i, name in by_name
            }
        if cset.joint_limits is not None:
            extra["joint_limits_used"] = cset.joint_limits_used()
        if cset.dexterity is not None:
            extra["dexterity_used"] = cset.dexterity_used()
        result.info["summary_extra"] = extra
