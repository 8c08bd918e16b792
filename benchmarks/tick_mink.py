"""mink's per-tick lines: one ``solve_ik`` + ``integrate_inplace`` per tick through MuJoCo.

mink's ``examples/franka_emika_panda.py`` setting (``FrameTask`` of costs 1 with
``lm_damping`` 1, ``PostureTask`` of cost 1e-2, ``solve_ik`` damping 1e-3), with
``ConfigurationLimit`` and daqp, on the Panda clik loads
(:mod:`benchmarks.mujoco_panda`): one QP per tick, given the look-ahead target
``x_d(t_k+1)`` as its examples set the target then solve. With the spheres, mink's
``CollisionAvoidanceLimit`` between the arm's geoms and the three sphere geoms.
"""

from __future__ import annotations

import importlib.metadata
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from benchmarks.config import DT
from benchmarks.mink_backend import Mink
from benchmarks.mujoco_panda import SPHERE_PREFIX, panda_with_spheres
from benchmarks.pink_barrier import OBSTACLE_THRESHOLD
from benchmarks.step_lines import OBSTACLE_RADIUS, OBSTACLES_ONE_ACTIVE, PandaSetup
from benchmarks.step_variant import RunOutcome
from benchmarks.tick_variant import TickReference, TickVariant

MINK_POSTURE_COST = 1e-2
"""Cost of mink's posture task (its example's)."""
MINK_DAMPING = 1e-3
"""Damping mink's Panda example gives ``solve_ik``."""
MINK_DETECTION_DISTANCE = OBSTACLE_THRESHOLD + 0.1
"""``collision_detection_distance`` [m]: a pair gets a row within 0.1 m of the kept
distance, the band in which clik asks coal for an obstacle's nearest distance every
tick (its ``monitor_margin``)."""
FK_AGREEMENT = 1e-9
"""Largest difference [m] between MuJoCo's and Pinocchio's hand position at ``q0``."""


@dataclass
class MinkTracking:
    """mink's loop over the reference, its tasks, limits and configuration built once."""

    mink: Mink
    targets: list[Any]
    q0: np.ndarray
    frame_task: Any
    tasks: list[Any]
    limits: list[Any]
    configuration: Any
    q_log: np.ndarray = field(init=False)
    recorded: int = field(init=False, default=0)

    def __post_init__(self) -> None:
        self.q_log = np.zeros((len(self.targets), len(self.q0)))

    def run(self) -> RunOutcome:
        """One whole run, each tick given ``x_d(t_k+1)``."""
        solve_ik, solver = self.mink.module.solve_ik, self.mink.solver
        configuration, frame_task, targets, q_log = (
            self.configuration, self.frame_task, self.targets, self.q_log,
        )  # fmt: skip
        tasks, limits = self.tasks, self.limits
        configuration.update(self.q0)
        status = "completed"
        n = steps = len(targets) - 1
        start = time.perf_counter()
        for k in range(n):
            q_log[k] = configuration.q
            frame_task.set_target(targets[k + 1])
            try:
                velocity = solve_ik(configuration, tasks, DT, solver, MINK_DAMPING, limits=limits)
            except Exception as exc:  # NoSolutionFound and the like
                status, steps = f"failed: {type(exc).__name__}", k + 1
                break
            configuration.integrate_inplace(velocity, DT)
        wall = time.perf_counter() - start
        self.recorded = steps
        if status == "completed":
            q_log[n] = configuration.q
            self.recorded = n + 1
        return steps, wall, {"status": status}

    def joints(self) -> np.ndarray:
        """The joints of the last run, ``q_0`` to the final one (recorded, nq) [rad]."""
        return self.q_log[: self.recorded]


def _check_same_robot(mj: Mink, model: Any, panda: PandaSetup) -> None:
    """MuJoCo's hand and Pinocchio's agree at ``q0`` (same joints, same order)."""
    data = mj.mujoco.MjData(model)
    data.qpos[:] = panda.q0
    mj.mujoco.mj_kinematics(model, data)
    pdata = panda.robot.model.createData()
    pin.framesForwardKinematics(panda.robot.model, pdata, panda.q0)
    gap = np.abs(data.body(panda.task.frame).xpos - pdata.oMf[panda.task.frame_id].translation)
    if model.nq != panda.robot.nq or gap.max() > FK_AGREEMENT:
        raise RuntimeError(f"MuJoCo's Panda differs from clik's ({model.nq} joints, {gap.max()} m)")


def _collision_limit(mj: Mink, model: Any, centres: int) -> tuple[Any, str]:
    """``CollisionAvoidanceLimit`` between the arm's geoms and the spheres, and its text."""
    spheres = [f"{SPHERE_PREFIX}{i}" for i in range(centres)]
    arm = [g for g in range(model.ngeom) if model.geom_bodyid[g] != 0]
    limit = mj.module.CollisionAvoidanceLimit(
        model=model,
        geom_pairs=[(arm, spheres)],
        minimum_distance_from_collisions=OBSTACLE_THRESHOLD,
        collision_detection_distance=MINK_DETECTION_DISTANCE,
    )
    paired = {g for pair in limit.geom_id_pairs for g in pair}
    left_out = sorted({model.body(model.geom_bodyid[g]).name for g in arm if g not in paired})
    text = (
        f"CollisionAvoidanceLimit between the {len(arm)} arm geoms (meshes as their convex "
        f"hulls, finger boxes) and {centres} sphere geoms of radius {OBSTACLE_RADIUS:g} m: "
        f"{len(limit.geom_id_pairs)} pairs (mink leaves out the bodies welded to, or "
        f"children of, the world body the spheres are on: {', '.join(left_out) or 'none'}), "
        f"minimum distance "
        f"{OBSTACLE_THRESHOLD:g} m, detection distance {MINK_DETECTION_DISTANCE:g} m, "
        f"gain {limit.gain:g} (its default)"
    )
    return limit, text


def mink_tick_variant(
    mj: Mink, panda: PandaSetup, reference: TickReference, obstacles: bool
) -> TickVariant:
    """The tick line of mink on the Panda's circle, with or without the spheres.

    Args:
        mj: The installed mink, MuJoCo and QP solver.
        panda: The Panda setup.
        reference: The reference at every tick.
        obstacles: Whether to add the spheres of
            :data:`~benchmarks.step_lines.OBSTACLES_ONE_ACTIVE` and mink's collision limit.
    """
    mink = mj.module
    centres = OBSTACLES_ONE_ACTIVE if obstacles else ()
    model = panda_with_spheres(mj.mujoco, panda.robot, centres, OBSTACLE_RADIUS)
    _check_same_robot(mj, model, panda)
    frame_task = mink.FrameTask(
        frame_name=panda.task.frame, frame_type="body", position_cost=1.0,
        orientation_cost=1.0, lm_damping=1.0,
    )  # fmt: skip
    posture_task = mink.PostureTask(model=model, cost=MINK_POSTURE_COST)
    posture_task.set_target(panda.q0)
    limits = [mink.ConfigurationLimit(model=model)]
    text = (
        f"mink {importlib.metadata.version('mink')} on MuJoCo "
        f"{importlib.metadata.version('mujoco')}, the same panda.urdf: FrameTask "
        f"(lm_damping 1) + PostureTask (cost {MINK_POSTURE_COST:g}), ConfigurationLimit, "
        f"{mj.solver} (damping {MINK_DAMPING:g}), solve_ik + integrate, each tick given "
        "x_d(t_k+1)"
    )
    if obstacles:
        limit, limit_text = _collision_limit(mj, model, len(centres))
        limits.append(limit)
        text = f"{text}; {limit_text}"
    targets = [mink.SE3.from_matrix(pose.homogeneous) for pose in reference.poses]
    tracking = MinkTracking(
        mj, targets, panda.q0.copy(), frame_task, [frame_task, posture_task], limits,
        mink.Configuration(model),
    )  # fmt: skip
    name = "mink_panda_pose" + ("_obstacles" if obstacles else "")
    return TickVariant(name, text, tracking.run, tracking.joints)


def mink_tick_variants(mj: Mink, panda: PandaSetup, reference: TickReference) -> list[TickVariant]:
    """The two tick lines of mink: the pose task alone, and with the spheres.

    Args:
        mj: The installed mink, MuJoCo and QP solver.
        panda: The Panda setup.
        reference: The reference at every tick.
    """
    return [
        mink_tick_variant(mj, panda, reference, False),
        mink_tick_variant(mj, panda, reference, True),
    ]
