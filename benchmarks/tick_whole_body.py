"""The whole-body tick lines: several tasks per tick, clik against pink and mink.

On the scenes of :mod:`benchmarks.whole_body` (``dual_arm``: Baxter; ``humanoid``: Talos
on a floating base), one Python call per 1 ms tick:

- clik: ``ctl.step({name: target}, {name: velocity})``, float64 arrays as a user's loop
  holds them (``Controller.step``'s fast path), joint-range rows;
- pink (its examples' setting): a ``FrameTask`` per pose (costs 1), a ``ComTask`` (cost
  1 on x, y), a ``PostureTask`` (cost 1e-3), ``ConfigurationLimit`` and
  ``VelocityLimit``, one ``solve_ik`` + ``integrate_inplace`` per tick, each given the
  look-ahead target ``x_d(t_k+1)``;
- mink, the same tasks on the same URDF compiled by MuJoCo (a free joint at the root of
  the humanoid; Baxter's Collada meshes, which MuJoCo does not read, left out: mink's
  tasks and limits need none), ``ConfigurationLimit``.

Every tool's joints go through the scene's own check (:meth:`WholeBody.quality`).
"""

from __future__ import annotations

import importlib.metadata
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from benchmarks.config import DT
from benchmarks.mink_backend import Mink
from benchmarks.mujoco_panda import mujoco_urdf
from benchmarks.pink_backend import PINK_DAMPING, Pink
from benchmarks.step_variant import RunOutcome
from benchmarks.tick_mink import MINK_DAMPING, MINK_POSTURE_COST
from benchmarks.tick_variant import TickVariant
from benchmarks.whole_body import WholeBody

PINK_POSTURE_COST = 1e-3
"""Cost of pink's posture task (its frame tasks' costs are 1)."""
COM_COST = (1.0, 1.0, 0.0)
"""The centre of mass's cost per axis (x, y held; z free), pink's and mink's."""


@dataclass
class PeerLoop:
    """pink's or mink's loop over a scene: targets set to ``x_d(t_k+1)``, solve, integrate.

    Attributes:
        scene: The scene.
        configuration: The tool's configuration (``update``, ``q``, ``integrate_inplace``).
        frames: Its frame tasks by task name.
        targets: Their targets at every tick (the tool's SE3 type), by task name.
        com: Its centre-of-mass task, or None.
        solve: One ``solve_ik`` on the configuration: the velocity.
        q0: The start, in the tool's joint order.
    """

    scene: WholeBody
    configuration: Any
    frames: dict[str, Any]
    targets: dict[str, list[Any]]
    com: Any
    solve: Callable[[], Any]
    q0: np.ndarray
    q_log: np.ndarray = field(init=False)
    recorded: int = field(init=False, default=0)

    def __post_init__(self) -> None:
        self.q_log = np.zeros((self.scene.ticks, len(self.q0)))

    def run(self) -> RunOutcome:
        """One whole run, each tick given ``x_d(t_k+1)``."""
        configuration, q_log, com, solve = self.configuration, self.q_log, self.com, self.solve
        configuration.update(self.q0)
        n = steps = self.scene.ticks - 1
        status = "completed"
        start = time.perf_counter()
        for k in range(n):
            q_log[k] = configuration.q
            for name, frame in self.frames.items():
                frame.set_target(self.targets[name][k + 1])
            if com is not None:
                com.set_target(self.scene.com[k + 1])  # type: ignore[index]
            try:
                velocity = solve()
            except Exception as exc:  # NoSolutionFound, NotWithinConfigurationLimits
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
        """The joints of the last run, ``q_0`` first (recorded, nq) [rad]."""
        return self.q_log[: self.recorded]


def clik_variant(scene: WholeBody) -> TickVariant:
    """Clik's line: a controller stepped with a mapping of arrays per tick."""
    ctl = scene.controller()
    joints = np.zeros((scene.ticks + 1, scene.robot.nq))
    targets, velocities, q0 = scene.targets, scene.velocities, scene.q0.copy()

    def run() -> RunOutcome:
        ctl.reset(q0)
        commanded = [q0]
        step, n, bad = ctl.step, scene.ticks, 0
        start = time.perf_counter()
        for k in range(n):
            tick = step(targets[k], velocities[k])
            commanded.append(tick.q)
            bad += tick.verdict != "ok"
        wall = time.perf_counter() - start
        joints[:] = commanded
        result = ctl.result()
        info: dict[str, Any] = {"status": result.status, "ticks_not_ok": bad,
                                "violations": len(result.violations)}  # fmt: skip
        if result.active_count is not None:
            info["active_rows_mean"] = float(np.mean(result.active_count))
        return n, wall, info

    text = f"clik.Controller, {scene.text}; each tick step({{name: array}}, {{name: velocity}})"
    return TickVariant(scene.name, text, run, lambda: joints, scene.quality)


def pink_variant(pink: Pink, scene: WholeBody) -> TickVariant:
    """Pink's line on the same model and references, given ``x_d(t_k+1)``."""
    from pink.limits import ConfigurationLimit, VelocityLimit
    from pink.tasks import ComTask, FrameTask, PostureTask

    model = scene.robot.model
    frames = {name: FrameTask(scene.frame(name), position_cost=1.0, orientation_cost=1.0)
              for name in scene.poses}  # fmt: skip
    targets = {name: [pin.SE3(p[:3, :3], p[:3, 3]) for p in poses]
               for name, poses in scene.poses.items()}  # fmt: skip
    tasks: list[Any] = list(frames.values())
    com = None
    if scene.com is not None:
        com = ComTask(cost=list(COM_COST))
        tasks.append(com)
    posture = PostureTask(cost=PINK_POSTURE_COST)
    posture.set_target(scene.q0)
    tasks.append(posture)
    limits = [ConfigurationLimit(model), VelocityLimit(model)]
    configuration = pink.module.Configuration(model, model.createData(), scene.q0)

    def solve() -> Any:
        return pink.module.solve_ik(
            configuration, tasks, DT, solver=pink.solver, damping=PINK_DAMPING, limits=limits
        )

    loop = PeerLoop(scene, configuration, frames, targets, com, solve, scene.q0)
    text = (
        f"pink {importlib.metadata.version('pin-pink')}: {len(frames)} FrameTask (costs 1)"
        f"{' + ComTask (x, y)' if com is not None else ''} + PostureTask (cost "
        f"{PINK_POSTURE_COST:g}), ConfigurationLimit + VelocityLimit, {pink.solver}, "
        "solve_ik + integrate, each tick given x_d(t_k+1)"
    )
    return TickVariant(f"pink_{scene.name}", text, loop.run, loop.joints, scene.quality)


def _mujoco_model(mj: Mink, scene: WholeBody) -> Any:
    """The scene's URDF compiled by MuJoCo (a free joint on a floating base)."""
    spec = mj.mujoco.MjSpec.from_string(mujoco_urdf(scene.robot))
    if scene.robot.base == "floating":
        spec.worldbody.first_body().add_freejoint()
    return spec.compile()


def _to_mujoco(mj: Mink, model: Any, scene: WholeBody) -> tuple[np.ndarray, np.ndarray]:
    """Index maps: MuJoCo's qpos from Pinocchio's q, and back (by joint name)."""
    pmodel = scene.robot.model
    to_mj = np.zeros(model.nq, dtype=int)
    for j in range(1, pmodel.njoints):
        name, joint = pmodel.names[j], pmodel.joints[j]
        if joint.nq == 7:  # the free-flyer: x y z qx qy qz qw -> x y z qw qx qy qz
            adr = model.jnt_qposadr[0]
            to_mj[adr : adr + 7] = joint.idx_q + np.array([0, 1, 2, 6, 3, 4, 5])
            continue
        jid = mj.mujoco.mj_name2id(model, mj.mujoco.mjtObj.mjOBJ_JOINT, name)
        if jid < 0 or joint.nq != 1:
            raise RuntimeError(f"MuJoCo's model lacks joint {name} of clik's {scene.robot.name}")
        to_mj[model.jnt_qposadr[jid]] = joint.idx_q
    back = np.zeros_like(to_mj)
    back[to_mj] = np.arange(model.nq)
    return to_mj, back


def mink_variant(mj: Mink, scene: WholeBody) -> TickVariant:
    """Mink's line on MuJoCo's compilation of the same URDF, given ``x_d(t_k+1)``."""
    mink = mj.module
    model = _mujoco_model(mj, scene)
    if model.nq != scene.robot.nq:
        raise RuntimeError(
            f"MuJoCo's {scene.robot.name} has {model.nq} joints, clik's {scene.robot.nq}"
        )
    to_mj, back = _to_mujoco(mj, model, scene)
    q0 = scene.q0[to_mj]
    frames = {name: mink.FrameTask(frame_name=scene.frame(name), frame_type="body",
                                   position_cost=1.0, orientation_cost=1.0, lm_damping=1.0)
              for name in scene.poses}  # fmt: skip
    targets = {name: [mink.SE3.from_matrix(p) for p in poses]
               for name, poses in scene.poses.items()}  # fmt: skip
    tasks: list[Any] = list(frames.values())
    com = None
    if scene.com is not None:
        com = mink.ComTask(cost=np.array(COM_COST))
        tasks.append(com)
    posture = mink.PostureTask(model=model, cost=MINK_POSTURE_COST)
    posture.set_target(q0)
    tasks.append(posture)
    limits = [mink.ConfigurationLimit(model=model)]
    configuration = mink.Configuration(model)

    def solve() -> Any:
        return mink.solve_ik(configuration, tasks, DT, mj.solver, MINK_DAMPING, limits=limits)

    loop = PeerLoop(scene, configuration, frames, targets, com, solve, q0)
    text = (
        f"mink {importlib.metadata.version('mink')} on MuJoCo "
        f"{importlib.metadata.version('mujoco')}, the same URDF: {len(frames)} FrameTask "
        f"(lm_damping 1){' + ComTask (x, y)' if com is not None else ''} + PostureTask (cost "
        f"{MINK_POSTURE_COST:g}), ConfigurationLimit, {mj.solver} (damping {MINK_DAMPING:g}), "
        "solve_ik + integrate, each tick given x_d(t_k+1)"
    )
    return TickVariant(
        f"mink_{scene.name}", text, loop.run, lambda: loop.joints()[:, back], scene.quality
    )


def whole_body_variants(pink: Pink | None, mink: Mink | None) -> list[TickVariant]:
    """Every whole-body tick line: clik's, then pink's and mink's where installed."""
    from benchmarks.whole_body import dual_arm_scene, humanoid_scene

    variants: list[TickVariant] = []
    for scene in (dual_arm_scene(), humanoid_scene()):
        variants.append(clik_variant(scene))
        if pink is not None:
            variants.append(pink_variant(pink, scene))
        if mink is not None:
            variants.append(mink_variant(mink, scene))
    return variants
