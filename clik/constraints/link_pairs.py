r"""Link pairs (clik's addition): the obstacle row with a second link in the obstacle's place.

For two links of the robot (not adjacent, not touching at the reference
configuration, not disabled by the robot's SRDF, see
:class:`~clik.constraints.collision_scene.CollisionScene`),
``d`` is their signed distance and ``d_o`` the threshold: error ``e = d_o - d``,
row ``n^T (J_pa - J_pb)`` (normalised form of (13)-(15) with both witness points
moving), no feed-forward. Pairs are pruned by bounding spheres before coal is
asked. The limit guarded is contact (a signed distance below zero).
"""

from __future__ import annotations

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
from clik.constraints.obstacle_rows import obstacle_row, point_jacobian
from clik.constraints.words import MILLIMETRES, PENETRATED

if TYPE_CHECKING:
    from clik.constraints.violations import ViolationMonitor


_STILL = np.zeros(3)
_STILL.flags.writeable = False  # a link pair's "obstacle" is at rest: read by every run


class LinkPairs(ConstraintKind):
    """Link-link rows (self-collision).

    Args:
        threshold: ``d_o`` of every pair [m].
        gain: The rows' gain [1/s]; None: the law's default.
    """

    name = "self"
    depth_measure = MILLIMETRES
    limit_words = PENETRATED
    """Two links in contact: how deep [m], in mm."""

    def __init__(self, threshold: float = 0.01, gain: float | None = None) -> None:
        self.threshold = float(threshold)
        self.gain = gain

    @classmethod
    def check_name(cls, key: str) -> str:
        """``self:link1:link5`` -> ``link pair link1-link5``."""
        return "link pair " + key.partition(":")[2].replace(":", "-", 1)

    @property
    def wants_rows(self) -> bool:
        """Link pairs alone do not ask for a free row (they monitor contact)."""
        return False

    def start(self, setup: RunSetup) -> LinkPairRun:
        """The pairs' state for one run."""
        return LinkPairRun(self, setup)

    def engine_config(self) -> Any:
        """``_engine.LinkPairsConfig``."""
        from clik.engine import load

        return load().LinkPairsConfig(threshold=self.threshold, gain=self.gain)

    def check(self, checker: PoseCheck, q: np.ndarray) -> list[Violation]:
        """Link pairs nearer than the threshold, from coal."""
        scene = checker.scene
        if scene is None or not scene.self_pairs:
            return []
        results = checker.distances(q)
        out = []
        labels = scene.link_labels
        for pair, a, b in scene.self_pairs:
            d = float(results[pair].min_distance)
            if self.threshold - d > CHECK_TOLERANCE:
                detail = f"{d:.4g} m apart < threshold {self.threshold:.4g} m"
                name = self.check_name(f"self:{labels[a]}:{labels[b]}")
                out.append(Violation(name, detail, self.threshold - d))
        return out

    def with_margin(self, margin: float) -> LinkPairs:
        """The threshold ``margin`` larger (solve mode)."""
        return LinkPairs(self.threshold + margin, self.gain)

    def fingerprint(self) -> tuple[Any, ...]:
        """Threshold and gain."""
        return (self.threshold, self.gain)


class LinkPairRun(KindRun):
    """Link pairs in one run: bounding-sphere prune, coal, rows, contacts."""

    def __init__(self, kind: LinkPairs, setup: RunSetup) -> None:
        super().__init__(kind)
        self.kind: LinkPairs = kind
        self.scene = setup.scene
        self.geometry = setup.geometry
        self._local = pin.SE3.Identity()  # a witness point in its joint's frame (row)
        self.reach = kind.threshold + setup.monitor_margin
        self.penetrations: list[tuple[str, float]] = []
        self._pairs: dict[int, tuple[float, np.ndarray, np.ndarray, np.ndarray]] = {}
        scene = self.scene
        if scene is None or not scene.self_pairs:
            self.n = 0
            return
        self.n = len(scene.self_pairs)
        labels = scene.link_labels
        self.names = [f"self:{labels[a]}:{labels[b]}" for _, a, b in scene.self_pairs]
        sp = np.array([(a, b) for _, a, b in scene.self_pairs])
        self.slots = (scene.link_slot[sp[:, 0]], scene.link_slot[sp[:, 1]])

    def evaluate(self, s: Sample, out: list[Candidate]) -> None:
        """Pairs whose bounding spheres are near, with coal."""
        scene, geometry = self.scene, self.geometry
        if not self.n or scene is None or geometry is None:
            return
        pos, r = geometry.place_joints(s.data), scene.joint_radius
        a, b = self.slots
        gap = np.linalg.norm(pos[a] - pos[b], axis=1) - r[a] - r[b]
        close = np.flatnonzero(gap < self.reach)
        if close.size:
            s.place_geometries()
        self.penetrations = []
        thr = self.kind.threshold
        for idx in close:
            pair = scene.self_pairs[idx][0]
            dist, pa, pb, normal = geometry.distance(pair)
            key = self.names[idx]
            if dist < 0.0:
                self.penetrations.append((key, float(dist)))
            if dist < thr or key in s.active_keys:
                self._pairs[int(idx)] = (dist, pa, pb, normal)
                c = Candidate(key, self, int(idx), thr - dist, thr, thr)
                c.witness = (pa, pb)
                out.append(c)

    def row(self, s: Sample, c: Candidate, out: np.ndarray) -> None:
        """The normalised row with both witness points moving."""
        scene = self.scene
        assert scene is not None
        dist, pa, pb, normal = self._pairs[c.item]
        _, ia, ib = scene.self_pairs[c.item]
        Jp = point_jacobian(s.model, s.data, int(scene.link_joint[ia]), pa, self._local)
        Jp = Jp - point_jacobian(s.model, s.data, int(scene.link_joint[ib]), pb, self._local)
        c.error, c.feed = obstacle_row(
            "normalized", c.threshold, dist, pa, pb, normal, Jp, _STILL, out
        )

    def observe_limits(self, tk: float, monitor: ViolationMonitor) -> None:
        """Two links in contact."""
        for key, dist in self.penetrations:
            monitor.observe_penetration(tk, key, dist)
