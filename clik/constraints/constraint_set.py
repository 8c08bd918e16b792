r"""The constraint bookkeeping around the CLIK step: candidates, activation, release.

The augmented task (METHOD.md, eqs. (20)-(25)) stacks the task rows and the
*active* constraint rows: ``J_e = (J; J_o; U)`` (24), ``e_e = (e; e_o; e_q)``
(25), and the law runs on them (``qdot = K J_e^T e_e`` for (23)). Per sample:

1. every monitored constraint's error is evaluated (joint ranges for all
   joints at once; link-obstacle and link-link pairs after a bounding-sphere
   prune, with coal's witness points);
2. **activation**: a constraint whose threshold is violated (error > 0) is
   activated, the most violated first, up to ``v <= n - m`` rows (22); the
   others are recorded as ``skipped``;
3. **release**: ``"sign"`` is the paper's rule (release when the error turns
   negative, less a hysteresis); ``"projection"`` releases a constraint only
   when it is at or beyond its threshold and the law computed *without* its
   row moves away from it (METHOD.md, "Implementation notes"): one activation
   and at most one release per constraint where the sign rule chatters.

Events are ``{"t", "constraint", "action"}`` records with action
``activate``, ``release`` or ``skipped``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.constraints.collision_scene import CollisionScene
from clik.constraints.joint_limits import JointLimits
from clik.constraints.obstacle import Obstacle
from clik.constraints.obstacle_rows import FORMS, obstacle_row, point_jacobian
from clik.errors import InputError

if TYPE_CHECKING:
    from clik.result import TrackingResult
    from clik.tracking import Tracker

RELEASE_RULES = ("projection", "sign")
_AT_THRESHOLD = 1e-6
"""A constraint is "at its threshold" when its error is below this fraction of its scale."""


class _Candidate:
    """One constraint whose row may enter the extended task at this sample."""

    __slots__ = ("error", "feed", "gain_scale", "key", "kind", "payload", "scale")

    def __init__(self, key: str, kind: str, error: float, scale: float, payload: Any) -> None:
        self.key, self.kind, self.error, self.scale, self.payload = key, kind, error, scale, payload
        self.feed = 0.0
        self.gain_scale = 1.0


class ConstraintSet:
    """Obstacle, joint-range and self-collision constraints of one run.

    Args:
        robot: The robot.
        obstacles: Obstacles; their distances are always monitored (recorded per sample).
        obstacle_rows: Whether obstacle rows may enter the task (False: monitor only).
        obstacle_threshold: Default ``d_o`` [m] (an obstacle's own threshold wins).
        obstacle_gain: Gain of obstacle rows [1/s]; None: the default of the law (see below).
        form: ``"normalized"`` (default) or ``"squared"`` (the paper's eq. (13)).
        links: Link names checked against obstacles (default: all with collision geometry).
        joint_limits: Joint-range rows (:class:`JointLimits`), or None.
        joint_gain: Gain of joint-range rows [1/s]; None: default of the law.
        self_collision: Link-link rows.
        self_threshold: Threshold of link-link pairs [m].
        self_gain: Gain of link-link rows [1/s]; None: default of the law.
        release: ``"projection"`` (default) or ``"sign"``.
        hysteresis: With the sign rule, release only when the error is below
            ``-hysteresis * threshold``.
        max_active: Bound on active rows (default and maximum ``n - m``, eq. (22)).
        monitor_margin: An obstacle's recorded distance is exact within
            ``threshold + monitor_margin`` [m]; beyond it, a lower bound no smaller than that
            (``min_obstacle_distance_exact_by_obstacle`` in the summary says which).

    Default gains: with law (10) every row gets the task's largest gain ``alpha``
    (``J_e^+`` normalises rows). With laws (9) and (8) a row adds about
    ``K dt |j|^2`` to ``dt lambda_max(K J_e J_e^T)``, which the task rows already
    bring near 1 when ``alpha = 1/dt``; the default ``K = alpha / (2 max(1, |j|^2))``
    keeps the sum below 2 (a row with ``K = alpha`` makes the case study's
    explicit Euler oscillate, measured).
    """

    def __init__(
        self,
        robot: object,
        *,
        obstacles: Sequence[Obstacle] = (),
        obstacle_rows: bool = True,
        obstacle_threshold: float = 0.03,
        obstacle_gain: float | None = None,
        form: str = "normalized",
        links: Sequence[str] | None = None,
        joint_limits: JointLimits | None = None,
        joint_gain: float | None = None,
        self_collision: bool = False,
        self_threshold: float = 0.01,
        self_gain: float | None = None,
        release: str = "projection",
        hysteresis: float = 0.0,
        max_active: int | None = None,
        monitor_margin: float = 0.1,
    ) -> None:
        if form not in FORMS:
            raise InputError("constraints.obstacles.form", "'normalized' or 'squared'", form)
        if release not in RELEASE_RULES:
            raise InputError("constraints.release", "'projection' or 'sign'", release)
        for field, value in (
            ("obstacle_threshold", obstacle_threshold),
            ("self_threshold", self_threshold),
            ("monitor_margin", monitor_margin),
        ):
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"constraints.{field}", "a positive distance [m]", value)
        for field, value in (
            ("obstacle_gain", obstacle_gain),
            ("joint_gain", joint_gain),
            ("self_gain", self_gain),
        ):
            if value is not None and not (math.isfinite(value) and value > 0):
                raise InputError(f"constraints.{field}", "a positive gain [1/s]", value)
        if not (math.isfinite(hysteresis) and hysteresis >= 0):
            raise InputError("constraints.hysteresis", "a number >= 0", hysteresis)
        self.robot = robot
        self.obstacles = list(obstacles)
        self.obstacle_rows = obstacle_rows
        self.obstacle_threshold = float(obstacle_threshold)
        self.gains = {"obstacle": obstacle_gain, "joint": joint_gain, "self": self_gain}
        self.form = form
        self.joint_limits = joint_limits
        self.self_threshold = float(self_threshold)
        self.release_rule = release
        self.hysteresis = float(hysteresis)
        self.max_active = max_active
        self.monitor_margin = float(monitor_margin)
        self._links = links
        self._self_collision = self_collision
        self.max_rows = robot.nv  # type: ignore[attr-defined]
        self.min_distance = math.inf
        self.events: list[dict[str, Any]] = []
        self.set_obstacles(self.obstacles)

    # -- obstacles between runs ----------------------------------------------------------

    def set_obstacles(self, obstacles: Sequence[Obstacle]) -> None:
        """Replace the obstacles (add, remove) between runs, keeping the robot as loaded.

        The link hulls are computed once per robot; only the collision pairs are rebuilt.
        """
        obstacles = list(obstacles)
        names = [o.name for o in obstacles]
        if len(set(names)) != len(names):
            raise InputError("obstacles", "distinct obstacle names", names)
        self.obstacles = obstacles
        need_scene = bool(obstacles) or self._self_collision
        self.scene = (
            CollisionScene(self.robot, obstacles, self._links, self._self_collision)
            if need_scene
            else None
        )
        self._setup_scene()

    def move_obstacle(
        self,
        name: str,
        position: Sequence[float] | np.ndarray,
        rpy: Sequence[float] | None = None,
        velocity: Sequence[float] | None = None,
    ) -> None:
        """Move an obstacle between runs (no rebuild): new position [m], rpy [rad], velocity."""
        names = [o.name for o in self.obstacles]
        if name not in names:
            raise InputError("obstacle", f"one of {names}", name)
        i = names.index(name)
        ob = self.obstacles[i]
        moved = Obstacle.__new__(Obstacle)
        moved.__dict__.update(ob.__dict__)
        moved.position = np.array(position, dtype=float)
        if moved.position.shape != (3,) or not np.all(np.isfinite(moved.position)):
            raise InputError(f"obstacles.{name}.position", "three finite numbers", position)
        if rpy is not None:
            moved.rpy = np.array(rpy, dtype=float)
            moved.rotation = pin.rpy.rpyToMatrix(*moved.rpy)
        if velocity is not None:
            moved.velocity = np.array(velocity, dtype=float)
        self.obstacles[i] = moved
        assert self.scene is not None
        self.scene.replace_obstacle(i, moved)
        self.obs_vel[i] = moved.velocity

    # -- set-up ------------------------------------------------------------------------

    def _setup_scene(self) -> None:
        scene = self.scene
        n_obs = len(self.obstacles)
        self.obs_threshold = np.array(
            [
                o.threshold if o.threshold is not None else self.obstacle_threshold
                for o in self.obstacles
            ]
        )
        self.obs_vel = np.array([o.velocity for o in self.obstacles]).reshape(n_obs, 3)
        if scene is None:
            self.link_labels: list[str] = []
            return
        counts: dict[str, int] = {}
        for link in scene.link_names:
            counts[link] = counts.get(link, 0) + 1
        geoms = scene.gmodel.geometryObjects
        self.link_labels = [
            link if counts[link] == 1 else geoms[i].name for i, link in enumerate(scene.link_names)
        ]
        self.pair_names = [
            [f"obstacle:{o.name}:{label}" for o in self.obstacles] for label in self.link_labels
        ]
        if scene.self_pairs:
            sp = np.array([(a, b) for _, a, b in scene.self_pairs])
            self.self_slots = (scene.link_slot[sp[:, 0]], scene.link_slot[sp[:, 1]])
        self._rho = scene.motion_bounds()
        self._thr_matrix = np.broadcast_to(self.obs_threshold, (scene.n_links, n_obs)).copy()
        self._margin = self.obs_threshold + self.monitor_margin
        self._near = np.zeros((scene.n_links, n_obs), dtype=bool)
        self._better = np.zeros(n_obs, dtype=bool)
        self._obs_index = np.arange(n_obs)

    def bind(self, tracker: Tracker) -> None:
        """Attach to a tracker (called by :class:`~clik.tracking.Tracker`)."""
        self.tracker = tracker
        self.m = tracker.task.m
        nv = self.robot.nv  # type: ignore[attr-defined]
        free = nv - self.m
        self.limit = free if self.max_active is None else min(int(self.max_active), free)
        if self.limit <= 0 and (self.obstacle_rows or self.joint_limits is not None):
            raise InputError(
                "constraints",
                f"a redundant task (n - m > 0) for constraint rows: n = {nv}, m = {self.m}",
            )
        self.alpha = float(np.max(tracker.K_task))
        self.law = tracker.law
        self._row = np.zeros(nv)
        self._qdot = np.zeros(nv)

    def reset(self, q: np.ndarray, t: np.ndarray, n_rec: int) -> None:
        """Start a run on time grid ``t``, with ``n_rec`` recorded samples."""
        self.t = t
        self.active: list[_Candidate] = []
        self._skipped: set[str] = set()
        self.events = []
        self.min_distance = math.inf
        n_obs = len(self.obstacles)
        self.run_min = np.full(n_obs, np.inf)
        self.run_min_link = ["" for _ in range(n_obs)]
        self.run_min_t = np.zeros(n_obs)
        self.run_min_exact = [False] * n_obs
        self.codes: dict[str, int] = {}
        self.rec_dist = np.full((n_rec, n_obs), np.inf)
        self.rec_link = np.full((n_rec, n_obs), -1, dtype=np.int16)
        self.rec_active = np.full((n_rec, max(self.limit, 1)), -1, dtype=np.int32)
        self.rec_witness = np.full((n_rec, max(self.limit, 1), 2, 3), np.nan)
        self._dist_o = np.full(n_obs, np.inf)
        self._link_o = np.full(n_obs, -1, dtype=np.int16)
        if self.scene is not None:  # distance certificates: unknown (-inf) at the start
            self._lb = np.full((self.scene.n_links, n_obs), -np.inf)
            self._evaluated = np.zeros((self.scene.n_links, n_obs), dtype=bool)
        self._q_prev: np.ndarray | None = None
        self._joint_slack = -1.0  # unknown: evaluate at the first sample
        dt = float(t[1] - t[0]) if t.shape[0] > 1 else 0.0
        speed = np.linalg.norm(self.obs_vel, axis=1) * dt
        self._obs_step = speed[None, :] if np.any(speed > 0.0) else None

    # -- per step ----------------------------------------------------------------------

    def update(self, k: int, q: np.ndarray) -> int:
        """Evaluate, activate, fill the active rows and release; returns ``v`` active rows."""
        tk = float(self.t[k])
        candidates = self._evaluate(tk, q)
        self._q_prev = q  # the tracker makes a new array per step (pin.integrate)
        active_keys = {c.key for c in self.active}
        current = {c.key: c for c in candidates}
        # Refresh the active constraints' data; drop those no longer evaluated (far away).
        still = []
        for c in self.active:
            new = current.get(c.key)
            if new is None:
                self._event(tk, c.key, "release")
            elif self.release_rule == "sign" and new.error < -self.hysteresis * new.scale:
                self._event(tk, c.key, "release")
            else:
                still.append(new)
        self.active = still
        # Activation, most violated first, within the bound (22).
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
            violated = {c.key for c in fresh}
            self._skipped &= violated
        v = self._fill_rows(q)
        if self.release_rule == "projection" and v:
            v = self._project_release(tk, v)
        return v

    def _evaluate(self, tk: float, q: np.ndarray) -> list[_Candidate]:
        """Constraints whose error is positive, or that are active, at this sample."""
        out: list[_Candidate] = []
        active = {c.key for c in self.active}
        # |dq| since the last sample, shared by the joint-range and obstacle certificates
        if self._q_prev is None:
            self._dq_abs = None
        else:
            dq = pin.difference(self.robot.model, self._q_prev, q)  # type: ignore[attr-defined]
            self._dq_abs = np.abs(dq, out=dq)
        jl = self.joint_limits
        if jl is not None:
            # Certificate: the smallest margin to a threshold band, lowered by max |dq| per
            # step; the rows are evaluated only when it may be crossed or a row is active.
            if self._dq_abs is not None:
                self._joint_slack -= float(self._dq_abs.max())
            joint_active = any(c.kind == "joint" for c in self.active)
            if self._joint_slack <= 0.0 or joint_active:
                self._joint_slack = jl.slack(q)
        if jl is not None and (self._joint_slack <= 0.0 or joint_active):
            e = jl.evaluate(q)
            for i in np.flatnonzero(e > -jl._thr):
                key = jl.names[i]
                if e[i] > 0.0 or key in active:
                    out.append(_Candidate(key, "joint", float(e[i]), float(jl._thr[i]), int(i)))
        if self.scene is not None:
            self._evaluate_scene(tk, out, active)
        return out

    def _evaluate_scene(self, tk: float, out: list[_Candidate], active: set[str]) -> None:
        """Link-obstacle pairs through distance certificates, then link-link pairs.

        Every pair keeps a lower bound of its distance: exact when coal last evaluated
        it, lowered each step by how far the link can have moved (``rho |dq|``, see
        :meth:`CollisionScene.motion_bounds`) and the obstacle's ``|v| dt``. coal is
        asked only for pairs whose bound is below the threshold (or active) and, per
        obstacle, for the nearest pair within ``threshold + monitor_margin``, so the
        recorded per-obstacle minimum is exact there and a lower bound beyond it.
        """
        scene = self.scene
        assert scene is not None
        robot = self.robot
        data = robot.data  # type: ignore[attr-defined]
        placed = False
        self.min_distance = math.inf
        if self.obstacles:
            lb, evaluated = self._lb, self._evaluated
            if self._dq_abs is not None:
                lb -= self._rho.dot(self._dq_abs)[:, None]
                if self._obs_step is not None:
                    lb -= self._obs_step
            evaluated[:] = False
            near = np.less(lb, self._thr_matrix, out=self._near)
            todo = np.argwhere(near).tolist() if near.any() else []
            todo += [c.payload[7] for c in self.active if c.kind == "obstacle"]
            thr_o, margin_o = self.obs_threshold, self._margin
            while True:  # evaluate, then the nearest pair of each obstacle, until settled
                for i, o in todo:
                    if evaluated[i, o]:
                        continue
                    if not placed:
                        scene.place_geometries(data, tk)
                        placed = True
                    dist, p_link, p_obs, normal = scene.distance(int(scene.obstacle_pairs[i, o]))
                    lb[i, o] = dist
                    evaluated[i, o] = True
                    thr = float(thr_o[o])
                    key = self.pair_names[i][o]
                    if self.obstacle_rows and (dist < thr or key in active):
                        squared = self.form != "normalized"
                        out.append(
                            _Candidate(
                                key,
                                "obstacle",
                                0.5 * (thr * thr - dist * abs(dist)) if squared else thr - dist,
                                0.5 * thr * thr if squared else thr,
                                (
                                    int(scene.link_joint[i]),
                                    dist,
                                    p_link,
                                    p_obs,
                                    normal,
                                    thr,
                                    o,
                                    (i, o),
                                ),
                            )
                        )
                nearest = lb.argmin(axis=0)
                dist_o = lb[nearest, self._obs_index]
                unsure = (dist_o < margin_o) & ~evaluated[nearest, self._obs_index]
                if not unsure.any():
                    break
                todo = [(int(nearest[o]), int(o)) for o in np.flatnonzero(unsure)]
            link_o = self._link_o
            self._dist_o = dist_o
            link_o[:] = nearest
            self.min_distance = float(dist_o.min())
            better = np.less(dist_o, self.run_min, out=self._better)
            if better.any():
                for o in np.flatnonzero(better):
                    self.run_min[o] = dist_o[o]
                    self.run_min_t[o] = tk
                    self.run_min_link[o] = self.link_labels[link_o[o]]
                    self.run_min_exact[o] = bool(evaluated[link_o[o], o])
        if scene.self_pairs:
            pos, r = scene.place_joints(data), scene.joint_radius
            a, b = self.self_slots
            gap = np.linalg.norm(pos[a] - pos[b], axis=1) - r[a] - r[b]
            close = np.flatnonzero(gap < self.self_threshold + self.monitor_margin)
            if close.size and not placed:
                scene.place_geometries(data, tk)
            for idx in close:
                pair, ia, ib = scene.self_pairs[idx]
                dist, pa, pb, normal = scene.distance(pair)
                key = f"self:{self.link_labels[ia]}:{self.link_labels[ib]}"
                if dist < self.self_threshold or key in active:
                    out.append(
                        _Candidate(
                            key,
                            "self",
                            self.self_threshold - dist,
                            self.self_threshold,
                            (
                                int(scene.link_joint[ia]),
                                int(scene.link_joint[ib]),
                                dist,
                                pa,
                                pb,
                                normal,
                            ),
                        )
                    )

    def _gain(self, kind: str, row_norm2: float) -> float:
        given = self.gains[kind]
        if given is not None:
            return given
        if self.law == "pseudoinverse":
            return self.alpha
        return 0.5 * self.alpha / max(1.0, row_norm2)

    def _fill_rows(self, q: np.ndarray) -> int:
        tr = self.tracker
        model, data = self.robot.model, self.robot.data  # type: ignore[attr-defined]
        m = self.m
        for s, c in enumerate(self.active):
            row = tr.J_e[m + s]
            if c.kind == "joint":
                self.joint_limits.row(c.payload, row)  # type: ignore[union-attr]
                c.feed = 0.0
            elif c.kind == "obstacle":
                joint, dist, p_link, p_obs, normal, thr, o, _ = c.payload
                Jp = point_jacobian(model, data, joint, p_link)
                c.error, c.feed = obstacle_row(
                    self.form, thr, dist, p_link, p_obs, normal, Jp, self.obs_vel[o], row
                )
            else:
                ja, jb, dist, pa, pb, normal = c.payload
                Jp = point_jacobian(model, data, ja, pa) - point_jacobian(model, data, jb, pb)
                c.error, c.feed = obstacle_row(
                    "normalized", self.self_threshold, dist, pa, pb, normal, Jp, np.zeros(3), row
                )
            tr.e_e[m + s] = c.error
            tr.ff_e[m + s] = c.feed
            tr.K_e[m + s] = self._gain(c.kind, float(row @ row))
        return len(self.active)

    def _project_release(self, tk: float, v: int) -> int:
        """Release one constraint at its threshold whose row-free solution moves away."""
        tr, m = self.tracker, self.m
        for s in range(v):
            c = self.active[s]
            if c.error > _AT_THRESHOLD * c.scale:
                continue
            last = m + v - 1
            if s != v - 1:  # move this row last, so the law can run without it
                _swap(tr, m + s, last)
                self.active[s], self.active[v - 1] = self.active[v - 1], self.active[s]
            tr.law_velocity(last, self._qdot)
            edot = tr.ff_e[last] - float(tr.J_e[last] @ self._qdot)
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
        if self.obstacles:
            self.rec_dist[j] = self._dist_o
            self.rec_link[j] = self._link_o
        for s, c in enumerate(self.active):
            code = self.codes.setdefault(c.key, len(self.codes))
            self.rec_active[j, s] = code
            if c.kind == "obstacle":
                self.rec_witness[j, s, 0] = c.payload[2]
                self.rec_witness[j, s, 1] = c.payload[3]
            elif c.kind == "self":
                self.rec_witness[j, s, 0] = c.payload[3]
                self.rec_witness[j, s, 1] = c.payload[4]

    def active_names(self) -> list[str]:
        """Names of the active constraints."""
        return [c.key for c in self.active]

    def finish(self, result: TrackingResult, n_rec: int) -> None:
        """Move the run's records into the result."""
        result.events = list(self.events)
        names = sorted(self.codes, key=self.codes.__getitem__)
        result.info["constraint_names"] = names
        result.info["obstacles"] = [
            {
                "name": o.name,
                "shape": o.shape,
                "position": o.position.tolist(),
                "rpy": o.rpy.tolist(),
                "velocity": o.velocity.tolist(),
                "threshold": float(self.obs_threshold[i]),
                **o.params,
            }
            for i, o in enumerate(self.obstacles)
        ]
        result.info["links"] = self.link_labels
        result.extra["active"] = self.rec_active[:n_rec]
        result.extra["witness"] = self.rec_witness[:n_rec]
        extra: dict[str, Any] = {
            "min_obstacle_distance": None,
            "min_obstacle_distance_by_obstacle": {},
        }
        if self.obstacles:
            result.extra["obstacle_distance"] = self.rec_dist[:n_rec]
            result.extra["obstacle_link"] = self.rec_link[:n_rec]
            extra["min_obstacle_distance"] = float(self.run_min.min())
            extra["min_obstacle_distance_by_obstacle"] = {
                o.name: float(self.run_min[i]) for i, o in enumerate(self.obstacles)
            }
            extra["min_obstacle_distance_link_by_obstacle"] = {
                o.name: self.run_min_link[i] for i, o in enumerate(self.obstacles)
            }
            extra["min_obstacle_distance_exact_by_obstacle"] = {
                o.name: self.run_min_exact[i] for i, o in enumerate(self.obstacles)
            }
            extra["min_obstacle_distance_time_by_obstacle"] = {
                o.name: float(self.run_min_t[i]) for i, o in enumerate(self.obstacles)
            }
        if self.joint_limits is not None:
            extra["joint_limits_used"] = {
                "lower": self.joint_limits.lower.tolist(),
                "upper": self.joint_limits.upper.tolist(),
                "threshold": self.joint_limits.threshold.tolist(),
            }
        result.info["summary_extra"] = extra


def _swap(tr: Tracker, a: int, b: int) -> None:
    for arr in (tr.J_e, tr.e_e, tr.ff_e, tr.K_e):
        tmp = arr[a].copy()
        arr[a] = arr[b]
        arr[b] = tmp
