r"""Obstacle avoidance, eqs. (13)-(15): one row per link-obstacle pair inside its threshold.

Every link geometry is paired with every obstacle. A pair's error is (13) in the
set's form (:func:`~clik.constraints.obstacle_rows.obstacle_error`), its row
``n^T J_po`` (or ``d^T J_po``) and feed-forward ``n^T cdot`` (14)-(15)
(:func:`~clik.constraints.obstacle_rows.obstacle_row`), from coal's witness points.

Distances are monitored through certificates (docs/method.md, "Statuses and
violations"): each pair keeps a lower bound of its distance, exact when coal last
evaluated it, lowered each sample by how far the link can have moved
(``rho |dq|``, :meth:`~clik.constraints.collision_scene.CollisionScene.motion_bounds`)
and the obstacle's ``|v| dt``. coal is asked only for pairs whose bound is below
the threshold (or active) and, per obstacle, for the nearest pair within
``threshold + monitor_margin`` (every obstacle's nearest pair on a recorded
sample), so per-obstacle minima are exact there. The limit guarded is the
obstacle's surface (a signed distance below zero).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.constraints.kind import (
    CHECK_TOLERANCE,
    Candidate,
    ConstraintKind,
    KindRun,
    PoseCheck,
    RunSetup,
    Sample,
    Violation,
)
from clik.constraints.obstacle import Obstacle
from clik.constraints.obstacle_rows import FORMS, obstacle_error, obstacle_row, point_jacobian
from clik.constraints.read_only import ReadOnlyList
from clik.constraints.words import MILLIMETRES, PENETRATED
from clik.errors import InputError

if TYPE_CHECKING:
    from clik.constraints.collision_scene import CollisionScene
    from clik.constraints.violations import ViolationMonitor
    from clik.outputs.result import TrackingResult


class ObstacleAvoidance(ConstraintKind):
    """Link-obstacle rows (13)-(15); the obstacles' distances are always monitored.

    Args:
        obstacles: The obstacles.
        rows: Whether their rows may enter the task (False: monitor only).
        threshold: Default ``d_o`` [m] (an obstacle's own threshold wins).
        form: ``"normalized"`` (default) or ``"squared"`` (the paper's (13)).
        gain: The rows' gain [1/s]; None: the law's default.
    """

    name = "obstacle"
    per_sample = ("obstacle_distance", "obstacle_link")
    depth_measure = MILLIMETRES
    limit_words = PENETRATED
    """A link in an obstacle: how deep [m], in mm."""

    def __init__(
        self,
        obstacles: Sequence[Obstacle] = (),
        rows: bool = True,
        threshold: float = 0.03,
        form: str = "normalized",
        gain: float | None = None,
    ) -> None:
        if form not in FORMS:
            raise InputError("constraints.obstacles.form", "'normalized' or 'squared'", form)
        for i, o in enumerate(obstacles):
            if not isinstance(o, Obstacle):
                raise InputError(f"obstacles[{i}]", "an Obstacle(name, shape, position, ...)", o)
        names = [o.name for o in obstacles]
        if len(set(names)) != len(names):
            raise InputError("obstacles", "distinct obstacle names", names)
        self.obstacles = ReadOnlyList(
            obstacles,
            "obstacles",
            "ConstraintSet.set_obstacles([...]) or ConstraintSet.move_obstacle(...)",
        )
        self.rows = bool(rows)
        self.threshold = float(threshold)
        self.form = form
        self.gain = gain
        self.thresholds = np.array(
            [o.threshold if o.threshold is not None else self.threshold for o in self.obstacles]
        )
        """``d_o`` per obstacle [m]."""
        self.velocities = np.array([o.velocity for o in self.obstacles]).reshape(-1, 3)
        """``cdot`` per obstacle (n_obs, 3) [m/s]."""
        self.thresholds.flags.writeable = self.velocities.flags.writeable = False

    @classmethod
    def check_name(cls, key: str) -> str:
        """``obstacle:ball:link4`` -> ``obstacle 'ball'`` (the check takes its nearest link)."""
        return f"obstacle {key.partition(':')[2].rpartition(':')[0]!r}"

    @property
    def wants_rows(self) -> bool:
        """Rows unless the set only monitors its obstacles."""
        return self.rows

    def start(self, setup: RunSetup) -> ObstacleRun:
        """The pairs' certificates and records for one run."""
        return ObstacleRun(self, setup)

    def engine_config(self) -> Any:
        """``_engine.ObstacleRowsConfig`` (each obstacle's geometry found from the scene)."""
        from clik.engine import load

        engine = load()
        configs = [
            engine.ObstacleConfig(
                name=o.name,
                position=o.position,
                rotation=o.rotation,
                velocity=self.velocities[i],
                threshold=float(self.thresholds[i]),
            )
            for i, o in enumerate(self.obstacles)
        ]
        return engine.ObstacleRowsConfig(
            obstacles=configs, rows=self.rows, form=self.form, gain=self.gain
        )

    def moved(self, i: int, obstacle: Obstacle) -> ObstacleAvoidance:
        """A new kind with obstacle ``i`` replaced by ``obstacle`` (this one is unchanged)."""
        obstacles = [obstacle if k == i else o for k, o in enumerate(self.obstacles)]
        return ObstacleAvoidance(obstacles, self.rows, self.threshold, self.form, self.gain)

    def info(self) -> list[dict[str, Any]]:
        """Each obstacle as a run's ``info["obstacles"]`` lists it (threshold included)."""
        return [
            {
                "name": o.name,
                "shape": o.shape,
                "position": o.position.tolist(),
                "rpy": o.rpy.tolist(),
                "velocity": o.velocity.tolist(),
                "threshold": float(self.thresholds[i]),
                **o.params,
            }
            for i, o in enumerate(self.obstacles)
        ]

    def finish(
        self, result: TrackingResult, records: dict[str, Any], n_rec: int, extra: dict[str, Any]
    ) -> None:
        """Distances per obstacle: the record's columns and the summary's minima."""
        result.info["obstacles"] = self.info()
        extra["min_obstacle_distance"] = None
        extra["min_obstacle_distance_by_obstacle"] = {}
        if not self.obstacles:
            return
        result.extra["obstacle_distance"] = records["obstacle_distance"][:n_rec]
        result.extra["obstacle_link"] = records["obstacle_link"][:n_rec]
        run_min, labels = np.asarray(records["run_min"]), result.info["links"]
        names = [o.name for o in self.obstacles]
        extra["min_obstacle_distance"] = float(run_min.min())
        extra["min_obstacle_distance_by_obstacle"] = {
            name: float(run_min[i]) for i, name in enumerate(names)
        }
        extra["min_obstacle_distance_link_by_obstacle"] = {
            name: labels[link] if link >= 0 else ""
            for name, link in zip(names, records["run_min_link"], strict=True)
        }
        extra["min_obstacle_distance_exact_by_obstacle"] = {
            name: bool(np.isfinite(run_min[i])) for i, name in enumerate(names)
        }
        extra["min_obstacle_distance_time_by_obstacle"] = {
            name: float(records["run_min_t"][i]) for i, name in enumerate(names)
        }

    def check(self, checker: PoseCheck, q: np.ndarray) -> list[Violation]:
        """Obstacles nearer than their ``d_o`` to some link (13), from coal."""
        scene = checker.scene
        if scene is None or not self.obstacles:
            return []
        results = checker.distances(q)
        out = []
        for o, obstacle in enumerate(self.obstacles):
            thr = float(self.thresholds[o])
            column = [results[int(p)].min_distance for p in scene.obstacle_pairs[:, o]]
            if not column:
                continue
            i = int(np.argmin(column))
            d = float(column[i])
            if thr - d > CHECK_TOLERANCE or not math.isfinite(d):
                link = scene.link_labels[i]
                detail = f"link {link} at {d:.4g} m < threshold {thr:.4g} m"
                name = self.check_name(f"obstacle:{obstacle.name}:{link}")
                out.append(Violation(name, detail, thr - d))
        return out

    def with_margin(self, margin: float) -> ObstacleAvoidance:
        """Every threshold ``margin`` larger, rows on (solve mode)."""
        moved_out = []
        for obstacle, threshold in zip(self.obstacles, self.thresholds, strict=True):
            o = copy.copy(obstacle)
            o.threshold = float(threshold) + margin
            moved_out.append(o)
        return ObstacleAvoidance(moved_out, True, self.threshold + margin, self.form, self.gain)

    def fingerprint(self) -> tuple[Any, ...]:
        """Obstacles' poses and thresholds, form, gain."""
        obstacles = tuple(
            (o.name, o.position.tobytes(), o.rotation.tobytes(), id(o.geometry), float(thr))
            for o, thr in zip(self.obstacles, self.thresholds, strict=True)
        )
        return (obstacles, self.threshold, self.form, self.rows, self.gain)


def pair_names(kind: ObstacleAvoidance, scene: CollisionScene) -> list[list[str]]:
    """``obstacle:<obstacle>:<link>`` per (link geometry, obstacle)."""
    return [[f"obstacle:{o.name}:{label}" for o in kind.obstacles] for label in scene.link_labels]


class ObstacleRun(KindRun):
    """Link-obstacle pairs in one run: certificates, candidates, rows, records.

    Attributes:
        dist_o: Per obstacle, this sample's nearest link distance [m]: exact when below
            the threshold plus the monitor margin, or on a recorded sample; else a
            lower bound.
        exact_o: Per obstacle, whether ``dist_o`` is exact.
        link_o: Per obstacle, the link geometry of ``dist_o``.
    """

    def __init__(self, kind: ObstacleAvoidance, setup: RunSetup) -> None:
        super().__init__(kind)
        self.kind: ObstacleAvoidance = kind
        n_obs = len(kind.obstacles)
        self.scene = setup.scene
        self.geometry = setup.geometry
        self.n_obs = n_obs
        n_rec = setup.n_rec
        self.dist_o = np.full(n_obs, np.inf)
        self.exact_o = np.zeros(n_obs, dtype=bool)
        self.link_o = np.full(n_obs, -1, dtype=np.int16)
        self.run_min = np.full(n_obs, np.inf)
        self.run_min_link = [-1] * n_obs
        self.run_min_t = np.zeros(n_obs)
        self._moved = np.zeros(n_obs, dtype=bool)  # moved since the last sample
        self.rec_dist = np.full((n_rec, n_obs), np.inf)
        self.rec_link = np.full((n_rec, n_obs), -1, dtype=np.int16)
        self._local = pin.SE3.Identity()  # a witness point in its joint's frame (row)
        scene = self.scene
        if scene is None or not n_obs:
            return
        self.names = pair_names(kind, scene)
        self.rho = scene.motion_bounds()
        self.thr_matrix = np.broadcast_to(kind.thresholds, (scene.n_links, n_obs)).copy()
        self.margin = kind.thresholds + setup.monitor_margin
        self._lb = np.full((scene.n_links, n_obs), -np.inf)  # unknown at the start
        self._evaluated = np.zeros((scene.n_links, n_obs), dtype=bool)
        self._near = np.zeros((scene.n_links, n_obs), dtype=bool)
        self.dt = setup.dt
        speed = np.linalg.norm(kind.velocities, axis=1) * setup.dt
        self._obs_step = speed[None, :] if np.any(speed > 0.0) else None
        self._obs_index = np.arange(n_obs)
        self._everywhere = np.full(n_obs, np.inf)  # the margin of a recorded sample
        self._pairs: dict[int, tuple[float, np.ndarray, np.ndarray, np.ndarray, int]] = {}

    def evaluate(self, s: Sample, out: list[Candidate]) -> None:
        """Pairs through distance certificates; candidates inside their threshold or active."""
        scene = self.scene
        if scene is None or not self.n_obs:
            return
        kind, lb, evaluated = self.kind, self._lb, self._evaluated
        n_obs = self.n_obs
        if s.dq_abs is not None:
            lb -= self.rho.dot(s.dq_abs)[:, None]
            if self._obs_step is not None:
                lb -= self._obs_step
        evaluated[:] = False
        near = np.less(lb, self.thr_matrix, out=self._near)
        todo: list[Any] = np.argwhere(near).tolist() if near.any() else []
        todo += [divmod(item, n_obs) for item in s.active_items(self)]
        margin_o = self._everywhere if s.exact else self.margin
        obs_index = self._obs_index
        while True:  # evaluate, then the nearest pair of each obstacle, until settled
            for i, o in todo:
                if evaluated[i, o]:
                    continue
                s.place_geometries()
                c = self._candidate(int(i), int(o))
                lb[i, o] = self._pairs[c.item][0]
                evaluated[i, o] = True
                # an active pair stays a candidate, unless its obstacle was just moved and
                # it is beyond its threshold: released (a jump must not pull the link after it)
                held = c.key in s.active_keys and not self._moved[o]
                if kind.rows and (lb[i, o] < c.threshold or held):
                    out.append(c)
            nearest = lb.argmin(axis=0)
            dist_o = lb[nearest, obs_index]
            unsure = (dist_o < margin_o) & ~evaluated[nearest, obs_index]
            if not unsure.any():
                break
            todo = [(int(nearest[o]), int(o)) for o in np.flatnonzero(unsure)]
        self._moved[:] = False  # a move counts for one sample
        self.dist_o = dist_o
        self.exact_o = evaluated[nearest, obs_index]
        self.link_o[:] = nearest
        exact_d = np.where(self.exact_o, dist_o, np.inf)
        self.min_distance = float(exact_d.min())
        better = exact_d < self.run_min
        for j in np.flatnonzero(better):
            self.run_min[j] = exact_d[j]
            self.run_min_t[j] = s.tk
            self.run_min_link[j] = int(nearest[j])

    def move_obstacle(self, obstacle: Obstacle) -> bool:
        """The obstacle so named, moved (from ``t = 0``); its certificates dropped.

        False: this kind has no obstacle so named.
        """
        names = [o.name for o in self.kind.obstacles]
        if obstacle.name not in names:
            return False
        o = names.index(obstacle.name)
        self.kind = self.kind.moved(o, obstacle)
        if self.scene is None or self.geometry is None:
            return True
        speed = np.linalg.norm(self.kind.velocities, axis=1) * self.dt
        self._obs_step = speed[None, :] if np.any(speed > 0.0) else None
        self._lb[:, o] = -np.inf
        self._moved[o] = True
        g = self.scene.obstacle_geom[o]
        self.geometry.moving = [(h, ob) for h, ob in self.geometry.moving if h != g]
        self.geometry.moving.append((g, obstacle))
        return True

    def _candidate(self, i: int, o: int) -> Candidate:
        """Distance, witness points and error of link geometry ``i`` and obstacle ``o``."""
        scene, geometry = self.scene, self.geometry
        assert scene is not None and geometry is not None
        dist, p_link, p_obs, normal = geometry.distance(int(scene.obstacle_pairs[i, o]))
        thr = float(self.kind.thresholds[o])
        error, scale = obstacle_error(self.kind.form, thr, dist)
        item = i * self.n_obs + o
        self._pairs[item] = (dist, p_link, p_obs, normal, int(scene.link_joint[i]))
        c = Candidate(self.names[i][o], self, item, error, scale, thr)
        c.witness = (p_link, p_obs)
        return c

    def row(self, s: Sample, c: Candidate, out: np.ndarray) -> None:
        """Row (15) and feed-forward (14) of a link-obstacle pair."""
        dist, p_link, p_obs, normal, joint = self._pairs[c.item]
        Jp = point_jacobian(s.model, s.data, joint, p_link, self._local)
        velocity = self.kind.velocities[c.item % self.n_obs]
        c.error, c.feed = obstacle_row(
            self.kind.form, c.threshold, dist, p_link, p_obs, normal, Jp, velocity, out
        )

    def observe_limits(self, tk: float, monitor: ViolationMonitor) -> None:
        """A link inside an obstacle (a penetrating pair is always evaluated: exact)."""
        if self.min_distance < 0.0:
            for o in np.flatnonzero(self.dist_o < 0.0):
                key = self.names[int(self.link_o[o])][o]
                monitor.observe_penetration(tk, key, float(self.dist_o[o]))

    def record(self, j: int) -> None:
        """Each obstacle's nearest distance and link in slot ``j``."""
        if self.n_obs:
            self.rec_dist[j] = self.dist_o
            self.rec_link[j] = self.link_o

    def records(self, n_rec: int) -> dict[str, Any]:
        """The distance record and the per-obstacle minima (the engine's keys)."""
        if not self.n_obs:
            return {}
        return {
            "obstacle_distance": self.rec_dist,
            "obstacle_link": self.rec_link,
            "run_min": self.run_min.copy(),
            "run_min_link": list(self.run_min_link),
            "run_min_t": self.run_min_t.copy(),
        }
