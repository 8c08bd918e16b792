r"""Is a configuration clear of its constraints? Checked directly, with coal and the joint values.

A configuration ``q`` *satisfies* a :class:`~clik.constraints.ConstraintSet` when

- every monitored link is at a distance ``d >= d_o`` from every obstacle, ``d_o`` that
  obstacle's threshold: the error (13) (normalised form ``e_o = d_o - d``) is not positive;
- with self-collision rows, every checked link pair is at least its threshold apart;
- every joint is inside the robot's limits and, with joint-range rows (16)-(19), at
  least ``d_q`` from each limit of the constraint (the tighter of the robot's and the
  override): the error (17) ``e_q = d_q - d`` is not positive.

Distances are computed by coal (``pinocchio.computeDistances``) on the constraint set's
own link geometry, the convex hulls of the links' collision meshes: a hull contains its
mesh, so a hull at ``d >= d_o`` puts the mesh at least as far. Nothing here trusts a
run's status or its recorded distances: :func:`clik.solve` calls :meth:`PoseCheck.violations`
on the pose it returns.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from clik.constraints.collision_scene import GJK_TOLERANCE
from clik.robot import PRISMATIC, REVOLUTE, joint_kind

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet

CHECK_TOLERANCE = 1e-12
"""Accepted shortfall of a distance below its threshold [m or rad] (rounding only)."""


@dataclass(frozen=True)
class Violation:
    """One constraint that ``q`` does not satisfy.

    Attributes:
        constraint: The constraint in words: ``"obstacle 'table'"``,
            ``"joint range of panda_joint4"`` or ``"link pair panda_link2-panda_link6"``.
        detail: Where and by how much, with units.
        shortfall: How far inside the threshold [m or rad], > 0.
    """

    constraint: str
    detail: str
    shortfall: float

    def describe(self) -> str:
        """``"obstacle 'table' blocks: link panda_link7 at 0.012 m < threshold 0.05 m"``."""
        return f"{self.constraint} blocks: {self.detail}"


def constraint_label(key: str) -> str:
    """A constraint row's key (``obstacle:table:panda_link7``, ``joint:j4:lower``) in words."""
    kind, _, rest = key.partition(":")
    name, _, part = rest.rpartition(":")
    if kind == "obstacle" and name:
        return f"obstacle {name!r} (link {part})"
    if kind == "joint" and name:
        return f"joint range of {name} ({part} limit)"
    return key


class PoseCheck:
    """Checks configurations against one constraint set (its own Pinocchio and coal data).

    Args:
        cset: The constraints. Its obstacles must be at rest (solve mode has no time).
    """

    def __init__(self, cset: ConstraintSet) -> None:
        self.cset = cset
        robot = cset.robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.scene = cset.scene
        self.gdata = None if self.scene is None else pin.GeometryData(self.scene.gmodel)
        if self.gdata is not None:
            for request in self.gdata.distanceRequests:
                request.gjk_tolerance = GJK_TOLERANCE
                request.epa_tolerance = GJK_TOLERANCE
        self.limited = [
            (name, joint.idx_q)
            for name, joint in zip(robot.joint_names, robot.model.joints[1:], strict=True)
            if joint_kind(joint) in (REVOLUTE, PRISMATIC)
            and math.isfinite(robot.lower[joint.idx_q])
            and math.isfinite(robot.upper[joint.idx_q])
        ]
        self.lower, self.upper = robot.lower, robot.upper

    def violations(self, q: np.ndarray) -> list[Violation]:
        """Every constraint ``q`` does not satisfy, the largest shortfall first."""
        found = self._joints(q)
        if self.gdata is not None:
            found += self._distances(q)
        return sorted(found, key=lambda v: -v.shortfall)

    def worst(self, q: np.ndarray) -> Violation | None:
        """The constraint ``q`` misses by most, or None when ``q`` satisfies them all."""
        found = self.violations(q)
        return found[0] if found else None

    def _joints(self, q: np.ndarray) -> list[Violation]:
        """Joints outside the robot's limits, or inside a joint-range row's band (17)."""
        out: list[Violation] = []
        for name, i in self.limited:
            below, above = self.lower[i] - q[i], q[i] - self.upper[i]
            if max(below, above) > CHECK_TOLERANCE:
                side, limit = ("lower", self.lower[i]) if below > 0 else ("upper", self.upper[i])
                detail = f"{name} = {q[i]:.6g} beyond its {side} limit {limit:.6g}"
                out.append(Violation(f"joint range of {name}", detail, float(max(below, above))))
        jl = self.cset.joint_limits
        if jl is None:
            return out
        qi = q[jl.q_index]
        for k, name in enumerate(jl.joint_names):
            unit, thr = jl.units[k], float(jl.threshold[k])
            for side, d in (("lower", qi[k] - jl.lower[k]), ("upper", jl.upper[k] - qi[k])):
                if thr - d <= CHECK_TOLERANCE:
                    continue
                limit = jl.lower[k] if side == "lower" else jl.upper[k]
                where = f"{-d:.4g} {unit} beyond" if d < 0 else f"{d:.4g} {unit} from"
                detail = (
                    f"{name} = {qi[k]:.6g} {unit}, {where} its {side} limit {limit:.6g} {unit} "
                    f"(threshold {thr:.4g} {unit})"
                )
                out.append(Violation(f"joint range of {name}", detail, float(thr - d)))
        return out

    def _distances(self, q: np.ndarray) -> list[Violation]:
        """Link-obstacle pairs nearer than the obstacle's ``d_o`` (13), link pairs too near."""
        scene, cset, gdata = self.scene, self.cset, self.gdata
        assert scene is not None and gdata is not None
        pin.computeDistances(self.model, self.data, scene.gmodel, gdata, q)
        results = gdata.distanceResults
        out: list[Violation] = []
        for o, obstacle in enumerate(cset.obstacles):
            thr = float(cset.obs_threshold[o])
            column = [results[int(p)].min_distance for p in scene.obstacle_pairs[:, o]]
            if not column:
                continue
            i = int(np.argmin(column))
            d = float(column[i])
            if thr - d > CHECK_TOLERANCE or not math.isfinite(d):
                detail = f"link {cset.link_labels[i]} at {d:.4g} m < threshold {thr:.4g} m"
                out.append(Violation(f"obstacle {obstacle.name!r}", detail, thr - d))
        for pair, a, b in scene.self_pairs:
            d = float(results[pair].min_distance)
            if cset.self_threshold - d > CHECK_TOLERANCE:
                label = f"{cset.link_labels[a]}-{cset.link_labels[b]}"
                detail = f"{d:.4g} m apart < threshold {cset.self_threshold:.4g} m"
                out.append(Violation(f"link pair {label}", detail, cset.self_threshold - d))
        return out
